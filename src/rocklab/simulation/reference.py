"""Event-driven reference integrator of :mod:`rocklab.simulation.rocking_model` (scipy's solve_ivp).

Converged to the tolerances given, slow: the yardstick of the numba engine
(:mod:`rocklab.simulation.engine`) and the simulator of the impact laws the
engine does not accept (:class:`rocklab.physics.impact.Custom`, nested
amplitude laws: no flat form, :meth:`rocklab.simulation.rocking_model.RockingModel.numba_law`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import cast

import numpy as np
import numpy.typing as npt
import pandas as pd

from rocklab._imports import lazy_module
from rocklab.physics import impact as _impact
from rocklab.physics.flight import FloatArray, Floats
from rocklab.simulation.engine import TURNED
from rocklab.simulation.rocking_model import OVERTURN, REST_TOL, RockingHistory, RockingModel, record_times

integrate = lazy_module("scipy.integrate")
optimize = lazy_module("scipy.optimize")


class _Record:
    """Linearly interpolated ground acceleration, zero after the last sample."""

    def __init__(self, ag: npt.ArrayLike | None, dt: float) -> None:
        if ag is None:
            self.t = np.array([0.0, 1.0])
            self.a = np.zeros(2)
        else:
            a = np.asarray(ag, float)
            self.a = np.append(a, 0.0)
            self.t = np.arange(len(self.a)) * float(dt)
        self.free = ag is None

    def __call__(self, t: Floats) -> Floats:
        return np.interp(t, self.t, self.a, left=self.a[0], right=0.0)

    def piece(self, t: float, t_hard: float) -> tuple[float, float, float, float]:
        """End of the straight piece of the record holding ``t`` (capped at
        ``t_hard``) and the piece as ag(tt) = a0 + slope (tt - t0)."""
        # a piece shorter than rounding (an onset found at a sample up to an
        # ulp) is merged into the next: solve_ivp cannot step over it
        k = int(np.searchsorted(self.t, t + 1e-12 * max(1.0, abs(t)), side="right"))
        if self.free or k >= len(self.t):
            return t_hard, 0.0, 0.0, t
        t0, t1 = self.t[k - 1], self.t[k]
        return min(t1, t_hard), self.a[k - 1], (self.a[k] - self.a[k - 1]) / (t1 - t0), t0


def _onset(
    model: RockingModel, rec: _Record, t0: float, t_stop: float, theta_rest: float, held: int | None = None
) -> tuple[float | None, int | None, int | None]:
    """First instant >= t0, side and direction in which a wall at rest starts rocking.

    The acceleration at rest is affine in ag, so the onset instant is the
    linear interpolation of its zero between record samples.  ``held``:
    the hinge of a wall held off the edge where a term in flight that jumps
    at a turn stopped it (either way on it); such a term acts against the
    direction each candidate tries (``model.jumps``).
    """
    if held is not None:
        candidates = [(held, +1), (held, -1)]
    elif theta_rest < 0:
        candidates = [(-1, +1)]
    else:
        candidates = [(+1, +1)] + ([(-1, -1)] if (not model.one_sided or model.gap > 0) else [])
    tk = rec.t[(rec.t > t0) & (rec.t < t_stop)]
    ts = np.concatenate([[t0], tk, [t_stop]])
    ag = rec(ts)
    best: tuple[float | None, int | None, int | None] = (None, None, None)
    for side, direction in candidates:
        f = direction * model.acceleration(theta_rest, direction * TURNED if model.jumps else 0.0, side, ag)
        pos = np.flatnonzero(f > 0)
        if pos.size == 0:
            continue
        k = pos[0]
        if k == 0:
            t_on = t0
        else:
            t_on = ts[k - 1] + (ts[k] - ts[k - 1]) * f[k - 1] / (f[k - 1] - f[k])
        if best[0] is None or t_on < best[0]:
            best = (t_on, side, direction)
    return best


def _missed_edge(dense: Callable[[Floats], FloatArray], t0: float, t1: float, s: float) -> float:
    """First instant in (t0, t1] at which the wall on hinge ``s`` is past its
    edge (s theta < 0), from the dense output of one segment.

    The grid is geometric from t0: the wall may leave the edge (an impact at
    t0) and cross it back long before t1.
    """
    tt = t0 + (t1 - t0) * np.concatenate([[0.0], np.geomspace(1e-9, 1.0, 256)])
    f = s * dense(tt)[0]
    k = int(np.flatnonzero(f < 0.0)[0])
    return cast(
        float, optimize.brentq(lambda u: s * dense(u)[0], tt[k - 1], tt[k], xtol=1e-15, rtol=4 * np.finfo(float).eps)
    )


def _never(tt: float, y: FloatArray) -> float:
    """An event function that never changes sign (an event not searched for)."""
    return 1.0


def _reference(
    model: RockingModel,
    rec: _Record,
    theta0: float,
    thetadot0: float,
    t_end: float,
    fs: float,
    overturn: float,
    rest_tol: float,
    rtol: float,
    atol: float,
    max_step: float,
    tail: float,
    apexes: bool = True,
) -> RockingHistory:
    v_rest = rest_tol * model.thetadot_r
    law_base, law_tr = model.base_law, model.transverse_law
    # a law of the impact speed on the excursions through a gap, and the landing speed that started one
    excursion = _impact.speed_law(law_base, -1)
    excursion = excursion if excursion is not None and excursion.excursion else None
    v_entry = 0.0
    t_out = record_times(t_end, fs)
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
    if model.hinge_rounding and not rec.free:
        raise ValueError(
            "a rocking angle that depends on the amplitude (hinge_rounding) is defined flight by flight in "
            "free rocking: under ground motion a flight's apex is not known when it starts"
        )
    # under ground motion a term that jumps at a turn may hold the wall where it turns (the ground
    # pushing it less than the term resists): each turn ends a segment, and the wall moves on the
    # other way or is held there (held: its hinge) until the ground moves it, as the engine does
    stick, held = model.jumps and not rec.free, None

    def moves(th: float, d: float, s: float, t: float) -> bool:
        """Whether the wall at th, at rest on hinge s at t, moves in the direction d (+1 / -1)."""
        return float(model.acceleration(th, d * TURNED, s, rec(t))) * d > 0.0

    # a wall released from rest where a term that jumps at a turn outweighs the restoring moment (dry
    # friction near its apex, sin(alpha - |theta0|) <= mu) is held there, in free rocking too: integrated,
    # it chatters at the release for ever
    if model.jumps and thd == 0.0 and not resting:
        d = math.copysign(1.0, float(model.acceleration(th, 0.0, side, rec(0.0))))
        if not moves(th, d, side, 0.0):
            resting, rest_at, held, t_rest = True, th, side, 0.0
        elif stick:
            thd = d * TURNED

    def fill(ta: float, tb: float, sol: Callable[[FloatArray], FloatArray] | None = None, value: float = 0.0) -> None:
        # the samples ta <= t <= tb of the ascending grid, found by bisection: a comparison of the
        # whole grid at every segment grew with the record's length times its flights
        sel = slice(int(np.searchsorted(t_out, ta, "left")), int(np.searchsorted(t_out, tb, "right")))
        if sol is None:
            theta_out[sel], thetadot_out[sel] = value, 0.0
        elif sel.stop > sel.start:
            y = sol(t_out[sel])
            theta_out[sel], thetadot_out[sel] = y[0], y[1]

    while t < t_hard:
        if t >= t_end:
            # beyond the instability angle of its hinge the wall is on the
            # falling side of the potential maximum: it falls or climbs back,
            # and only the integration tells which
            below = abs(th) < model.alpha_side(side)
            if resting or (
                below and all(model.energy(th, thd, side) < model.critical_energy(s) for s in model.reachable_sides())
            ):
                break
        if resting:
            t_stop = t_end
            t_on, s_on, d_on = _onset(model, rec, t, t_stop, rest_at, held)
            if t_on is None:
                fill(t, t_end, value=rest_at)
                break
            fill(t, t_on, value=rest_at)
            # an onset found: its side and direction are not None
            t, th, thd, side, resting, t_rest = (
                t_on,
                rest_at,
                (cast(int, d_on) * TURNED if stick else 0.0),
                cast(int, s_on),
                False,
                None,
            )
            held = None
        s = side
        # one straight piece of the record at a time: the solution is smooth
        # inside it, so the error control never meets the record's kinks
        t_seg, a0, slope, tk = rec.piece(t, t_hard)
        rhs = model.flight_model(th, thd, s).equation_of_motion(s, a0, slope, tk)

        # a segment that starts on the edge (after an impact, or at an onset)
        # must not find that edge again at its first instant: when the first
        # step spans the whole excursion, the root search would otherwise
        # return the start and log a chain of impacts at one instant
        def ev_base(tt: float, y: FloatArray, t0: float = t, s: float = s) -> float:
            return y[0] if tt > t0 else float(s)

        # solve_ivp reads an event's terminal and direction from attributes of the function
        ev_base.terminal, ev_base.direction = True, -float(s)  # type: ignore[attr-defined]

        def ev_over(tt: float, y: FloatArray) -> float:
            return cast(float, abs(y[0]) - overturn)

        ev_over.terminal, ev_over.direction = True, 1.0  # type: ignore[attr-defined]

        # a terminal peak must not find the turn a segment starts from (stick: the speed is TURNED)
        def ev_peak(tt: float, y: FloatArray, t0: float = t, start: float = thd or float(s)) -> float:
            return y[1] if not stick or tt > t0 else start

        ev_peak.terminal = stick  # type: ignore[attr-defined]
        # the apexes only for the impacts' table: without it, an event never active (no root to search)
        # keeps the events' places
        located = stick or apexes
        peak_event = ev_peak if located else _never

        # a wall moving towards its edge that turns back: if it turns past the
        # edge, it crossed the edge and came back inside one solver step (a
        # small excursion under ground motion), an impact that the sign test
        # of ev_base misses (not at the segment's start: an onset or a turn)
        def ev_turn(tt: float, y: FloatArray, t0: float = t, s: float = s) -> float:
            return y[1] if tt > t0 else float(s)

        ev_turn.terminal, ev_turn.direction = True, float(s)  # type: ignore[attr-defined]

        events = [ev_base, ev_over, peak_event, ev_turn]
        if model.one_sided and model.gap > 0 and s < 0:

            def ev_tr(tt: float, y: FloatArray, t0: float = t) -> float:
                return y[0] + model.gap if tt > t0 else 1.0

            ev_tr.terminal, ev_tr.direction = True, -1.0  # type: ignore[attr-defined]
            events.append(ev_tr)
            # the excursion in the gap can be far shorter than a free step
            seg_step = min(max_step, 0.05 * math.sqrt(2.0 * model.gap / (model.p**2 * model.alpha_minus)))
        else:
            seg_step = max_step
        sol = integrate.solve_ivp(
            rhs,
            (t, t_seg),
            [th, thd],
            method="DOP853",
            rtol=rtol,
            atol=atol,
            max_step=seg_step,
            events=events,
            dense_output=True,
        )
        if sol.status == -1:
            raise RuntimeError(f"solve_ivp failed at t = {t:.6g} s: {sol.message}")
        t_new, v_before = sol.t[-1], sol.y[1, -1]
        turned = sol.status == 1 and sol.t_events[3].size > 0
        if turned and s * sol.y[0, -1] < 0.0:
            t_new = _missed_edge(sol.sol, t, t_new, s)
            v_before = float(sol.sol(t_new)[1])
        fill(t, min(t_new, t_end), sol.sol)
        peaks = [abs(th), abs(sol.y[0, -1])] + [abs(y[0]) for y in sol.y_events[2]]
        edge = sol.t_events[0].size or sol.t_events[1].size or (len(events) == 5 and sol.t_events[4].size)
        if stick and sol.status == 1 and sol.t_events[2].size and not edge and not (turned and s * sol.y[0, -1] < 0):
            # a turn: the other way, unless the term holds the wall there
            d = -math.copysign(1.0, float(sol.sol(0.5 * (t + t_new))[1]))
            t, th = t_new, float(sol.y[0, -1])
            if moves(th, d, s, t):
                thd = d * TURNED
            else:
                resting, rest_at, held, thd, t_rest = True, th, s, 0.0, t
            continue
        if sol.status != 1 or (turned and s * sol.y[0, -1] >= 0.0):
            # the end of the piece, or a turn short of the edge
            t, th, thd = t_new, sol.y[0, -1], sol.y[1, -1]
            continue
        if sol.t_events[1].size:
            overturned, t_ov = True, float(sol.t_events[1][0])
            break
        transverse = len(events) == 5 and sol.t_events[4].size > 0
        t = t_new
        if transverse:
            e = float(law_tr.coefficient(v_before, -1, model.alpha, model.p))
            th = -model.gap
        else:
            e = float(law_base.coefficient(v_before, s, model.alpha, model.p))
            th = 0.0
            if model.one_sided and model.gap > 0:
                # a law of the impact speed acts on the excursion through the gap as a whole, on the
                # speed of the landing that started it (wall_model.impact_speeds)
                if s > 0:
                    v_entry = abs(v_before)
                elif excursion is not None and v_entry > 0:
                    e *= float(excursion.factor(e * v_before / v_entry, v_entry, model.alpha, model.p))
                    v_entry = 0.0
        thd = e * v_before
        rows.append((t, "transverse" if transverse else "base", v_before, thd, max(peaks) if located else math.nan))
        wrong_way = (model.one_sided and model.gap == 0 and thd <= 0) or (transverse and thd <= 0)
        if abs(thd) < v_rest or wrong_way:
            resting, rest_at, thd, t_rest = True, th, 0.0, t
            held, v_entry = None, 0.0
        elif not transverse:
            side = 1 if thd > 0 else -1
    if resting and t < t_end:
        fill(t, t_end, value=rest_at)
    impacts = pd.DataFrame(rows, columns=["t", "kind", "thetadot_before", "thetadot_after", "theta_peak_before"])
    return RockingHistory(t_out, theta_out, thetadot_out, impacts, overturned, t_ov, t_rest, model)


def simulate_free(
    model: RockingModel,
    theta0: float,
    thetadot0: float = 0.0,
    t_end: float = 30.0,
    fs: float = 400.0,
    *,
    overturn: float = OVERTURN,
    rest_tol: float = REST_TOL,
    rtol: float = 1e-12,
    atol: float = 1e-14,
    apexes: bool = True,
) -> RockingHistory:
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
    apexes : bool
        Locate each flight's apex for the impacts' ``theta_peak_before``; False: NaN there, and a
        root search less per flight (the motion is the same to the last bit), for a caller that reads
        the record only.

    Returns
    -------
    RockingHistory
    """
    return _reference(
        model, _Record(None, 1.0), theta0, thetadot0, t_end, fs, overturn, rest_tol, rtol, atol, np.inf, 0.0, apexes
    )


def simulate_ground(
    model: RockingModel,
    ag: npt.ArrayLike,
    dt: float,
    t_end: float | None = None,
    fs: float | None = None,
    overturn: float = OVERTURN,
    *,
    theta0: float = 0.0,
    thetadot0: float = 0.0,
    rest_tol: float = REST_TOL,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    tail: float = 120.0,
) -> RockingHistory:
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
