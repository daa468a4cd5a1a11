"""Rocking wall of Housner (1963), Sect. 1 and Fig. 1 of the paper.

The exact simulator's wall.  The causes of the diagnosis do not map
themselves onto it: a wall of the diagnosis' model is derived from the
one model, :class:`rocklab.diagnosis.wall_model.ModelParams`, by
:func:`rocklab.diagnosis.wall_model.simulator` (the calibrated walls of the maps
too), from the causes' laws (:mod:`rocklab.physics.law`).

Equation of motion (per unit I_O) on the hinge ``s = sign(theta)`` with
rocking angle ``alpha_s`` (``alpha_rock`` for s = +1, ``alpha_neg`` for -1)::

    exact:   thetaddot = -p^2 [sin(s alpha_s - theta) + (ag/g) cos(s alpha_s - theta)]
    linear:  thetaddot =  p^2 theta - p^2 (s alpha_s + ag/g)         (Housner, small alpha)

each with the optional losses in flight between impacts,
``- 2 zeta p thetadot - mu p^2 sign(thetadot) - kappa thetadot |thetadot|``: viscous,
dry friction at the hinge and quadratic drag
(:func:`rocklab.physics.flight.loss_deceleration`), and the terms in flight
of other laws (``terms``), each the deceleration its law declares
(:class:`rocklab.physics.law.FlightTerm`).

Conventions
-----------
Sign of ``ag``
    ``ag`` is the ground acceleration [m/s^2], positive in the direction the
    top of the wall moves for theta > 0 (outwards, away from the transverse
    walls).  Its d'Alembert force pushes the wall the other way: a positive
    ``ag`` drives theta negative.  The record is linearly interpolated between
    samples and is zero after its last sample (a ramp to zero over one step).
Rocking onset
    A wall at rest starts to rock at the linearly interpolated instant its
    angular acceleration at rest changes sign: for the exact form when
    ``-ag > g tan(alpha_rock)`` (positive hinge) or ``ag > g tan(alpha_neg)``
    (negative hinge); for the linear form the same with ``tan(alpha)``
    replaced by ``alpha``, consistently with its equation of motion.
Impacts
    Located at the root of theta = 0 (or theta = -gap), then
    ``thetadot^+ = e thetadot^-`` with the signed e of :mod:`rocklab.physics.impact`.
Rest
    After an impact with ``|thetadot^+| < REST_TOL * thetadot_r`` (Eq. 16,
    nominal alpha) the wall is at rest: the geometric series of ever smaller
    impacts (chattering) is cut there.  ``REST_TOL = 1e-3`` leaves a peak
    rotation of about 5e-7 alpha.  Under ground motion it stays at rest until
    the onset condition holds again.
Overturning
    ``|theta| >= overturn`` with default ``pi/2`` for both forms: the wall
    lies on the ground, where even the linear form cannot be recovered by any
    realistic record (it would need |ag| > g (pi/2 - alpha)).  ``alpha`` itself
    would be premature under ground motion, which can push a wall back from
    beyond alpha.  After the end of the record, a wall still rocking is
    followed in free motion until it overturns, comes to rest, or, standing
    within the instability rotation of its hinge, its energy can no longer
    reach that of a reachable hinge (every law with |e| <= 1 then keeps it
    standing).  A wall beyond the instability rotation is on the falling side
    of the potential maximum: with less energy it cannot climb back and
    falls, so it is always followed.
Terms in flight that jump
    A term that jumps where thetadot changes sign (dry friction, a moment
    on the rise only: :attr:`rocklab.physics.law.FlightTerm.smooth` false)
    acts against the direction the wall moves, and a wall at rest starts
    only when the ground overcomes it too.  Under ground motion it may hold
    the wall where it turns, the ground pushing it less than the term
    resists either way: the wall stays there (a rest off the edge) until
    the ground moves it.  The engine locates every turn and starts anew
    from it, and so does the reference under ground motion; in free
    rocking the reference steps over the turns and looks for no hold (dry
    friction that holds a wall at its apex, above), as it always has.
One-sided rocking and the gap
    ``boundary="one-sided"`` keeps theta >= 0 and with ``gap == 0`` applies the
    impact law (default Eq. 14, negative: a rebound) at theta = 0.  With
    ``gap > 0`` the wall rocks two-sided on its inner hinge in
    ``-gap <= theta < 0``: crossing theta = 0 is a base impact (default Eq. 2),
    reaching theta = -gap the impact on the transverse walls (default
    Eqs. 12-13, a rebound).  Base + transverse + base reproduces Eq. 14 as
    gap -> 0 (Fig. 12).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Self, TypeAlias

import numpy as np
import pandas as pd
import xarray as xr

from rocklab.io import cf_attrs
from rocklab.physics import flight, wall
from rocklab.physics import impact as _impact
from rocklab.physics.boundary import Boundary
from rocklab.physics.flight import FloatArray, Floats
from rocklab.physics.law import DRAG, DRY_FRICTION, FlightLoss, FlightTerm
from rocklab.simulation import engine
from rocklab.simulation.flight_terms import flight_slots

#: Rest threshold: |thetadot^+| below REST_TOL * thetadot_r (Eq. 16) is rest.
REST_TOL = 1e-3

#: Default overturning rotation [rad] (wall lying on the ground).
OVERTURN = math.pi / 2

#: Terms in flight with their values, ``(term, values)``.
TermValues: TypeAlias = tuple[tuple[FlightTerm, Sequence[Floats]], ...]


def record_times(t_end: float, fs: float) -> np.ndarray:
    """The sample times [s] of a simulated record, 0 to ``t_end`` at ``fs`` [Hz] (the last
    sample may lie past ``t_end`` by up to half an interval), of both simulators."""
    return np.arange(0.0, t_end + 0.5 / fs, 1.0 / fs)


def _sign(x: float) -> float:
    """sign(x) of a float, 0 at 0 (the scalar right-hand side of the reference)."""
    return 1.0 if x > 0.0 else (-1.0 if x < 0.0 else 0.0)


def _restoring(
    theta: Floats, a: Floats, ag_g: Floats, linear: bool, sin: Callable[[Any], Any], cos: Callable[[Any], Any]
) -> Floats:
    """thetaddot / p^2 without the flight loss on the hinge at signed angle
    ``a`` (module docstring, exact or linear); ``sin``, ``cos`` from math or
    numpy."""
    if linear:
        return theta - a - ag_g
    return -(sin(a - theta) + ag_g * cos(a - theta))


@dataclass(frozen=True)
class RockingModel:
    """A rocking wall: geometry, boundary condition, impact law and form.

    Attributes
    ----------
    alpha : float
        Nominal slenderness angle [rad], used by the analytic e (Sect. 3).
    p : float
        Frequency parameter sqrt(m g R / I_O) [rad/s].
    boundary : {"two-sided", "one-sided"}
    impact : ImpactLaw, optional
        Law of the base impacts.  Default: Eq. 2 for two-sided rocking and
        for one-sided rocking with a gap, Eq. 14 for one-sided without gap.
    alpha_rock : float, optional
        Rocking angle of the positive hinge, alpha_ind <= alpha (rounded
        hinge, Sect. 3) [rad]; default alpha.
    alpha_neg : float, optional
        Rocking angle of the negative hinge (asymmetry) [rad]; default
        alpha_rock.
    zeta : float
        Viscous-like loss between impacts, -2 zeta p thetadot [-].
    mu : float
        Dry friction at the hinge: a constant moment mu m g R opposing
        thetadot, the deceleration mu p^2 sign(thetadot) [-].  A wall whose
        restoring moment at an apex is below it (sin(alpha - |theta|) <= mu)
        sticks there: released there from rest, or at a turn under ground
        motion, it is held (both simulators); at a turn in free rocking it is
        not modelled (the reference integrator chatters), so release it below
        alpha - mu, with no speed that carries it past.
    kappa : float
        Quadratic drag -kappa thetadot |thetadot| [1/rad].
    gap : float
        One-sided only: inward rotation [rad] through which the wall rocks
        two-sided before striking the transverse walls.
    form : {"exact", "linear"}
    transverse_impact : ImpactLaw, optional
        Law of the impact on the transverse walls (gap > 0); default Eqs. 12-13.
    hinge_rounding : float
        k of a rocking angle that depends on the amplitude (a rounded or
        crushing hinge, :func:`rocklab.physics.flight.flight_angle`): each
        free flight of apex A rocks on alpha_s (1 - k) + k A, the fall from
        the release on that of the release rotation; -1 < k < 1, 0 the rigid
        hinge.  Free rocking only (under ground motion a flight's apex is
        not known when it starts), not in the gap of a one-sided wall.
    terms : tuple
        Terms in flight of other laws: ``(term, values)`` pairs, ``term`` a
        :class:`rocklab.physics.law.FlightTerm` and ``values`` its
        parameters (floats, in the order of ``term.params``).
    """

    alpha: float
    p: float
    boundary: str = Boundary.TWO_SIDED
    impact: _impact.ImpactLaw | None = None
    alpha_rock: float | None = None
    alpha_neg: float | None = None
    zeta: float = 0.0
    gap: float = 0.0
    mu: float = 0.0
    kappa: float = 0.0
    form: str = "exact"
    transverse_impact: _impact.ImpactLaw | None = field(default=None)
    hinge_rounding: float = 0.0
    terms: TermValues = ()

    def __post_init__(self) -> None:
        if self.boundary not in set(Boundary):
            raise ValueError(f"boundary must be 'two-sided' or 'one-sided', not {self.boundary!r}")
        if self.form not in ("exact", "linear"):
            raise ValueError(f"form must be 'exact' or 'linear', not {self.form!r}")
        if self.gap < 0 or (self.gap > 0 and self.boundary != Boundary.ONE_SIDED):
            raise ValueError("gap must be >= 0 and is only meaningful for one-sided rocking")
        if not -1.0 < self.hinge_rounding < 1.0:
            raise ValueError(f"hinge_rounding must be in (-1, 1), not {self.hinge_rounding!r}")
        if min(self.zeta, self.mu, self.kappa) < 0:
            raise ValueError("zeta, mu and kappa are losses: >= 0")
        for term, values in self.terms:
            if len(values) != len(term.params):
                raise ValueError(f"{term.name} has the parameters {', '.join(term.params)}, not {values!r}")

    @classmethod
    def from_wall(cls, height_m: float, thickness_m: float, **kw: Any) -> Self:
        """Homogeneous wall of height h and thickness b [m] (rocklab.physics.wall)."""
        alpha = float(wall.slenderness_angle(height_m, thickness_m))
        p = float(wall.frequency_parameter(wall.half_diagonal(height_m, thickness_m)))
        return cls(alpha=alpha, p=p, **kw)

    @property
    def alpha_pos(self) -> float:
        return self.alpha if self.alpha_rock is None else float(self.alpha_rock)

    @property
    def alpha_minus(self) -> float:
        return self.alpha_pos if self.alpha_neg is None else float(self.alpha_neg)

    @property
    def one_sided(self) -> bool:
        return self.boundary == Boundary.ONE_SIDED

    @property
    def base_law(self) -> _impact.ImpactLaw:
        return _impact.analytic(self.boundary, self.gap > 0) if self.impact is None else self.impact

    @property
    def transverse_law(self) -> _impact.ImpactLaw:
        return _impact.Transverse() if self.transverse_impact is None else self.transverse_impact

    @property
    def thetadot_r(self) -> float:
        """Overturning velocity of Eq. 16 (nominal alpha) [rad/s]."""
        return float(wall.overturning_velocity(self.alpha, self.p))

    def alpha_side(self, side: Floats) -> Floats:
        """Rocking angle of hinge ``side`` (+1 / -1, array_like) [rad]."""
        if np.ndim(side) == 0:
            return self.alpha_pos if side > 0 else self.alpha_minus
        return np.where(np.asarray(side) > 0, self.alpha_pos, self.alpha_minus)

    def flight_terms(self) -> TermValues:
        """The terms in flight with their values, ``(term, values)``: the losses zeta, mu and kappa
        (:attr:`rocklab.physics.law.FlightLoss.TERMS`), then ``terms``."""
        return (*zip(FlightLoss.TERMS, ((self.zeta,), (self.mu,), (self.kappa,))), *self.terms)

    def engine_terms(self) -> TermValues:
        """The terms in flight the numba engine takes as declared, ``(term, values)``: all but the
        viscous loss, which it integrates itself; none at their null."""
        own = ((DRY_FRICTION, (self.mu,)), (DRAG, (self.kappa,)), *self.terms)
        return tuple((t, v) for t, v in own if any(v))

    @property
    def jumps(self) -> bool:
        """Whether a term in flight jumps where thetadot changes sign (dry friction, ...): the wall may
        be held where it turns, or at rest until the ground overcomes the term too."""
        return any(not t.smooth for t, _ in self.engine_terms())

    def acceleration(self, theta: Floats, thetadot: Floats, side: Floats, ag: Floats) -> Floats:
        """Angular acceleration [rad/s^2] on hinge ``side`` under ``ag`` [m/s^2] (array_like; theta
        [rad] and thetadot [rad/s] floats where the wall has ``terms``)."""
        a = side * self.alpha_side(side)
        restoring = _restoring(theta, a, ag / wall.G, self.form == "linear", np.sin, np.cos)
        acc = self.p**2 * restoring - flight.loss_deceleration(thetadot, self.p, self.zeta, self.mu, self.kappa)
        for term, values in self.terms:
            acc = acc - term.deceleration(theta, thetadot, self.p, values, 0)
        return acc

    def equation_of_motion(
        self, side: float, a0: float, slope: float, t0: float
    ) -> Callable[[float, FloatArray], list[float]]:
        """Right-hand side f(t, y) for solve_ivp, y = (theta, thetadot), on hinge
        ``side`` under ag(t) = a0 + slope (t - t0) [m/s^2]; scalar (math, not
        numpy), since the event-driven reference calls it millions of times."""
        a = side * float(self.alpha_side(side))
        p2, c, g, lin = self.p**2, 2.0 * self.zeta * self.p, wall.G, self.form == "linear"

        if self.mu or self.kappa or self.terms:
            p = self.p
            (first, q0), *rest = ((term.deceleration, values) for term, values in self.flight_terms())

            def rhs_terms(t: float, y: FloatArray) -> list[float]:
                ag_g = (a0 + slope * (t - t0)) / g
                # the terms see the rotation on this hinge, its mirror past the edge (a solver step that
                # finds the impact reaches past it): each continued smoothly there
                th = side * abs(y[0])
                # the sum in the order of the terms: that of flight.loss_deceleration for the losses
                d = first(th, y[1], p, q0, 0)
                for deceleration, q in rest:
                    d = d + deceleration(th, y[1], p, q, 0)
                return [y[1], p2 * _restoring(y[0], a, ag_g, lin, math.sin, math.cos) - d]

            return rhs_terms

        def rhs(t: float, y: FloatArray) -> list[float]:
            return [y[1], p2 * _restoring(y[0], a, (a0 + slope * (t - t0)) / g, lin, math.sin, math.cos) - c * y[1]]

        return rhs

    def energy(self, theta: Floats, thetadot: Floats, side: Floats) -> Floats:
        """Energy per unit I_O measured as 1/2 thetadot^2 at theta = 0 [rad^2/s^2].

        Conserved between impacts in free undamped motion; the wall can reach
        the instability rotation of hinge s only if it exceeds
        :meth:`critical_energy` (s).
        """
        return flight.energy(np.abs(theta), thetadot, self.alpha_side(side), self.p, self.form == "linear")

    def critical_energy(self, side: Floats) -> Floats:
        """Energy that reaches the instability rotation of hinge ``side`` [rad^2/s^2]."""
        a = self.alpha_side(side)
        return flight.energy(a, 0.0, a, self.p, self.form == "linear")

    def reachable_sides(self) -> tuple[int, ...]:
        return (1,) if self.one_sided else (1, -1)

    def flight_model(self, theta: float, thetadot: float, side: float) -> RockingModel:
        """The model of the free flight that starts at (theta, thetadot) on hinge ``side``.

        Itself, unless the rocking angle depends on the amplitude
        (``hinge_rounding``): then the rigid model on the angle of this
        flight, from its apex (:func:`rocklab.physics.flight.apex_after` from
        theta = 0, with the losses in flight, the release rotation otherwise).
        """
        if not self.hinge_rounding or (self.one_sided and side < 0):
            return self
        a, k = self.alpha_side(side), self.hinge_rounding
        loss: dict[str, Any] = {"zeta": self.zeta, "mu": self.mu, "kappa": self.kappa, "k": k, "terms": self.terms}
        A = flight.apex_after(abs(thetadot), a, self.p, **loss) if theta == 0 else abs(theta)
        angle = float(flight.flight_angle(A, a, k))
        pos, neg = (angle, self.alpha_minus) if side > 0 else (self.alpha_pos, angle)
        return replace(self, alpha_rock=pos, alpha_neg=neg, hinge_rounding=0.0)

    def numba_params(
        self,
        overturn: float = OVERTURN,
        rest_tol: float = REST_TOL,
        substeps: int = 1,
        terms: Sequence[FlightTerm] | None = None,
    ) -> FloatArray:
        """Parameter vector of the numba engine, by the names of :data:`rocklab.simulation.engine.LAYOUT`.

        ``terms``: the terms in flight whose parameters the vector holds, in
        the slots of :func:`rocklab.simulation.flight_terms.flight_slots` (a
        batch of walls: those of all of them); default the wall's own
        (:meth:`engine_terms`).

        Raises
        ------
        NotImplementedError
            For a rocking angle that depends on the amplitude (``hinge_rounding``):
            the engines integrate ground motion, where a flight's apex is not known when it starts;
            for terms in flight beyond the viscous loss in the linear form,
            whose closed form has that loss alone
            (:mod:`rocklab.simulation.reference` simulates them, and the
            engine's exact form).
        """
        if self.hinge_rounding:
            raise NotImplementedError(
                f"a rocking angle that depends on the amplitude (hinge_rounding = {self.hinge_rounding:g}) is "
                "defined flight by flight in free rocking; the engines integrate ground motion"
            )
        own = self.engine_terms()
        if own and self.form == "linear":
            found = ", ".join(f"{t.name} ({', '.join(f'{n} = {v:g}' for n, v in zip(t.params, q))})" for t, q in own)
            raise NotImplementedError(
                f"the numba engine's linear form is a closed form with the viscous loss alone, not {found}: "
                "simulate the exact form, or with rocklab.simulation.reference"
            )
        slots = flight_slots(tuple(t for t, _ in own) if terms is None else terms)
        prm = np.zeros(len(engine.LAYOUT))
        values = {
            "alpha_pos": self.alpha_pos,
            "alpha_neg": self.alpha_minus,
            "p": self.p,
            "zeta": self.zeta,
            "gap": self.gap,
            "one_sided": float(self.one_sided),
            "linear": float(self.form == "linear"),
            "overturn": overturn,
            "v_rest": rest_tol * self.thetadot_r,
            "g": wall.G,
            "substeps": float(substeps),
            "v_r": self.thetadot_r,
            "terms": float(bool(own)),
            "turns": float(self.jumps),
        }
        for name, value in values.items():
            prm[engine.slot(name)] = value
        for term, q in own:
            prm[slots[term] : slots[term] + len(q)] = q
        return prm

    def numba_law(self) -> FloatArray:
        """Impact laws as a (3, 4) array: rows base +, base -, transverse;
        columns e0, a, b of the flat form (:meth:`rocklab.physics.impact.ImpactLaw.flat`)
        and v_stick [thetadot_r] of a :class:`~rocklab.physics.impact.Sticking`
        law (0: none); a wall with a law of the impact speed
        (:class:`~rocklab.physics.impact.SpeedLaw`) has two more columns and one per
        knot of :data:`rocklab.physics.law.KNOTS`: whether it acts on each impact or
        on an excursion through a gap as a whole (:data:`rocklab.simulation.engine.SPEED_EACH`,
        :data:`~rocklab.simulation.engine.SPEED_EXCURSION`) and its values g at the knots.

        Raises
        ------
        NotImplementedError
            For a law the engines cannot evaluate (no flat form).
        """
        rows = [
            _engine_row(self.base_law, 1, self.alpha),
            _engine_row(self.base_law, -1, self.alpha),
            _engine_row(self.transverse_law, -1, self.alpha),
        ]
        width = max(len(r) for r in rows)
        return np.array([r + [0.0] * (width - len(r)) for r in rows])


def _engine_row(law: _impact.ImpactLaw, side: int, alpha: float) -> list[float]:
    """(e0, a, b, v_stick) of ``law`` on hinge ``side``: the flat form, with
    the sticking threshold of a :class:`~rocklab.physics.impact.Sticking`
    law (possibly per hinge, :class:`~rocklab.physics.impact.Sided`), then the
    columns of a :class:`~rocklab.physics.impact.SpeedLaw` where it has one
    (:meth:`RockingModel.numba_law`)."""
    if isinstance(law, _impact.Sided):
        return _engine_row(law.law_pos if side > 0 else law.law_neg, side, alpha)
    if isinstance(law, _impact.Sticking):
        row = _engine_row(law.law, side, alpha)
        return [*row[:3], law.v_stick, *row[4:]]
    if isinstance(law, _impact.SpeedLaw):
        mode = engine.SPEED_EXCURSION if law.excursion else engine.SPEED_EACH
        return [*_engine_row(law.law, side, alpha)[:4], mode, *law.knots]
    return [*law.flat(alpha)[0 if side > 0 else 1], 0.0]


@dataclass
class RockingHistory:
    """Response of one wall on a uniform time grid.

    Attributes
    ----------
    t, theta, thetadot : ndarray
        Time [s], rotation [rad], angular velocity [rad/s]; NaN after
        overturning.
    impacts : pandas.DataFrame
        One row per impact: t [s], kind ('base' | 'transverse'),
        thetadot_before, thetadot_after [rad/s], theta_peak_before [rad]
        (largest |theta| since the previous impact or the release).
    overturned : bool
    t_overturn : float or None
    t_rest : float or None
        Start of the final rest, if the wall ends at rest.
    """

    t: FloatArray
    theta: FloatArray
    thetadot: FloatArray
    impacts: pd.DataFrame
    overturned: bool
    t_overturn: float | None
    t_rest: float | None
    model: RockingModel | None = None
    ag: FloatArray | None = None

    def to_xarray(self) -> xr.Dataset:
        """CF-1.8 dataset: theta, thetadot (and ag) on time; impacts on their own dim.

        ``time`` [s] runs from the start of the simulation, not a date (see
        :mod:`rocklab.io`); ``impact_kind`` is written as a character array,
        which CF-1.8 tools read, whatever writes the dataset.
        """
        ds = xr.Dataset(
            {
                "theta": ("time", self.theta, {"long_name": "rotation of the wall", "units": "rad"}),
                "thetadot": ("time", self.thetadot, {"long_name": "angular velocity", "units": "rad/s"}),
            },
            coords={"time": ("time", self.t, {"long_name": "time since the start of the simulation", "units": "s"})},
        )
        if self.ag is not None:
            ds["ag"] = ("time", self.ag, {"long_name": "ground acceleration (+ towards +theta)", "units": "m/s2"})
        imp = self.impacts
        ds = ds.assign_coords(impact=("impact", np.arange(len(imp)), {"long_name": "impact index", "units": "1"}))
        ds["impact_time"] = ("impact", imp["t"].to_numpy(float), {"long_name": "time of the impact", "units": "s"})
        ds["impact_kind"] = ("impact", imp["kind"].to_numpy(str).astype("U10"), {"long_name": "base or transverse"})
        ds["impact_kind"].encoding["dtype"] = "S1"
        for name, long_name in (
            ("thetadot_before", "angular velocity just before the impact"),
            ("thetadot_after", "angular velocity just after the impact"),
        ):
            ds[name] = ("impact", imp[name].to_numpy(float), {"long_name": long_name, "units": "rad/s"})
        ds["theta_peak_before"] = (
            "impact",
            imp["theta_peak_before"].to_numpy(float),
            {"long_name": "largest |theta| since the previous impact or the release", "units": "rad"},
        )
        attrs = {
            **cf_attrs("rocking wall history", "rocking simulation (rocklab.simulation)"),
            "overturned": int(self.overturned),
            "t_overturn": np.nan if self.t_overturn is None else self.t_overturn,
            "t_rest": np.nan if self.t_rest is None else self.t_rest,
        }
        if self.model is not None:
            m = self.model
            attrs.update(
                alpha=m.alpha,
                p=m.p,
                boundary=m.boundary,
                form=m.form,
                alpha_rock=m.alpha_pos,
                alpha_neg=m.alpha_minus,
                zeta=m.zeta,
                mu=m.mu,
                kappa=m.kappa,
                hinge_rounding=m.hinge_rounding,
                gap=m.gap,
                impact=type(m.base_law).__name__,
            )
            if m.terms:
                attrs["flight_terms"] = "; ".join(
                    f"{t.name} ({', '.join(f'{n} = {v:g}' for n, v in zip(t.params, q))})" for t, q in m.terms
                )
        ds.attrs.update(attrs)
        return ds
