"""What a cause does to a rocking wall, as composable laws.

A cause of the diagnosis (:mod:`rocklab.diagnosis.causes`) declares its
physics once, as a tuple of these laws (``Cause.laws(values)``); every
consumer reads the laws rather than the cause's name:

- the diagnosis' per-test wall model: each law says what it does to the
  model's arrays (:meth:`Law.act_on`, which
  :meth:`rocklab.diagnosis.wall_model.ModelParams.under` calls), from which
  the exact simulator's :class:`rocklab.simulation.rocking_model.RockingModel`
  is derived (:func:`rocklab.diagnosis.wall_model.simulator`) and with it the
  calibrated walls of the maps (:mod:`rocklab.seismic.calibrated`);
- the shake-table block (:func:`rocklab.shake_table.block.block_model`: its extra loss, ``restitution_scale``);
- the limestone block tables (:meth:`rocklab.diagnosis.block_tests.BlockProblem.model_e`).

A law holds the change, not the wall: a factor on what the base model has
(the rocking angle, e), a term it adds (a loss in flight), or a rule
(a gap, a stop).  Its values are floats, or per-test arrays where a cause
takes one value per test (a stop threshold left out test by test).  The
laws of several causes compose by acting in turn, in the catalogue's order
(:data:`rocklab.diagnosis.catalogue.CAUSES`): factors multiply, a term or a
rule is that of the last law to set it.  Null values leave the base model
as it is.

A law that acts in flight declares its term of the equation of motion
once, as a :class:`FlightTerm`: its deceleration, which the reference
simulator and the numba engine integrate, and its work over a half flight,
which the closed forms of a flight (:mod:`rocklab.physics.flight`) take.
A new mechanism is then one module: its law (a :class:`Law` whose
:meth:`~Law.act_on` sets its term on the model,
:meth:`rocklab.diagnosis.wall_model.ModelParams.with_term`) and its cause;
no consumer names it (tests/test_mechanism.py).

Beyond the speeds it was fitted on, every law is its own closed form
(Eq. 17's parabola, the last segment of :class:`SpeedFactor` continued),
never held flat, and every law of e is within the physical bounds of
:func:`rocklab.physics.impact.bounded_factor`: e keeps the sign of the base
law and |e| <= 1.  A loss in flight only takes energy (its parameters are
not negative, :class:`FlightLoss`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any, ClassVar

import numpy as np
import numpy.typing as npt

from rocklab.physics import restitution
from rocklab.physics.flight import FloatArray, Floats


class Law:
    """A law of this module: what it does to the wall model, declared by the law itself."""

    def act_on(self, mp: Any) -> Any:
        """The model ``mp`` (:class:`rocklab.diagnosis.wall_model.ModelParams`, per-test arrays) as
        this law changes it: a new model, ``mp`` left as it is."""
        raise NotImplementedError


@dataclass(frozen=True)
class FlightTerm:
    """A term of the equation of motion between impacts, declared once for every simulator and closed form.

    In flight the wall decelerates by ``deceleration(theta, thetadot, p, q, i)``
    [rad/s^2] beside the restoring moment: theta [rad], thetadot [rad/s],
    p [rad/s], its parameters ``q[i], q[i + 1], ...`` (one per name of
    ``params``, in that order).  A function of floats that numba compiles:
    the reference simulator (:mod:`rocklab.simulation.reference`) calls it
    as it is, the numba engine (:mod:`rocklab.simulation.engine`) compiles
    it into its exact form.  Every parameter 0: no deceleration (the base
    model).

    Attributes
    ----------
    name : str
    params : tuple of str
        Its parameters, by name, and their order in ``q``.
    deceleration : callable
        As above.
    smooth : bool
        Whether the deceleration is continuous along a flight: one that
        jumps where thetadot changes sign (dry friction, a moment on the
        rise only) makes the engine start a new step at each turn, where a
        step over it would lose RK4's order.
    work : callable, optional
        ``work(A, a, p, rise, *values)``: the energy per unit I_O it takes
        [rad^2/s^2] over the rise from theta = 0 to the apex A [rad] on a
        hinge of angle a [rad] (``rise`` True) or over the fall from A back
        to 0, array_like, broadcast; its share of the closed forms of a
        flight (:func:`rocklab.physics.flight.landing_speed`,
        :func:`~rocklab.physics.flight.apex_after`,
        :func:`~rocklab.physics.flight.takeoff_speed`, keyword ``terms``).
        None for the losses of :class:`FlightLoss`, which the closed forms
        hold themselves (keywords zeta, mu, kappa).
    work_slope : callable, optional
        ``work_slope(A, a, p, *values)``: d work / dA of the rise [rad/s^2],
        the slope of the Newton passes that find the apex.
    """

    name: str
    params: tuple[str, ...]
    deceleration: Callable[..., float]
    smooth: bool = True
    work: Callable[..., Any] | None = None
    work_slope: Callable[..., Any] | None = None


# q: the parameters, an array at run time (Sequence: its items read as floats, which numba compiles)
def _viscous(theta: float, thetadot: float, p: float, q: Sequence[float], i: int) -> float:
    return 2.0 * q[i] * p * thetadot


def _dry_friction(theta: float, thetadot: float, p: float, q: Sequence[float], i: int) -> float:
    return q[i] * p**2 * (1.0 if thetadot > 0.0 else (-1.0 if thetadot < 0.0 else 0.0))


def _drag(theta: float, thetadot: float, p: float, q: Sequence[float], i: int) -> float:
    return q[i] * thetadot * abs(thetadot)


# the terms of rocklab.physics.flight.loss_deceleration, each its share of it, the same operations
VISCOUS = FlightTerm("viscous", ("zeta",), _viscous)
DRY_FRICTION = FlightTerm("dry friction", ("mu",), _dry_friction, smooth=False)
DRAG = FlightTerm("drag", ("kappa",), _drag)


@dataclass(frozen=True)
class Restitution(Law):
    """e times ``scale`` exp(+-``asymmetry``/2) on leaving hinge +-1 (Sect. 3, Figs. 14b, 15).

    A scale c of e_an is ``Restitution(c)``; hinges that differ by a ratio
    exp(s_e) of their e, ``Restitution(asymmetry=s_e)``.  A ``drift`` d
    (None: none) makes the factors follow the test's place n in its series
    (0 first, 1 last) or in the range of the test log's column ``along``:
    times exp(d (n - 1/2)).
    """

    scale: float = 1.0
    asymmetry: float = 0.0
    drift: float | None = None
    along: str | None = None

    def factors(self, place: Floats = None) -> tuple[Floats, Floats]:
        """The factors (hinge +1, hinge -1) of a wall at its place n [-] (read only with a drift)."""
        pos, neg = self.scale * math.exp(self.asymmetry / 2), self.scale * math.exp(-(self.asymmetry / 2))
        if self.drift is None:
            return pos, neg
        f = np.exp(self.drift * (place - 0.5))
        return pos * f, neg * f

    def on_impacts(self, leaving_plus: Floats) -> Floats:
        """The factor of each impact, ``leaving_plus`` (bool array) where it leaves hinge +1 [-]."""
        return self.scale * np.exp(np.where(leaving_plus, 0.5, -0.5) * self.asymmetry)

    def act_on(self, mp: Any) -> Any:
        pos, neg = self.factors(None if self.drift is None else mp.place(self.along))
        return replace(mp, c_pos=pos * mp.c_pos, c_neg=neg * mp.c_neg)


@dataclass(frozen=True)
class HousnerLoss(Law):
    """e = 1 - fraction (1 - |e_an|) - constant, with the sign of e_an: a fraction of the loss
    Eq. 2 gives the slenderness plus a constant loss per impact (issue 12); |e| within [0, 1]."""

    fraction: float = 1.0
    constant: float = 0.0

    def restitution(self, e_an: Floats) -> Floats:
        """The base e [-] from the analytic one, ``e_an`` (array_like, signed)."""
        return np.sign(e_an) * np.clip(1.0 - self.fraction * (1.0 - np.abs(e_an)) - self.constant, 0.0, 1.0)

    def act_on(self, mp: Any) -> Any:
        return replace(mp, e0=self.restitution(mp.e0))


@dataclass(frozen=True)
class Amplitude(Law):
    """Eq. 17: e times a - b (thetadot^-/thetadot_r)^2, the bracket clipped to [0, 1/|e|]
    (:func:`rocklab.physics.impact.amplitude_factor`); ``a`` multiplies, ``b`` is set."""

    a: float = 1.0
    b: float = 0.0

    def act_on(self, mp: Any) -> Any:
        return replace(mp, amp_a=self.a * mp.amp_a, amp_b=self.b * np.ones_like(mp.alpha))


@dataclass(frozen=True)
class SpeedFactor(Law):
    """e times g(thetadot^-/thetadot_r), g piecewise linear between its values ``knots`` at
    :data:`KNOTS` (its last segment continued beyond them, :func:`hats`; e within the bounds of
    :func:`rocklab.physics.impact.bounded_factor`): a law of the impact speed no closed form
    dictates.  The exact simulator's law is :class:`rocklab.physics.impact.SpeedLaw` (the
    reference integrator and the numba engine)."""

    knots: tuple[float, ...] = (1.0, 1.0, 1.0, 1.0)

    def act_on(self, mp: Any) -> Any:
        return replace(mp, speed_knots=np.tile(np.array(self.knots), (mp.alpha.size, 1)))


#: Knots of :class:`SpeedFactor` in thetadot^- / thetadot_r [-].
KNOTS = np.array([0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0])


def hats(x: Floats) -> Floats:
    """Piecewise-linear basis at :data:`KNOTS` of speeds x [thetadot_r], shape (..., knots).

    Beyond the last knot the last segment goes on (the convention of every
    law past its fitted speeds, module docstring); speeds are not negative.
    """
    x = np.maximum(np.asarray(x, float), KNOTS[0])[..., None]
    h = KNOTS[1] - KNOTS[0]
    inside = np.maximum(1.0 - np.abs(np.minimum(x, KNOTS[-1]) - KNOTS) / h, 0.0)
    past = np.maximum(x - KNOTS[-1], 0.0) / h
    return inside + past * np.r_[np.zeros(KNOTS.size - 2), -1.0, 1.0]


def speed_factor(x: Floats, knots: npt.ArrayLike) -> Floats:
    """g(x) of :class:`SpeedFactor` [-]: the piecewise-linear law of its values ``knots`` at :data:`KNOTS`
    (:func:`hats`), at speeds x [thetadot_r]; ``knots`` (..., knots) one law per leading index of x
    (a law per test of (tests, impacts) speeds) or one for all."""
    h = hats(x)
    k = np.asarray(knots, float)
    if 1 < k.ndim < h.ndim:
        k = k.reshape(k.shape[:-1] + (1,) * (h.ndim - k.ndim) + k.shape[-1:])
    return np.sum(h * k, axis=-1)


def speed_factor_at(x: float, knots: FloatArray) -> float:
    """g(x) of :func:`speed_factor` at one speed x [thetadot_r], ``knots`` one law, in scalar
    arithmetic: the form the numba engine compiles (:mod:`rocklab.simulation.engine`).

    Linear between the knots of :data:`KNOTS` (a uniform grid), the last segment continued past them.
    """
    n = KNOTS.size
    h = KNOTS[1] - KNOTS[0]
    x = max(x, KNOTS[0])
    j = min(int((x - KNOTS[0]) / h), n - 2)
    return float(knots[j] + (knots[j + 1] - knots[j]) * ((x - KNOTS[j]) / h))


@dataclass(frozen=True)
class Hinge(Law):
    """The rocking angles times ``ratio`` exp(+-``asymmetry``/2) on hinge +-1: a rounded or indented
    hinge (alpha_r = r alpha, Sect. 3), hinges that differ.  With ``rounding`` k the angle of a
    flight of apex A is a (1 - k) + k A (:func:`rocklab.physics.flight.flight_angle`)."""

    ratio: float = 1.0
    asymmetry: float = 0.0
    rounding: float | None = None

    def angles(self, a_pos: Floats, a_neg: Floats) -> tuple[Floats, Floats]:
        """The rocking angles [rad] of hinges +1 and -1 of angles ``a_pos``, ``a_neg``."""
        h = self.asymmetry / 2
        return self.ratio * a_pos * math.exp(h), self.ratio * a_neg * math.exp(-h)

    def act_on(self, mp: Any) -> Any:
        a_pos, a_neg = self.angles(mp.a_pos, mp.a_neg)
        k = mp.rounding if self.rounding is None else self.rounding * np.ones_like(mp.alpha)
        return replace(mp, a_pos=a_pos, a_neg=a_neg, rounding=k)


@dataclass(frozen=True)
class FlightLoss(Law):
    """Losses between impacts (:func:`rocklab.physics.flight.loss_deceleration`): viscous ``zeta``
    [-], dry friction at the hinge ``mu_over_alpha`` (mu / alpha) and quadratic drag
    ``kappa_alpha`` (kappa alpha), set (not added) by the law: the model's zeta, mu [-] and
    kappa [1/rad], whose closed forms :mod:`rocklab.physics.flight` holds itself."""

    zeta: float = 0.0
    mu_over_alpha: float = 0.0
    kappa_alpha: float = 0.0

    #: Its terms in flight, those of the model's zeta, mu and kappa in that order.
    TERMS: ClassVar[tuple[FlightTerm, ...]] = (VISCOUS, DRY_FRICTION, DRAG)

    def act_on(self, mp: Any) -> Any:
        return replace(
            mp,
            zeta=self.zeta * np.ones_like(mp.alpha),
            mu=self.mu_over_alpha * mp.alpha,
            kappa=self.kappa_alpha / mp.alpha,
        )


@dataclass(frozen=True)
class Gap(Law):
    """A one-sided wall swings inwards through g = ``over_alpha`` alpha before it strikes the
    transverse walls (Fig. 12): base impacts of Eq. 2, the transverse impact of Eqs. 12-13."""

    over_alpha: float = 0.0

    def act_on(self, mp: Any) -> Any:
        gap_model = mp.one_sided.copy()
        return replace(
            mp,
            gap_model=gap_model,
            e0=np.where(gap_model, restitution.two_sided(mp.alpha), mp.e0),
            gap=self.over_alpha * mp.alpha,
        )


@dataclass(frozen=True)
class Stop(Law):
    """A landing slower than ``v_stop`` thetadot_r (Eq. 16) sticks: e = 0
    (:class:`rocklab.physics.impact.Sticking`)."""

    v_stop: float | FloatArray = 0.0

    def act_on(self, mp: Any) -> Any:
        return replace(mp, stop=self.v_stop * np.ones_like(mp.alpha))
