"""Impact laws of a rocking wall as interchangeable objects.

An impact law returns the *signed* coefficient of restitution
``e = thetadot^+ / thetadot^-`` of one impact.  A positive ``e`` (two-sided
rocking, Eqs. 1-2) keeps the sign of the angular velocity, so the wall passes
to the other hinge; a negative ``e`` (one-sided rocking, Eq. 14, or the
transverse-wall impact of Eqs. 12-13) is a rebound on the same hinge.

Arguments of :meth:`ImpactLaw.coefficient`:

``thetadot_before``
    angular velocity just before the impact [rad/s];
``side``
    +1 or -1, the sign of the rotation before the impact, i.e. the hinge the
    wall is *leaving* (+1: it was rocking with theta > 0);
``alpha``
    nominal slenderness angle [rad] used by the analytic coefficients
    (the paper computes e_an with the nominal alpha, Sect. 3);
``p``
    frequency parameter [rad/s], needed by the amplitude law (Eq. 16).

Laws that the numba engines can evaluate expose :meth:`ImpactLaw.flat`: for
each side a triple ``(e0, a, b)`` meaning
``e = e0 * clip(a - b (|thetadot^-| / thetadot_r)^2, 0, 1/|e0|)``, with
``thetadot_r`` of Eq. 16.  Constant laws have ``a = 1, b = 0``.

Physical bounds, one convention for every law (:func:`bounded_factor`): a
law that multiplies a base e by a factor (a scale, Eq. 17's bracket, a law
of the impact speed, :mod:`rocklab.physics.law`) is its own closed form at
every speed, those past the speeds it was fitted on included (it is not
held at the value of the fastest impact fitted), with the factor clipped to
[0, 1/|e_base|]: e keeps the sign of the base law (a fitted law extrapolated
to fast impacts never turns a rebound into a pass-through, it stops the
wall: Eq. 17 of the one-sided walls reaches e = 0 past 1.5 thetadot_r) and
|e| <= 1 (an impact never creates energy).  The diagnosis' one-step model
(:func:`rocklab.diagnosis.wall_model.impact_speeds`), the limestone blocks, the
exact simulators and the calibrated maps read their laws through it.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from rocklab.physics import restitution
from rocklab.physics.boundary import Boundary
from rocklab.physics.flight import FloatArray, Floats
from rocklab.physics.law import speed_factor
from rocklab.physics.wall import overturning_velocity


def bounded_factor(e0: Floats, factor: Floats) -> Floats:
    """A law's factor on the base e ``e0`` (signed) within the physical bounds: clipped to [0, 1/|e0|] [-].

    The one convention of every impact law, at any speed (module
    docstring): the lower clip keeps the sign of e (a fitted law
    extrapolated to large velocities must not turn a rebound into a
    pass-through); the upper clip keeps |e0 factor| <= 1, so an impact never
    creates energy.
    """
    size = np.abs(e0)
    hi = np.where(size > 0, 1.0 / np.maximum(size, 1e-300), np.inf)
    return np.clip(factor, 0.0, hi)


def amplitude_factor(e0: Floats, a: Floats, b: Floats, thetadot_before: Floats, alpha: Floats, p: Floats) -> Floats:
    """a - b (thetadot^-/thetadot_r)^2 within the bounds of :func:`bounded_factor` (the bracket of Eq. 17)."""
    return amplitude_factor_at(e0, a, b, np.abs(thetadot_before) / overturning_velocity(alpha, p))


def amplitude_factor_at(e0: Floats, a: Floats, b: Floats, ratio: Floats) -> Floats:
    """:func:`amplitude_factor` at the speed ratio |thetadot^-| / thetadot_r [-] (Eq. 16), for a
    caller that holds thetadot_r: a - b ratio^2 within the bounds of :func:`bounded_factor`."""
    return bounded_factor(e0, a - b * ratio**2)


class ImpactLaw:
    """Base class: signed coefficient of restitution of one impact."""

    def coefficient(self, thetadot_before: Floats, side: float, alpha: Floats, p: Floats) -> Floats:
        """Signed e = thetadot^+ / thetadot^- [-] (see module docstring)."""
        e0, a, b = self._triple(side, alpha)
        if a == 1.0 and b == 0.0:
            return e0 * bounded_factor(e0, np.ones_like(np.asarray(thetadot_before, float)))
        return e0 * amplitude_factor(e0, a, b, thetadot_before, alpha, p)

    def flat(self, alpha: float) -> FloatArray:
        """Parameters for the numba engines: array (2, 3), rows side +1, -1.

        Raises
        ------
        NotImplementedError
            For laws that are not of the form e0 * (a - b (v/v_r)^2).
        """
        return np.array([self._triple(+1, alpha), self._triple(-1, alpha)], float)

    def _triple(self, side: float, alpha: float) -> tuple[float, float, float]:
        raise NotImplementedError(f"{type(self).__name__} has no flat form")


class HousnerTwoSided(ImpactLaw):
    """Housner's analytic e_an,2s, Eqs. 1-2 (homogeneous wall by default)."""

    def __init__(self, mR2_over_Io: float | None = None) -> None:
        self.mR2_over_Io = mR2_over_Io

    def _triple(self, side: float, alpha: float) -> tuple[float, float, float]:
        return (float(restitution.two_sided(alpha, self.mR2_over_Io)), 1.0, 0.0)


class AsymmetricBody(ImpactLaw):
    """The rigid impact of a planar body whose edges are not symmetric about its centre of mass.

    e of leaving edge +1 (theta > 0) for edge -1, and the reverse, from
    angular momentum about the edge landed on
    (:func:`rocklab.physics.restitution.two_sided_asymmetric`); Eq. 1 of
    :class:`HousnerTwoSided` when ``b_plus == b_minus``.

    Parameters
    ----------
    b_plus, b_minus : float
        Horizontal distances [m] from the centre of mass to edges +1 and -1.
    height : float
        Height [m] of the centre of mass above the base.
    gyration_radius : float
        Radius of gyration [m] about the centre of mass in the rocking plane.
    """

    def __init__(self, b_plus: float, b_minus: float, height: float, gyration_radius: float) -> None:
        self.b_plus, self.b_minus = float(b_plus), float(b_minus)
        self.height, self.gyration_radius = float(height), float(gyration_radius)

    def _triple(self, side: float, alpha: float) -> tuple[float, float, float]:
        leave, land = (self.b_plus, self.b_minus) if side > 0 else (self.b_minus, self.b_plus)
        return (restitution.two_sided_asymmetric(leave, land, self.height, self.gyration_radius), 1.0, 0.0)


class OneSided(ImpactLaw):
    """Analytic e_an,1s of one-sided rocking, Eq. 14 (negative: a rebound)."""

    def __init__(self, mR2_over_Io: float | None = None) -> None:
        self.mR2_over_Io = mR2_over_Io

    def _triple(self, side: float, alpha: float) -> tuple[float, float, float]:
        return (float(restitution.one_sided(alpha, self.mR2_over_Io)), 1.0, 0.0)


class Transverse(ImpactLaw):
    """Impact on the transverse walls, e_an,tr of Eqs. 12-13 (a rebound).

    Used by the gap model of one-sided rocking (see :mod:`rocklab.simulation.rocking_model`).
    """

    def __init__(self, mR2_over_Io: float | None = None) -> None:
        self.mR2_over_Io = mR2_over_Io

    def _triple(self, side: float, alpha: float) -> tuple[float, float, float]:
        return (float(restitution.transverse(alpha, self.mR2_over_Io)), 1.0, 0.0)


class Constant(ImpactLaw):
    """A given signed coefficient, the same on both sides."""

    def __init__(self, e: float) -> None:
        self.e = float(e)

    def _triple(self, side: float, alpha: float) -> tuple[float, float, float]:
        return (self.e, 1.0, 0.0)


class Zero(Constant):
    """e = 0: the wall stops at the first impact (Liberatore & Spera 2003)."""

    def __init__(self) -> None:
        super().__init__(0.0)


class Scaled(ImpactLaw):
    """c times another law, e.g. 0.95 e_an,2s or 1.05 e_an,1s (Sect. 5)."""

    def __init__(self, law: ImpactLaw, c: float) -> None:
        self.law, self.c = law, float(c)

    def coefficient(self, thetadot_before: Floats, side: float, alpha: Floats, p: Floats) -> Floats:
        e = self.law.coefficient(thetadot_before, side, alpha, p)
        return e * bounded_factor(e, self.c)

    def _triple(self, side: float, alpha: float) -> tuple[float, float, float]:
        # the flat form carries the bounded constant, so that Eq. 17's bracket
        # on top clips against the e the impact really has
        e0, a, b = self.law._triple(side, alpha)
        return (e0 * float(bounded_factor(e0, self.c)), a, b)


class AmplitudeLaw(ImpactLaw):
    """Amplitude-dependent law, Eq. 17 with any coefficients.

    e = e_law * (a - b (|thetadot^-| / thetadot_r)^2), thetadot_r of Eq. 16
    (nominal alpha and p).  The bracket is clipped to [0, 1/|e_law|]: e keeps
    the sign of the underlying law and |e| <= 1.  The paper's fit for
    one-sided rocking is ``AmplitudeLaw(OneSided())``, a and b of
    :data:`rocklab.physics.restitution.AMPLITUDE_LAW_ONE_SIDED`.
    """

    def __init__(
        self,
        law: ImpactLaw,
        a: float = restitution.AMPLITUDE_LAW_ONE_SIDED[0],
        b: float = restitution.AMPLITUDE_LAW_ONE_SIDED[1],
    ) -> None:
        self.law, self.a, self.b = law, float(a), float(b)

    def coefficient(self, thetadot_before: Floats, side: float, alpha: Floats, p: Floats) -> Floats:
        e = self.law.coefficient(thetadot_before, side, alpha, p)
        return e * amplitude_factor(e, self.a, self.b, thetadot_before, alpha, p)

    def _triple(self, side: float, alpha: float) -> tuple[float, float, float]:
        e0, a, b = self.law._triple(side, alpha)
        if (a, b) != (1.0, 0.0):
            raise NotImplementedError("nested amplitude laws have no flat form")
        return (e0, self.a, self.b)


class Sided(ImpactLaw):
    """A different law for each hinge being left (hinge asymmetry)."""

    def __init__(self, law_pos: ImpactLaw, law_neg: ImpactLaw) -> None:
        self.law_pos, self.law_neg = law_pos, law_neg

    def coefficient(self, thetadot_before: Floats, side: float, alpha: Floats, p: Floats) -> Floats:
        law = self.law_pos if side > 0 else self.law_neg
        return law.coefficient(thetadot_before, side, alpha, p)

    def _triple(self, side: float, alpha: float) -> tuple[float, float, float]:
        return (self.law_pos if side > 0 else self.law_neg)._triple(side, alpha)


class Sticking(ImpactLaw):
    """Another law, but a landing slower than ``v_stick`` thetadot_r (Eq. 16)
    stops the wall dead (e = 0).

    A hinge that is not a sharp edge (mortar, chipped corners: the
    "imperfection of the rocking hinge" of Sect. 4) absorbs the last, small
    landings whole, so the walls stop after fewer impacts than any
    coefficient of restitution predicts, a number that scatters from test to
    test (Fig. 18).  The numba engine reads the threshold from the fourth
    column of :meth:`rocklab.simulation.rocking_model.RockingModel.numba_law`.
    """

    def __init__(self, law: ImpactLaw, v_stick: float) -> None:
        self.law, self.v_stick = law, float(v_stick)

    def coefficient(self, thetadot_before: Floats, side: float, alpha: Floats, p: Floats) -> Floats:
        e = self.law.coefficient(thetadot_before, side, alpha, p)
        slow = np.abs(thetadot_before) < self.v_stick * overturning_velocity(alpha, p)
        return np.where(slow, 0.0, e)


class SpeedLaw(ImpactLaw):
    """Another law times g(|thetadot^-| / thetadot_r), g piecewise linear between its values ``knots``
    at :data:`rocklab.physics.law.KNOTS` (:class:`rocklab.physics.law.SpeedFactor`, its last segment
    continued past them), within the bounds of :func:`bounded_factor`.

    ``excursion``: the law of a one-sided wall swinging through a gap (Fig. 12), where the factor acts
    on the sequence base impact, flight in the gap, transverse impact, flight back, base impact as a
    whole, as the diagnosis' closed form reads it
    (:func:`rocklab.diagnosis.wall_model.impact_speeds`): no factor on a single impact
    (:meth:`coefficient` is the other law's), g of the landing speed v that started the excursion on
    the speed the wall leaves the base with at its return, v_out -> v_out bounded_factor(v_out / v,
    g(v / thetadot_r)) (:meth:`factor`, read by the simulators at the return).

    The numba engine reads it from the columns past the fourth of
    :meth:`rocklab.simulation.rocking_model.RockingModel.numba_law`.
    """

    def __init__(self, law: ImpactLaw, knots: npt.ArrayLike, excursion: bool = False) -> None:
        self.law, self.knots, self.excursion = law, np.asarray(knots, float), bool(excursion)

    def factor(self, e: Floats, thetadot_before: Floats, alpha: Floats, p: Floats) -> Floats:
        """g(|thetadot^-| / thetadot_r) within the bounds of :func:`bounded_factor` on the signed e ``e``
        of the impact (or of the excursion as a whole: v_out / v) [-]."""
        return bounded_factor(e, speed_factor(np.abs(thetadot_before) / overturning_velocity(alpha, p), self.knots))

    def coefficient(self, thetadot_before: Floats, side: float, alpha: Floats, p: Floats) -> Floats:
        e = self.law.coefficient(thetadot_before, side, alpha, p)
        return e if self.excursion else e * self.factor(e, thetadot_before, alpha, p)


def speed_law(law: ImpactLaw, side: float) -> SpeedLaw | None:
    """The law of the impact speed that ``law`` applies on leaving hinge ``side`` (through a
    :class:`Sided` or :class:`Sticking`), or None."""
    if isinstance(law, Sided):
        return speed_law(law.law_pos if side > 0 else law.law_neg, side)
    if isinstance(law, Sticking):
        return speed_law(law.law, side)
    return law if isinstance(law, SpeedLaw) else None


class Custom(ImpactLaw):
    """User-defined ``func(thetadot_before, side, alpha, p) -> e``.

    Only the event-driven reference integrator accepts it.
    """

    def __init__(self, func: Callable[..., Floats]) -> None:
        self.func = func

    def coefficient(self, thetadot_before: Floats, side: float, alpha: Floats, p: Floats) -> Floats:
        return self.func(thetadot_before, side, alpha, p)


def analytic(boundary: str, gap: bool = False) -> ImpactLaw:
    """The analytic law of the base impacts of a wall: Eq. 14 for a one-sided wall without a gap
    (a rebound), Eq. 2 otherwise (two-sided, or a one-sided wall swinging through a gap, Fig. 12)."""
    return OneSided() if boundary == Boundary.ONE_SIDED and not gap else HousnerTwoSided()


def calibrated(law: ImpactLaw, c_pos: Floats = 1.0, c_neg: Floats = 1.0, a: Floats = 1.0, b: Floats = 0.0) -> ImpactLaw:
    """``law`` times c_pos on leaving hinge +1, c_neg on leaving hinge -1, and Eq. 17's bracket
    a - b (thetadot^-/thetadot_r)^2: the one composition of a calibrated impact law.

    Only what departs from the null values is wrapped, so a law at its null
    is ``law`` itself: ``Scaled`` where both hinges share the factor,
    ``Sided`` where they differ, then ``AmplitudeLaw``.
    """
    if c_pos != c_neg:
        law = Sided(Scaled(law, float(c_pos)), Scaled(law, float(c_neg)))
    elif c_pos != 1.0:
        law = Scaled(law, float(c_pos))
    if b != 0.0 or a != 1.0:
        law = AmplitudeLaw(law, float(a), float(b))
    return law
