"""Rocking wall of Housner (1963), Sect. 1 and Fig. 1 of the paper.

Equation of motion (per unit I_O) on the hinge ``s = sign(theta)`` with
rocking angle ``alpha_s`` (``alpha_rock`` for s = +1, ``alpha_neg`` for -1)::

    exact:   thetaddot = -p^2 [sin(s alpha_s - theta) + (ag/g) cos(s alpha_s - theta)]
    linear:  thetaddot =  p^2 theta - p^2 (s alpha_s + ag/g)         (Housner, small alpha)

each with the optional viscous-like loss ``- 2 zeta p thetadot`` between impacts.

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
    ``thetadot^+ = e thetadot^-`` with the signed e of :mod:`rocklab.impact`.
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
    followed in free motion until it overturns, comes to rest, or its energy
    can no longer reach the instability rotation of a reachable hinge (every
    law with |e| <= 1 then keeps it standing).
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
from dataclasses import dataclass, field

import numba
import numpy as np
import pandas as pd
import xarray as xr
from scipy.integrate import solve_ivp

from rocklab import impact as _impact
from rocklab import wall

#: Rest threshold: |thetadot^+| below REST_TOL * thetadot_r (Eq. 16) is rest.
REST_TOL = 1e-3

#: Default overturning rotation [rad] (wall lying on the ground).
OVERTURN = math.pi / 2


def _restoring(theta, a, ag_g, linear, sin, cos):
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
    flight_damping : float
        zeta of the viscous-like term -2 zeta p thetadot between impacts [-].
    gap : float
        One-sided only: inward rotation [rad] through which the wall rocks
        two-sided before striking the transverse walls.
    form : {"exact", "linear"}
    transverse_impact : ImpactLaw, optional
        Law of the impact on the transverse walls (gap > 0); default Eqs. 12-13.
    """

    alpha: float
    p: float
    boundary: str = "two-sided"
    impact: _impact.ImpactLaw | None = None
    alpha_rock: float | None = None
    alpha_neg: float | None = None
    flight_damping: float = 0.0
    gap: float = 0.0
    form: str = "exact"
    transverse_impact: _impact.ImpactLaw | None = field(default=None)

    def __post_init__(self):
        if self.boundary not in ("two-sided", "one-sided"):
            raise ValueError(f"boundary must be 'two-sided' or 'one-sided', not {self.boundary!r}")
        if self.form not in ("exact", "linear"):
            raise ValueError(f"form must be 'exact' or 'linear', not {self.form!r}")
        if self.gap < 0 or (self.gap > 0 and self.boundary != "one-sided"):
            raise ValueError("gap must be >= 0 and is only meaningful for one-sided rocking")

    @classmethod
    def from_wall(cls, height_m, thickness_m, **kw):
        """Homogeneous wall of height h and thickness b [m] (rocklab.wall)."""
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
        return self.boundary == "one-sided"

    @property
    def base_law(self) -> _impact.ImpactLaw:
        if self.impact is not None:
            return self.impact
        if self.one_sided and self.gap == 0:
            return _impact.OneSided()
        return _impact.HousnerTwoSided()

    @property
    def transverse_law(self) -> _impact.ImpactLaw:
        return _impact.Transverse() if self.transverse_impact is None else self.transverse_impact

    @property
    def thetadot_r(self) -> float:
        """Overturning velocity of Eq. 16 (nominal alpha) [rad/s]."""
        return float(wall.overturning_velocity(self.alpha, self.p))

    def alpha_side(self, side):
        """Rocking angle of hinge ``side`` (+1 / -1, array_like) [rad]."""
        if np.ndim(side) == 0:
            return self.alpha_pos if side > 0 else self.alpha_minus
        return np.where(np.asarray(side) > 0, self.alpha_pos, self.alpha_minus)

    def acceleration(self, theta, thetadot, side, ag):
        """Angular acceleration [rad/s^2] on hinge ``side`` under ``ag`` [m/s^2]."""
        a = side * self.alpha_side(side)
        restoring = _restoring(theta, a, ag / wall.G, self.form == "linear", np.sin, np.cos)
        return self.p**2 * restoring - 2.0 * self.flight_damping * self.p * thetadot

    def equation_of_motion(self, side, a0, slope, t0):
        """Right-hand side f(t, y) for solve_ivp, y = (theta, thetadot), on hinge
        ``side`` under ag(t) = a0 + slope (t - t0) [m/s^2]; scalar (math, not
        numpy), since the event-driven reference calls it millions of times."""
        a = side * float(self.alpha_side(side))
        p2, c, g, lin = self.p**2, 2.0 * self.flight_damping * self.p, wall.G, self.form == "linear"

        def rhs(t, y):
            return [y[1], p2 * _restoring(y[0], a, (a0 + slope * (t - t0)) / g, lin, math.sin, math.cos) - c * y[1]]

        return rhs

    def energy(self, theta, thetadot, side):
        """Energy per unit I_O measured as 1/2 thetadot^2 at theta = 0 [rad^2/s^2].

        Conserved between impacts in free undamped motion; the wall can reach
        the instability rotation of hinge s only if it exceeds
        :meth:`critical_energy` (s).
        """
        a = self.alpha_side(side)
        th = np.abs(theta)
        if self.form == "linear":
            pot = self.p**2 * (a * th - 0.5 * th**2)
        else:
            pot = self.p**2 * (np.cos(a - th) - np.cos(a))
        return 0.5 * thetadot**2 + pot

    def critical_energy(self, side):
        a = self.alpha_side(side)
        if self.form == "linear":
            return 0.5 * self.p**2 * a**2
        return self.p**2 * (1.0 - math.cos(a))

    def reachable_sides(self):
        return (1,) if self.one_sided else (1, -1)

    def numba_params(self, overturn=OVERTURN, rest_tol=REST_TOL, substeps=1):
        """Flat parameter vector of the numba engines (see ``_P_*`` indices)."""
        return np.array(
            [
                self.alpha_pos,
                self.alpha_minus,
                self.p,
                self.flight_damping,
                self.gap,
                float(self.one_sided),
                float(self.form == "linear"),
                overturn,
                rest_tol * self.thetadot_r,
                wall.G,
                float(substeps),
                self.thetadot_r,
            ]
        )

    def numba_law(self):
        """Impact laws as a (3, 3) array: rows base +, base -, transverse."""
        base = self.base_law.flat(self.alpha)
        tr = self.transverse_law.flat(self.alpha)
        return np.vstack([base, tr[1:2]])


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

    t: np.ndarray
    theta: np.ndarray
    thetadot: np.ndarray
    impacts: pd.DataFrame
    overturned: bool
    t_overturn: float | None
    t_rest: float | None
    model: RockingModel | None = None
    ag: np.ndarray | None = None

    def to_xarray(self) -> xr.Dataset:
        """CF-style dataset: theta, thetadot (and ag) on time; impacts on their own dim."""
        ds = xr.Dataset(
            {
                "theta": ("time", self.theta, {"long_name": "rotation of the wall", "units": "rad"}),
                "thetadot": ("time", self.thetadot, {"long_name": "angular velocity", "units": "rad/s"}),
            },
            coords={"time": ("time", self.t, {"standard_name": "time", "units": "s"})},
        )
        if self.ag is not None:
            ds["ag"] = ("time", self.ag, {"long_name": "ground acceleration (+ towards +theta)", "units": "m/s2"})
        imp = self.impacts
        ds = ds.assign_coords(impact=("impact", np.arange(len(imp))))
        ds["impact_time"] = ("impact", imp["t"].to_numpy(float), {"units": "s"})
        ds["impact_kind"] = ("impact", imp["kind"].to_numpy(str).astype("U10"))
        ds["thetadot_before"] = ("impact", imp["thetadot_before"].to_numpy(float), {"units": "rad/s"})
        ds["thetadot_after"] = ("impact", imp["thetadot_after"].to_numpy(float), {"units": "rad/s"})
        ds["theta_peak_before"] = ("impact", imp["theta_peak_before"].to_numpy(float), {"units": "rad"})
        attrs = {
            "Conventions": "CF-1.8",
            "title": "rocking wall history (rocklab.rocking)",
            "overturned": int(self.overturned),
            "t_overturn": np.nan if self.t_overturn is None else self.t_overturn,
            "t_rest": np.nan if self.t_rest is None else self.t_rest,
        }
        if self.model is not None:
            m = self.model
            attrs.update(
                alpha=m.alpha, p=m.p, boundary=m.boundary, form=m.form, alpha_rock=m.alpha_pos,
                alpha_neg=m.alpha_minus, flight_damping=m.flight_damping, gap=m.gap,
                impact=type(m.base_law).__name__,
            )
        ds.attrs.update(attrs)
        return ds


# ---------------------------------------------------------------------------
# event-driven reference (scipy.integrate.solve_ivp)


class _Record:
    """Linearly interpolated ground acceleration, zero after the last sample."""

    def __init__(self, ag, dt):
        if ag is None:
            self.t = np.array([0.0, 1.0])
            self.a = np.zeros(2)
        else:
            a = np.asarray(ag, float)
            self.a = np.append(a, 0.0)
            self.t = np.arange(len(self.a)) * float(dt)
        self.free = ag is None

    def __call__(self, t):
        return np.interp(t, self.t, self.a, left=self.a[0], right=0.0)

    def piece(self, t, t_hard):
        """End of the straight piece of the record holding ``t`` (capped at
        ``t_hard``) and the piece as ag(tt) = a0 + slope (tt - t0)."""
        # a piece shorter than rounding (an onset found at a sample up to an
        # ulp) is merged into the next: solve_ivp cannot step over it
        k = int(np.searchsorted(self.t, t + 1e-12 * max(1.0, abs(t)), side="right"))
        if self.free or k >= len(self.t):
            return t_hard, 0.0, 0.0, t
        t0, t1 = self.t[k - 1], self.t[k]
        return min(t1, t_hard), self.a[k - 1], (self.a[k] - self.a[k - 1]) / (t1 - t0), t0


def _onset(model, rec, t0, t_stop, theta_rest):
    """First instant >= t0 and side at which a wall at rest starts rocking.

    The acceleration at rest is affine in ag, so the onset instant is the
    linear interpolation of its zero between record samples.
    """
    if theta_rest < 0:
        candidates = [(-1, +1)]
    else:
        candidates = [(+1, +1)] + ([(-1, -1)] if (not model.one_sided or model.gap > 0) else [])
    tk = rec.t[(rec.t > t0) & (rec.t < t_stop)]
    ts = np.concatenate([[t0], tk, [t_stop]])
    ag = rec(ts)
    best = (None, None)
    for side, direction in candidates:
        f = direction * model.acceleration(theta_rest, 0.0, side, ag)
        pos = np.flatnonzero(f > 0)
        if pos.size == 0:
            continue
        k = pos[0]
        if k == 0:
            t_on = t0
        else:
            t_on = ts[k - 1] + (ts[k] - ts[k - 1]) * f[k - 1] / (f[k - 1] - f[k])
        if best[0] is None or t_on < best[0]:
            best = (t_on, side)
    return best


def _reference(model, rec, theta0, thetadot0, t_end, fs, overturn, rest_tol, rtol, atol, max_step, tail):
    v_rest = rest_tol * model.thetadot_r
    law_base, law_tr = model.base_law, model.transverse_law
    t_out = np.arange(0.0, t_end + 0.5 / fs, 1.0 / fs)
    theta_out = np.full(t_out.shape, np.nan)
    thetadot_out = np.full(t_out.shape, np.nan)
    rows = []
    t, th, thd = 0.0, float(theta0), float(thetadot0)
    resting = th == 0.0 and thd == 0.0
    side = 1 if (th > 0 or (th == 0 and thd >= 0)) else -1
    if model.one_sided and th < -model.gap:
        raise ValueError("one-sided wall: theta0 must be >= -gap")
    rest_at = 0.0
    overturned, t_ov, t_rest = False, None, (0.0 if resting else None)
    t_hard = t_end + tail

    def fill(ta, tb, sol=None, value=0.0):
        sel = (t_out >= ta) & (t_out <= tb)
        if sol is None:
            theta_out[sel], thetadot_out[sel] = value, 0.0
        elif sel.any():
            y = sol(t_out[sel])
            theta_out[sel], thetadot_out[sel] = y[0], y[1]

    while t < t_hard:
        if t >= t_end:
            if resting or all(model.energy(th, thd, side) < model.critical_energy(s) for s in model.reachable_sides()):
                break
        if resting:
            t_stop = t_end
            t_on, s_on = _onset(model, rec, t, t_stop, rest_at)
            if t_on is None:
                fill(t, t_end, value=rest_at)
                break
            fill(t, t_on, value=rest_at)
            t, th, thd, side, resting, t_rest = t_on, rest_at, 0.0, s_on, False, None
        s = side
        # one straight piece of the record at a time: the solution is smooth
        # inside it, so the error control never meets the record's kinks
        t_seg, a0, slope, tk = rec.piece(t, t_hard)
        rhs = model.equation_of_motion(s, a0, slope, tk)

        # a segment that starts on the edge (after an impact, or at an onset)
        # must not find that edge again at its first instant: when the first
        # step spans the whole excursion, the root search would otherwise
        # return the start and log a chain of impacts at one instant
        def ev_base(tt, y, t0=t, s=s):
            return y[0] if tt > t0 else float(s)

        ev_base.terminal, ev_base.direction = True, -float(s)

        def ev_over(tt, y):
            return abs(y[0]) - overturn

        ev_over.terminal, ev_over.direction = True, 1.0

        def ev_peak(tt, y):
            return y[1]

        events = [ev_base, ev_over, ev_peak]
        if model.one_sided and model.gap > 0 and s < 0:

            def ev_tr(tt, y, t0=t):
                return y[0] + model.gap if tt > t0 else 1.0

            ev_tr.terminal, ev_tr.direction = True, -1.0
            events.append(ev_tr)
            # the excursion in the gap can be far shorter than a free step
            seg_step = min(max_step, 0.05 * math.sqrt(2.0 * model.gap / (model.p**2 * model.alpha_minus)))
        else:
            seg_step = max_step
        sol = solve_ivp(
            rhs, (t, t_seg), [th, thd], method="DOP853", rtol=rtol, atol=atol,
            max_step=seg_step, events=events, dense_output=True,
        )
        t_new = sol.t[-1]
        fill(t, min(t_new, t_end), sol.sol)
        peaks = [abs(th), abs(sol.y[0, -1])] + [abs(y[0]) for y in sol.y_events[2]]
        if sol.status == -1:
            raise RuntimeError(f"solve_ivp failed at t = {t:.6g} s: {sol.message}")
        if sol.status != 1:  # reached the end of the piece
            t, th, thd = t_new, sol.y[0, -1], sol.y[1, -1]
            continue
        if sol.t_events[1].size:
            overturned, t_ov = True, float(sol.t_events[1][0])
            break
        transverse = len(events) == 4 and sol.t_events[3].size > 0
        v_before = sol.y[1, -1]
        t = t_new
        if transverse:
            e = float(law_tr.coefficient(v_before, -1, model.alpha, model.p))
            th = -model.gap
        else:
            e = float(law_base.coefficient(v_before, s, model.alpha, model.p))
            th = 0.0
        thd = e * v_before
        rows.append((t, "transverse" if transverse else "base", v_before, thd, max(peaks)))
        wrong_way = (model.one_sided and model.gap == 0 and thd <= 0) or (transverse and thd <= 0)
        if abs(thd) < v_rest or wrong_way:
            resting, rest_at, thd, t_rest = True, th, 0.0, t
        elif not transverse:
            side = 1 if thd > 0 else -1
    if resting and t < t_end:
        fill(t, t_end, value=rest_at)
    impacts = pd.DataFrame(rows, columns=["t", "kind", "thetadot_before", "thetadot_after", "theta_peak_before"])
    return RockingHistory(t_out, theta_out, thetadot_out, impacts, overturned, t_ov, t_rest, model)


def simulate_free(model, theta0, thetadot0=0.0, t_end=30.0, fs=400.0, *, overturn=OVERTURN,
                  rest_tol=REST_TOL, rtol=1e-12, atol=1e-14):
    """Free rocking from given initial conditions, exact event-driven reference.

    Parameters
    ----------
    model : RockingModel
    theta0 : float
        Release rotation [rad] (>= -gap for one-sided walls).
    thetadot0 : float
        Initial angular velocity [rad/s].
    t_end : float
        Duration [s].
    fs : float
        Output sampling frequency [Hz] (400 Hz as in the tests, Sect. 2.1).
    overturn : float
        Overturning rotation |theta| [rad], default pi/2.

    Returns
    -------
    RockingHistory
    """
    return _reference(model, _Record(None, 1.0), theta0, thetadot0, t_end, fs, overturn, rest_tol,
                      rtol, atol, np.inf, 0.0)


def simulate_ground(model, ag, dt, t_end=None, fs=None, overturn=OVERTURN, *, theta0=0.0, thetadot0=0.0,
                    rest_tol=REST_TOL, rtol=1e-10, atol=1e-12, tail=120.0):
    """Response to a ground acceleration record, exact event-driven reference.

    Parameters
    ----------
    model : RockingModel
    ag : array_like
        Ground acceleration [m/s^2], positive towards +theta (module docstring),
        linearly interpolated, zero after the record.
    dt : float
        Sample interval [s].
    t_end : float, optional
        End of the output grid [s]; default the record's duration.
    fs : float, optional
        Output sampling frequency [Hz]; default 1/dt.
    overturn : float
        Overturning rotation |theta| [rad], default pi/2.
    tail : float
        Longest free motion [s] followed after t_end to decide overturning
        of a wall still able to reach alpha.
    """
    ag = np.asarray(ag, float)
    t_end = len(ag) * dt if t_end is None else float(t_end)
    fs = 1.0 / dt if fs is None else float(fs)
    rec = _Record(ag, dt)
    # the solver must not step over the record's kinks
    hist = _reference(model, rec, theta0, thetadot0, t_end, fs, overturn, rest_tol, rtol, atol, dt, tail)
    hist.ag = rec(hist.t)
    return hist


# ---------------------------------------------------------------------------
# numba event-driven engine: one history, record stepped sample by sample

_P_APOS, _P_ANEG, _P_P, _P_ZETA, _P_GAP, _P_ONE, _P_LIN, _P_OV, _P_VREST, _P_G, _P_SUB, _P_VR = range(12)


@numba.njit(cache=True, inline="always")
def _accel(x, v, s, ag, prm):
    a = s * (prm[_P_APOS] if s > 0 else prm[_P_ANEG])
    p2 = prm[_P_P] ** 2
    damp = 2.0 * prm[_P_ZETA] * prm[_P_P] * v
    if prm[_P_LIN] > 0:
        return p2 * (x - a - ag / prm[_P_G]) - damp
    return -p2 * (math.sin(a - x) + ag / prm[_P_G] * math.cos(a - x)) - damp


@numba.njit(cache=True, inline="always")
def _transition(l1, l2, E1, E2):
    """State-transition matrix of y'' + 2 zeta p y' - p^2 y = 0 over a time u,
    from E1, E2 = exp(l1 u), exp(l2 u), the roots l1, l2 of
    l^2 + 2 zeta p l - p^2 (cosh/sinh for zeta = 0)."""
    d = l1 - l2
    return ((l1 * E2 - l2 * E1) / d, (E1 - E2) / d, l1 * l2 * (E2 - E1) / d, (l1 * E1 - l2 * E2) / d)


@numba.njit(cache=True, inline="always")
def _linear_state(x0, v0, c0, c1, u, zp, F):
    """Closed form of x'' + 2 zeta p x' - p^2 x = -p^2 (c0 + c1 u) after time u.

    ``F`` is :func:`_transition` over u: as a matrix product the new state
    is two multiply-adds away from the old one, a short dependency chain in
    the record loop (1.6x faster than through the modal constants).
    """
    xp0 = c0 + zp * c1
    y0 = x0 - xp0
    yd0 = v0 - c1
    return F[0] * y0 + F[1] * yd0 + xp0 + c1 * u, F[2] * y0 + F[3] * yd0 + c1


@numba.njit(cache=True)
def _rk4(x, v, s, ga, gb, u, prm):
    """One RK4 step of length u, ground acceleration linear from ga to gb."""
    gm = 0.5 * (ga + gb)
    k1x, k1v = v, _accel(x, v, s, ga, prm)
    k2x, k2v = v + 0.5 * u * k1v, _accel(x + 0.5 * u * k1x, v + 0.5 * u * k1v, s, gm, prm)
    k3x, k3v = v + 0.5 * u * k2v, _accel(x + 0.5 * u * k2x, v + 0.5 * u * k2v, s, gm, prm)
    k4x, k4v = v + u * k3v, _accel(x + u * k3x, v + u * k3v, s, gb, prm)
    return (x + u / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x), v + u / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v))


@numba.njit(cache=True, inline="always")
def _advance(x, v, s, ga, gb, u, prm, l1, l2, zp, h, Fh):
    """State after time u from (x, v) on hinge s, ag linear from ga to gb."""
    if prm[_P_LIN] > 0:
        a = s * (prm[_P_APOS] if s > 0 else prm[_P_ANEG])
        g = prm[_P_G]
        if u == h:
            # multiplications by reciprocals: divisions cost as much as the
            # closed form itself in the record loop
            ig = 1.0 / g
            return _linear_state(x, v, a + ga * ig, (gb - ga) * (ig / h), u, zp, Fh)
        c1 = (gb - ga) / (g * u) if u > 0 else 0.0
        return _linear_state(x, v, a + ga / g, c1, u, zp, _transition(l1, l2, math.exp(l1 * u), math.exp(l2 * u)))
    return _rk4(x, v, s, ga, gb, u, prm)


@numba.njit(cache=True)
def _coefficient(law, row, v, prm):
    e0, a, b = law[row, 0], law[row, 1], law[row, 2]
    if a == 1.0 and b == 0.0:
        return e0
    r = abs(v) / prm[_P_VR]
    f = a - b * r * r
    if f < 0.0:
        f = 0.0
    if e0 != 0.0 and f > 1.0 / abs(e0):
        f = 1.0 / abs(e0)
    return e0 * f


@numba.njit(cache=True)
def _can_overturn(x, v, s, prm):
    p2 = prm[_P_P] ** 2
    a = prm[_P_APOS] if s > 0 else prm[_P_ANEG]
    th = abs(x)
    if prm[_P_LIN] > 0:
        en = 0.5 * v * v + p2 * (a * th - 0.5 * th * th)
        crit = 0.5 * p2 * prm[_P_APOS] ** 2
        if prm[_P_ONE] == 0:
            crit = min(crit, 0.5 * p2 * prm[_P_ANEG] ** 2)
    else:
        en = 0.5 * v * v + p2 * (math.cos(a - th) - math.cos(a))
        crit = p2 * (1.0 - math.cos(prm[_P_APOS]))
        if prm[_P_ONE] == 0:
            crit = min(crit, p2 * (1.0 - math.cos(prm[_P_ANEG])))
    return en >= crit


@numba.njit(cache=True)
def _outside(x, s, prm, ov):
    """0 inside the current hinge's range, 1 base, 2 transverse, 3 overturned."""
    if abs(x) >= ov:
        return 3
    if s > 0:
        return 1 if x < 0.0 else 0
    if x > 0.0:
        return 1
    if prm[_P_ONE] > 0 and x < -prm[_P_GAP]:
        return 2
    return 0


@numba.njit(cache=True)
def _locate(x, v, s, ga, gb, u, prm, l1, l2, zp, h, Fh, ov, edge, target, f0, f1):
    """First root in (0, u] of theta - ``target`` (``edge``) or of thetadot.

    Safeguarded Newton from the linear interpolation of ``f0``, ``f1`` (the
    function at the step ends): each trial integrates from the step start,
    the derivative is thetadot or :func:`_accel`, and a trial that leaves
    the bracket falls back to bisection.  The bracket side is decided by the
    hinge's range (edge) or by the sign of thetadot.

    Returns
    -------
    t, theta, thetadot at the root.
    """
    lo, hi = 0.0, u
    tn = u * f0 / (f0 - f1) if f0 != f1 else 0.5 * u
    xm, vm = x, v
    # theta is a sum of terms of size ~ alpha + |ag|/g: below this rounding
    # floor Newton only wanders (slow, small velocities)
    floor = 1e-15 * (abs(x) + prm[_P_APOS] + abs(ga) / prm[_P_G]) if edge else 0.0
    tol = (1e-13 if edge else 1e-12) * u
    tm = tn
    for _ in range(60):
        if not (lo < tn < hi):
            tn = 0.5 * (lo + hi)
        # the instant of the state returned, whatever the next trial would be
        tm = tn
        gm = ga + (gb - ga) * tm / u
        xm, vm = _advance(x, v, s, ga, gm, tm, prm, l1, l2, zp, h, Fh)
        if edge:
            f, df, inside = xm - target, vm, _outside(xm, s, prm, ov) == 0
        else:
            f, df, inside = vm, _accel(xm, vm, s, gm, prm), vm * v > 0.0
        if inside:
            lo = tn
        else:
            hi = tn
        if f == 0.0 or hi - lo <= tol:
            break
        if df == 0.0:
            tn = 0.5 * (lo + hi)
            continue
        d = f / df
        if abs(d) <= 1e-12 * u or abs(f) <= floor:
            break
        tn = tn - d
    return tm, xm, vm


@numba.njit(cache=True)
def run_history(ag, h, scale, n_tail, prm, law, x, v, log_t, log_vb, log_va, log_peak):
    """Event-driven integration of one wall, sample interval by sample interval.

    ``ag`` [m/s^2] (times ``scale``) is stepped with interval ``h`` [s] (the
    record's dt times a duration scale), then ``n_tail`` free steps follow
    while the wall can still overturn.  Linear form: exact closed form per
    interval; exact form: ``prm[_P_SUB]`` RK4 substeps per interval.  Events
    (impact, overturning, onset, velocity zero for the peaks) are located by
    bisection inside the step.  Impacts are logged into the ``log_*`` arrays
    up to their length.

    Peaks inside a step (zeros of thetadot) are located only when impacts
    are logged; otherwise max |theta| is sampled at the step ends.

    Returns
    -------
    overturned : bool, t_overturn : float (nan), max |theta|/alpha_s : float,
    number of impacts : int
    """
    n_rec = ag.shape[0]
    n_steps = n_rec + n_tail
    p = prm[_P_P]
    zeta = prm[_P_ZETA]
    l1 = p * (-zeta + math.sqrt(zeta * zeta + 1.0))
    l2 = p * (-zeta - math.sqrt(zeta * zeta + 1.0))
    zp = 2.0 * zeta / p if p > 0 else 0.0
    ih = 1.0 / h
    Fh = _transition(l1, l2, math.exp(l1 * h), math.exp(l2 * h))
    want_peaks = log_t.shape[0] > 0
    ov = prm[_P_OV]
    gap = prm[_P_GAP]
    one = prm[_P_ONE] > 0
    nsub = 1 if prm[_P_LIN] > 0 else max(1, int(prm[_P_SUB]))
    hs = h / nsub
    resting = x == 0.0 and v == 0.0
    hold = False
    rest_at = 0.0
    s = 1.0 if (x > 0.0 or (x == 0.0 and v >= 0.0)) else -1.0
    peak = abs(x)
    max_ratio = 0.0
    n_imp = 0
    max_log = log_t.shape[0]
    k = -1
    while k + 1 < n_steps:
        k += 1
        if k >= n_rec:
            if resting or not _can_overturn(x, v, s, prm):
                break
        if resting:
            # fast-forward through the samples that cannot start the motion:
            # the acceleration at rest is affine in ag, A0 + A1 ag
            A0p = _accel(rest_at, 0.0, 1.0 if rest_at == 0.0 else -1.0, 0.0, prm)
            A1p = _accel(rest_at, 0.0, 1.0 if rest_at == 0.0 else -1.0, 1.0, prm) - A0p
            two = rest_at == 0.0 and not (one and gap == 0.0)
            A0n = _accel(0.0, 0.0, -1.0, 0.0, prm)
            A1n = _accel(0.0, 0.0, -1.0, 1.0, prm) - A0n
            while k + 1 < n_rec - 1:
                a_next = scale * ag[k + 1]
                if A0p + A1p * a_next > 0.0 or (two and A0n + A1n * a_next < 0.0):
                    break
                k += 1
        ga0 = scale * ag[k] if k < n_rec else 0.0
        hold = False
        ga1 = scale * ag[k + 1] if k + 1 < n_rec else 0.0
        t0 = k * h
        tau = 0.0
        while tau < h:
            ga = ga0 + (ga1 - ga0) * (tau * ih)
            if resting:
                # onset: first zero of the (affine in ag) acceleration at rest
                t_on = h + 1.0
                s_on = 0.0
                for c in range(2):
                    if rest_at < 0.0:
                        if c == 1:
                            break
                        ss, dd = -1.0, 1.0
                    elif c == 0:
                        ss, dd = 1.0, 1.0
                    else:
                        if one and gap == 0.0:
                            break
                        ss, dd = -1.0, -1.0
                    fa = dd * _accel(rest_at, 0.0, ss, ga, prm)
                    fb = dd * _accel(rest_at, 0.0, ss, ga1, prm)
                    if fa > 0.0:
                        tc = tau
                    elif fb > 0.0:
                        tc = tau + (h - tau) * fa / (fa - fb)
                    else:
                        continue
                    if tc < t_on:
                        t_on, s_on = tc, ss
                if s_on == 0.0 or hold:
                    break
                resting = False
                s = s_on
                x, v = rest_at, 0.0
                peak = abs(x)
                tau = t_on
                continue
            # one substep (or the rest of it) from tau
            tb = h if nsub == 1 else min(h, (math.floor(tau / hs + 1e-9) + 1.0) * hs)
            u = tb - tau
            if u <= 1e-14 * h:
                tau = tb
                continue
            gb = ga0 + (ga1 - ga0) * (tb * ih)
            x1, v1 = _advance(x, v, s, ga, gb, u, prm, l1, l2, zp, h, Fh)
            ev = _outside(x1, s, prm, ov)
            toward_edge = s * v < 0.0 or (one and s < 0.0)
            if ev == 0 and v * v1 < 0.0 and (want_peaks or toward_edge):
                # thetadot changes sign inside the step: the turning point is a
                # peak, or (moving towards an edge) may lie past the edge, an
                # impact that both step ends miss
                tm, xm, vm = _locate(x, v, s, ga, gb, u, prm, l1, l2, zp, h, Fh, ov, False, 0.0, v, v1)
                if toward_edge and _outside(xm, s, prm, ov) != 0:
                    gb = ga + (gb - ga) * tm / u
                    u, x1, v1 = tm, xm, vm
                    ev = _outside(x1, s, prm, ov)
                else:
                    peak = max(peak, abs(xm))
            if ev == 0:
                x, v = x1, v1
                peak = max(peak, abs(x))
                tau = tb
                continue
            # event: the exit from the hinge's range
            if ev == 3:
                target = ov if x1 > 0 else -ov
            elif ev == 2:
                target = -gap
            else:
                target = 0.0
            tn, xm, vm = _locate(x, v, s, ga, gb, u, prm, l1, l2, zp, h, Fh, ov, True, target, x - target, x1 - target)
            ev = _outside(xm, s, prm, ov)
            if ev == 0:
                ev = _outside(x1, s, prm, ov)
            tau = tau + tn
            if ev == 3:
                a_s = prm[_P_APOS] if s > 0 else prm[_P_ANEG]
                max_ratio = max(max_ratio, ov / a_s)
                return True, t0 + tau, max_ratio, n_imp
            if ev == 2:
                e = _coefficient(law, 2, vm, prm)
                x = -gap
            else:
                e = _coefficient(law, 0 if s > 0 else 1, vm, prm)
                x = 0.0
            peak = max(peak, abs(xm))
            a_s = prm[_P_APOS] if s > 0 else prm[_P_ANEG]
            max_ratio = max(max_ratio, peak / a_s)
            v_after = e * vm
            if n_imp < max_log:
                log_t[n_imp] = t0 + tau
                log_vb[n_imp] = vm
                log_va[n_imp] = v_after
                log_peak[n_imp] = peak
            n_imp += 1
            peak = 0.0
            wrong_way = (one and gap == 0.0 and v_after <= 0.0) or (ev == 2 and v_after <= 0.0)
            if abs(v_after) < prm[_P_VREST] or wrong_way:
                # a landing slower than rest (ground held at the onset
                # threshold) would lift again at once, endlessly: the wall
                # stays down to the end of the step, then the onset is tested
                hold = abs(vm) < prm[_P_VREST]
                resting = True
                rest_at = x
                v = 0.0
            else:
                v = v_after
                if ev == 1:
                    s = 1.0 if v_after > 0.0 else -1.0
    a_s = prm[_P_APOS] if s > 0 else prm[_P_ANEG]
    max_ratio = max(max_ratio, peak / a_s)
    return False, math.nan, max_ratio, n_imp


# The batch kernel lives beside run_history: numba's on-disk cache is per
# file and does not see changes in the functions a cached kernel calls.


@numba.njit(cache=True)
def _row(ag, h, scale, n_tail, prm, law, x0, v0, logs, out, i):
    # called from the prange body instead of run_history itself: inlined into
    # the parallel loop, run_history runs 4-8x slower (measured, numba 0.68)
    o, t, m, k = run_history(ag, h[i], scale[i], n_tail[i], prm[i], law[i], x0[i], v0[i], logs[0, i], logs[1, i],
                             logs[2, i], logs[3, i])
    out[0][i], out[1][i], out[2][i], out[3][i] = o, t, m, k


@numba.njit(parallel=True, cache=True)
def batch_kernel(ag, h, scale, n_tail, prm, law, x0, v0, max_log):
    """:func:`run_history` of every row (history) in parallel; the Python
    front ends are in :mod:`rocklab.batch`."""
    n = h.shape[0]
    over = np.zeros(n, np.bool_)
    t_over = np.full(n, np.nan)
    max_ratio = np.zeros(n)
    n_imp = np.zeros(n, np.int64)
    logs = np.full((4, n, max_log), np.nan)
    out = (over, t_over, max_ratio, n_imp)
    for i in numba.prange(n):
        _row(ag, h, scale, n_tail, prm, law, x0, v0, logs, out, i)
    return over, t_over, max_ratio, n_imp, logs[0], logs[1], logs[2], logs[3]
