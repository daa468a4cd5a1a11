"""Numba event-driven engine: one rocking history, the record stepped sample by sample.

Same conventions as :mod:`rocklab.simulation.rocking_model` (onset, impacts, rest,
overturning); :mod:`rocklab.simulation.batch` runs many histories over the
cores.  The linear form is advanced in closed form per record interval (a
state-transition matrix), the exact form by RK4 substeps.

A wall is a parameter vector laid out by name (:data:`LAYOUT`, :func:`slot`)
and the laws of its impacts.  Between impacts the engine integrates the
viscous loss itself (slot ``zeta``: the linear form's closed form holds
it); any other term in flight (:class:`rocklab.physics.law.FlightTerm`:
dry friction, drag, the term of a law of a cause) is its declared
deceleration, compiled into one function of the state
(:func:`rocklab.simulation.flight_terms.flight_function`) with its
parameters in the vector's ``flight_*`` slots, in the exact form only.

Size: one compiled engine, the kernel and every function it calls: numba's
on-disk cache is per file and does not see a change in a function of another
file that a cached kernel calls; every function with its types.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TypeAlias

import numba
import numpy as np
import numpy.typing as npt
from numba.np.unsafe.ndarray import to_fixed_tuple

from rocklab.physics import flight
from rocklab.physics.flight import FloatArray
from rocklab.physics.law import speed_factor_at

#: The parameter vector of one wall as the helpers take it, a tuple (:func:`run_history`).
Params: TypeAlias = tuple[float, ...]
#: The function of a wall's terms in flight (:data:`rocklab.simulation.flight_terms.FLIGHT_TYPE`).
FlightFunction: TypeAlias = Callable[[float, float, Params], float]
#: :func:`_transition` over one step, a 2 x 2 matrix by rows.
Transition: TypeAlias = tuple[float, float, float, float]

#: Parameters of the terms in flight beyond the viscous loss that one wall may have.
FLIGHT_SLOTS = tuple(f"flight_{j}" for j in range(6))
#: The parameter vector (:meth:`rocklab.simulation.rocking_model.RockingModel.numba_params`), by name:
#: rocking angles of hinges +1 and -1 [rad], p [rad/s], zeta [-], gap [rad], one-sided and linear
#: form (1 or 0), overturning rotation [rad], rest and overturning speed (Eq. 16) [rad/s], g [m/s^2],
#: RK4 substeps per interval, whether the wall has terms in flight beyond the viscous loss and whether
#: one jumps at a turn (1 or 0, :attr:`rocklab.physics.law.FlightTerm.smooth`), their parameters.
LAYOUT = (
    "alpha_pos",
    "alpha_neg",
    "p",
    "zeta",
    "gap",
    "one_sided",
    "linear",
    "overturn",
    "v_rest",
    "g",
    "substeps",
    "v_r",
    "terms",
    "turns",
    *FLIGHT_SLOTS,
)
# the kernels' names of the slots, in the order of LAYOUT
_P_APOS, _P_ANEG, _P_P, _P_ZETA, _P_GAP, _P_ONE, _P_LIN, _P_OV, _P_VREST, _P_G, _P_SUB, _P_VR, _P_TERMS, _P_TURNS = (
    range(14)
)
_N_P = len(LAYOUT)
#: The speed a wall leaves a turn or its rest with, in the direction it moves [rad/s]: 0 to the last
#: bit of every sum, but a sign a term that jumps at the turn reads (its first RK4 stage).
TURNED = 1e-300
#: The column of an impact law's row (:meth:`rocklab.simulation.rocking_model.RockingModel.numba_law`) that
#: says whether it has a law of the impact speed (:class:`rocklab.physics.impact.SpeedLaw`), its values at
#: :data:`rocklab.physics.law.KNOTS` in the columns after it: none (0, or a row without the column), on each
#: impact, or on an excursion through a gap as a whole, read at its return.
_L_SPEED = 4
SPEED_EACH, SPEED_EXCURSION = 1.0, 2.0
#: Samples of a record per block of :func:`_block_range`.
_BLOCK = 16


def slot(name: str) -> int:
    """Index of parameter ``name`` in the engine's parameter vector (:data:`LAYOUT`)."""
    return LAYOUT.index(name)


@numba.njit(cache=True, inline="always")
def _accel(x: float, v: float, s: float, ag: float, prm: Params, terms: FlightFunction, d: float) -> float:
    """thetaddot [rad/s^2] at (x, v) on hinge s under ag [m/s^2]; the terms in flight (``terms``) see
    the rotation on hinge s, its mirror past the edge, and where ``d`` is not 0 the wall moving that
    way: each continued smoothly past the jump it makes at the edge or at a turn, for the steps that
    locate them."""
    a = s * (prm[_P_APOS] if s > 0 else prm[_P_ANEG])
    p2 = prm[_P_P] ** 2
    damp = 2.0 * prm[_P_ZETA] * prm[_P_P] * v
    if prm[_P_LIN] > 0:
        acc = p2 * (x - a - ag / prm[_P_G]) - damp
    else:
        acc = -p2 * (math.sin(a - x) + ag / prm[_P_G] * math.cos(a - x)) - damp
    if prm[_P_TERMS] > 0:
        acc = acc - terms(s * abs(x), v if d == 0.0 or v * d > 0.0 else math.copysign(TURNED, d), prm)
    return acc


@numba.njit(cache=True, inline="always")
def _transition(l1: float, l2: float, E1: float, E2: float) -> Transition:
    """State-transition matrix of y'' + 2 zeta p y' - p^2 y = 0 over a time u,
    from E1, E2 = exp(l1 u), exp(l2 u), the roots l1, l2 of
    l^2 + 2 zeta p l - p^2 (cosh/sinh for zeta = 0)."""
    d = l1 - l2
    return ((l1 * E2 - l2 * E1) / d, (E1 - E2) / d, l1 * l2 * (E2 - E1) / d, (l1 * E1 - l2 * E2) / d)


@numba.njit(cache=True, inline="always")
def _linear_state(
    x0: float, v0: float, c0: float, c1: float, u: float, zp: float, F: Transition
) -> tuple[float, float]:
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
def _rk4(
    x: float, v: float, s: float, ga: float, gb: float, u: float, prm: Params, terms: FlightFunction, d: float
) -> tuple[float, float]:
    """One RK4 step of length u, ground acceleration linear from ga to gb (``d``: :func:`_accel`)."""
    gm = 0.5 * (ga + gb)
    k1x, k1v = v, _accel(x, v, s, ga, prm, terms, d)
    k2x, k2v = v + 0.5 * u * k1v, _accel(x + 0.5 * u * k1x, v + 0.5 * u * k1v, s, gm, prm, terms, d)
    k3x, k3v = v + 0.5 * u * k2v, _accel(x + 0.5 * u * k2x, v + 0.5 * u * k2v, s, gm, prm, terms, d)
    k4x, k4v = v + u * k3v, _accel(x + u * k3x, v + u * k3v, s, gb, prm, terms, d)
    return (x + u / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x), v + u / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v))


@numba.njit(cache=True, inline="always")
def _advance(
    x: float,
    v: float,
    s: float,
    ga: float,
    gb: float,
    u: float,
    prm: Params,
    terms: FlightFunction,
    d: float,
    l1: float,
    l2: float,
    zp: float,
    h: float,
    Fh: Transition,
) -> tuple[float, float]:
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
    return _rk4(x, v, s, ga, gb, u, prm, terms, d)


@numba.njit(cache=True)
def _bounded(e: float, f: float) -> float:
    """The factor f on the signed e ``e`` clipped to [0, 1/|e|] (:func:`rocklab.physics.impact.bounded_factor`)."""
    if f < 0.0:
        f = 0.0
    if e != 0.0 and f > 1.0 / abs(e):
        f = 1.0 / abs(e)
    return f


@numba.njit(cache=True)
def _coefficient(law: FloatArray, row: int, v: float, prm: Params) -> float:
    """Signed e of law row ``row`` (e0, a, b, v_stick, and a law of the impact speed) for a landing at v [rad/s].

    ``E clip(a - b (v/thetadot_r)^2, 0, 1/|E|)`` with E = e0 clipped to
    [-1, 1] (:func:`rocklab.physics.impact.bounded_factor`: a scale, a
    constant or a per-history e_scale beyond 1/|e| never makes an impact
    create energy, as in :class:`rocklab.physics.impact.Scaled`;
    :func:`rocklab.physics.impact.amplitude_factor`), and 0 for a landing
    slower than v_stick thetadot_r (:class:`rocklab.physics.impact.Sticking`).
    A row with a law of the impact speed on each impact (fifth column 1,
    :class:`rocklab.physics.impact.SpeedLaw`) multiplies that e by its factor
    g(v / thetadot_r) within the same bounds.
    """
    # the law's entries are floats (an array's items read as Any)
    e0: float
    a: float
    b: float
    e0, a, b = law[row, 0], law[row, 1], law[row, 2]
    if abs(v) < law[row, 3] * prm[_P_VR]:
        return 0.0
    if e0 > 1.0:
        e0 = 1.0
    elif e0 < -1.0:
        e0 = -1.0
    e = e0
    if not (a == 1.0 and b == 0.0):
        r = abs(v) / prm[_P_VR]
        e = e0 * _bounded(e0, a - b * r * r)
    if law.shape[1] > _L_SPEED and law[row, _L_SPEED] == SPEED_EACH:
        e = e * _bounded(e, _speed_factor(abs(v) / prm[_P_VR], law[row, _L_SPEED + 1 :]))
    return e


@numba.njit(cache=True)
def _excursion_factor(law: FloatArray, v_out: float, v_entry: float, prm: Params) -> float:
    """The factor of a law of the impact speed on an excursion through a gap as a whole (row base -1,
    fifth column :data:`SPEED_EXCURSION`; :class:`rocklab.physics.impact.SpeedLaw`): g(v / thetadot_r)
    of the landing speed v = ``v_entry`` [rad/s] that started it, within the bounds of the excursion's
    ratio v_out / v, v_out [rad/s] the speed the wall leaves the base with at its return; 1 without one
    (or without an entry: a wall that came into the gap from rest)."""
    if law.shape[1] <= _L_SPEED or law[1, _L_SPEED] != SPEED_EXCURSION or not v_entry > 0.0:
        return 1.0
    return _bounded(abs(v_out) / v_entry, _speed_factor(v_entry / prm[_P_VR], law[1, _L_SPEED + 1 :]))


# the one definition of a law of the impact speed and of the block's energy, compiled for the engine
_speed_factor = numba.njit(cache=True, inline="always")(speed_factor_at)
_potential = numba.njit(cache=True, inline="always")(flight.potential)
_potential_linear = numba.njit(cache=True, inline="always")(flight.potential_linear)


@numba.njit(cache=True)
def _can_overturn(x: float, v: float, s: float, prm: Params) -> bool:
    """Whether a wall in free motion at (x [rad], v [rad/s]) on hinge s may still overturn.

    Below the instability angle of its hinge it may only if its energy
    reaches the critical energy of a reachable hinge.  Beyond it, the wall is
    on the falling side of the potential maximum: with less energy it cannot
    climb back and falls, with more it crosses back, so it is always followed.
    """
    p = prm[_P_P]
    a = prm[_P_APOS] if s > 0 else prm[_P_ANEG]
    th = abs(x)
    if th >= a:
        return True
    # energies of floats (the compiled potential reads as Any)
    en: float
    crit: float
    if prm[_P_LIN] > 0:
        en = 0.5 * v * v + _potential_linear(th, a, p)
        crit = _potential_linear(prm[_P_APOS], prm[_P_APOS], p)
        if prm[_P_ONE] == 0:
            crit = min(crit, _potential_linear(prm[_P_ANEG], prm[_P_ANEG], p))
    else:
        en = 0.5 * v * v + _potential(th, a, p)
        crit = _potential(prm[_P_APOS], prm[_P_APOS], p)
        if prm[_P_ONE] == 0:
            crit = min(crit, _potential(prm[_P_ANEG], prm[_P_ANEG], p))
    return en >= crit


@numba.njit(cache=True)
def _outside(x: float, s: float, prm: Params, ov: float) -> int:
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


@numba.njit(cache=True, inline="always")
def _lifts(a: float, A0p: float, A1p: float, two: bool, A0n: float, A1n: float) -> bool:
    """Whether the ground acceleration ``a`` [m/s^2] starts a wall at rest.

    The acceleration at rest is affine in ``a``, ``A0 + A1 a``: the wall
    lifts onto the positive hinge when it is positive, onto the negative
    one (if ``two`` hinges may start) when it is negative.
    """
    return A0p + A1p * a > 0.0 or (two and A0n + A1n * a < 0.0)


@numba.njit(cache=True)
def _block_range(ag: FloatArray) -> FloatArray:
    """Smallest and largest sample of each block of ``_BLOCK`` samples of ``ag``, shape (2, n_blocks).

    NaN samples are left out: they never start a wall at rest (:func:`_lifts`
    is false for them), so the range of a block need not cover them.
    """
    n_blocks = (ag.shape[0] + _BLOCK - 1) // _BLOCK
    out = np.empty((2, n_blocks))
    for b in range(n_blocks):
        lo, hi = np.inf, -np.inf
        for a in ag[b * _BLOCK : (b + 1) * _BLOCK]:
            lo = min(lo, a)
            hi = max(hi, a)
        out[0, b], out[1, b] = lo, hi
    return out


@numba.njit(cache=True)
def _locate(
    x: float,
    v: float,
    s: float,
    ga: float,
    gb: float,
    u: float,
    prm: Params,
    terms: FlightFunction,
    l1: float,
    l2: float,
    zp: float,
    h: float,
    Fh: Transition,
    ov: float,
    edge: bool,
    target: float,
    f0: float,
    f1: float,
) -> tuple[float, float, float]:
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
    # a term that jumps at a turn: the trials see the motion as it starts (_accel), also past the turn
    hold = math.copysign(1.0, v) if prm[_P_TURNS] > 0 else 0.0
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
        xm, vm = _advance(x, v, s, ga, gm, tm, prm, terms, hold, l1, l2, zp, h, Fh)
        if edge:
            f, df, inside = xm - target, vm, _outside(xm, s, prm, ov) == 0
        else:
            f, df, inside = vm, _accel(xm, vm, s, gm, prm, terms, hold), vm * v > 0.0
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
def run_history(
    ag: FloatArray,
    ag_range: FloatArray,
    h: float,
    scale: float,
    n_tail: int,
    to_rest: bool,
    params: FloatArray,
    law: FloatArray,
    terms: FlightFunction,
    x: float,
    v: float,
    log_t: FloatArray,
    log_vb: FloatArray,
    log_va: FloatArray,
    log_peak: FloatArray,
    record: FloatArray,
) -> tuple[bool, float, float, int]:
    """Event-driven integration of one wall, sample interval by sample interval.

    ``ag`` [m/s^2] (times ``scale``) is stepped with interval ``h`` [s] (the
    record's dt times a duration scale; ``ag_range`` is its
    :func:`_block_range`), then up to ``n_tail`` free steps
    follow: until the wall rests if ``to_rest``, otherwise only while it can
    still overturn (enough to decide overturning).  Linear form: exact closed form per
    interval; exact form: ``params[_P_SUB]`` RK4 substeps per interval.  Events
    (impact, overturning, onset, velocity zero for the peaks) are located by
    bisection inside the step.  Impacts are logged into the ``log_*`` arrays
    up to their length, and theta [rad] at the ends of the steps into ``record``
    up to its length (``record[k]`` at k h, the release at 0; a wall that
    overturns leaves the rest unwritten).

    Peaks inside a step (zeros of thetadot) are located only when impacts
    are logged; otherwise max |theta| is sampled at the step ends.  A term
    in flight that jumps where thetadot changes sign (``params`` slot
    ``turns``; ``terms`` the function of the wall's terms,
    :func:`rocklab.simulation.flight_terms.flight_function`) has every turn located and a new step started
    there, and the release and every onset start in the direction the wall
    moves: RK4 over the jump would be of first order.

    Returns
    -------
    overturned : bool, t_overturn : float (nan), max |theta|/alpha_s : float,
    number of impacts : int
    """
    # the helpers take the parameters as a tuple: every call that passes an
    # array costs two atomic reference counts, in the record loop and in
    # each trial of _locate
    # numba's stub of the intrinsic names its typing context too, which numba passes itself
    prm: Params = to_fixed_tuple(params, _N_P)  # type: ignore[call-arg]
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
    # the landing speed that started an excursion through the gap (0: none)
    v_entry = 0.0
    nsub = 1 if prm[_P_LIN] > 0 else max(1, int(prm[_P_SUB]))
    hs = h / nsub
    # the linear form's full record intervals in free motion, without the
    # general step's bookkeeping (the same operations in the same order, so
    # the same numbers): most of a map's time is spent in them
    fast = prm[_P_LIN] > 0
    ig = 1.0 / prm[_P_G]
    igh = ig / h
    hih = h * ih
    resting = x == 0.0 and v == 0.0
    hold = False
    rest_at = 0.0
    s = 1.0 if (x > 0.0 or (x == 0.0 and v >= 0.0)) else -1.0
    turns = prm[_P_TURNS] > 0
    # held where a term that jumps at a turn stops it, off the edge: a rest on hinge s at rest_at
    held = False
    # the speed a wall at rest starts with, in the direction it tries (the onset tests): 0, or the
    # direction itself for a term that jumps there
    vt = TURNED if turns else 0.0
    if turns and v == 0.0 and not resting:
        ga = scale * ag[0] if n_rec > 0 else 0.0
        d = math.copysign(1.0, _accel(x, 0.0, s, ga, prm, terms, 0.0))
        v = d * TURNED
        if _accel(x, v, s, ga, prm, terms, 0.0) * d <= 0.0:
            resting, held, rest_at, v = True, True, x, 0.0
    peak = abs(x)
    max_ratio = 0.0
    n_imp = 0
    max_log = log_t.shape[0]
    n_record = record.shape[0]
    if n_record > 0:
        record[0] = x
    k = -1
    while k + 1 < n_steps:
        k += 1
        if k >= n_rec:
            if resting or not (to_rest or _can_overturn(x, v, s, prm)):
                break
        if resting:
            # fast-forward through the samples that cannot start the motion:
            # the acceleration at rest is affine in ag, A0 + A1 ag
            sp, sn = (s, s) if held else (1.0 if rest_at == 0.0 else -1.0, -1.0)
            A0p = _accel(rest_at, vt, sp, 0.0, prm, terms, 0.0)
            A1p = _accel(rest_at, vt, sp, 1.0, prm, terms, 0.0) - A0p
            two = held or (rest_at == 0.0 and not (one and gap == 0.0))
            A0n = _accel(rest_at if held else 0.0, 0.0 - vt, sn, 0.0, prm, terms, 0.0)
            A1n = _accel(rest_at if held else 0.0, 0.0 - vt, sn, 1.0, prm, terms, 0.0) - A0n
            # the step's own first sample too: at k = 0 (or after a hold) no
            # earlier step has tested it, and skipping the step would miss an
            # onset in its first part
            lifts = _lifts(scale * ag[k], A0p, A1p, two, A0n, A1n)
            k_rest = k
            while not lifts and k + 1 < n_rec - 1:
                # a whole block at once where neither its smallest nor its
                # largest sample lifts the wall: the test is monotone in ag,
                # in floating point too (rounding is monotone), so no sample
                # between them does
                b = (k + 1) // _BLOCK
                if (
                    (k + 1) % _BLOCK == 0
                    and k + _BLOCK < n_rec - 1
                    and not _lifts(scale * ag_range[0, b], A0p, A1p, two, A0n, A1n)
                    and not _lifts(scale * ag_range[1, b], A0p, A1p, two, A0n, A1n)
                ):
                    k += _BLOCK
                    continue
                if _lifts(scale * ag[k + 1], A0p, A1p, two, A0n, A1n):
                    break
                k += 1
            # the steps skipped start at rest
            for j in range(k_rest + 1, min(k + 1, n_record)):
                record[j] = rest_at
        elif fast:
            a_s = s * (prm[_P_APOS] if s > 0 else prm[_P_ANEG])
            turns_matter = want_peaks or (one and s < 0.0)
            while k + 1 < n_rec:
                ga0 = scale * ag[k]
                ga1 = scale * ag[k + 1]
                # gb of the general step at tb = h
                gb = ga0 + (ga1 - ga0) * hih
                x1, v1 = _linear_state(x, v, a_s + ga0 * ig, (gb - ga0) * igh, h, zp, Fh)
                # an event in this interval: the general step below takes it
                if _outside(x1, s, prm, ov) != 0 or (v * v1 < 0.0 and (turns_matter or s * v < 0.0)):
                    break
                x, v = x1, v1
                peak = max(peak, abs(x))
                k += 1
                if k < n_record:
                    record[k] = x
        ga0 = scale * ag[k] if k < n_rec else 0.0
        hold = False
        t_lift = -1.0
        ga1 = scale * ag[k + 1] if k + 1 < n_rec else 0.0
        t0 = k * h
        tau = 0.0
        while tau < h:
            ga = ga0 + (ga1 - ga0) * (tau * ih)
            if resting:
                # onset: first zero of the (affine in ag) acceleration at rest
                t_on = h + 1.0
                s_on = d_on = 0.0
                for c in range(2):
                    if held:
                        ss, dd = s, 1.0 - 2.0 * c
                    elif rest_at < 0.0:
                        if c == 1:
                            break
                        ss, dd = -1.0, 1.0
                    elif c == 0:
                        ss, dd = 1.0, 1.0
                    else:
                        if one and gap == 0.0:
                            break
                        ss, dd = -1.0, -1.0
                    vd = dd * vt if turns else 0.0
                    fa = dd * _accel(rest_at, vd, ss, ga, prm, terms, 0.0)
                    fb = dd * _accel(rest_at, vd, ss, ga1, prm, terms, 0.0)
                    if fa > 0.0:
                        tc = tau
                    elif fb > 0.0:
                        tc = tau + (h - tau) * fa / (fa - fb)
                    else:
                        continue
                    if tc < t_on:
                        t_on, s_on, d_on = tc, ss, dd
                if s_on == 0.0 or hold:
                    break
                resting = held = False
                t_lift = t_on
                s = s_on
                x, v = rest_at, (d_on * vt if turns else 0.0)
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
            # a term that jumps at a turn sees the motion as the step starts (from a turn or an onset, at
            # a speed of rounding): a turn inside the step is located, and a new step starts there
            x1, v1 = _advance(
                x, v, s, ga, gb, u, prm, terms, math.copysign(1.0, v) if turns else 0.0, l1, l2, zp, h, Fh
            )
            ev = _outside(x1, s, prm, ov)
            toward_edge = s * v < 0.0 or (one and s < 0.0)
            if v * v1 < 0.0 and ((ev == 0 and (want_peaks or toward_edge)) or turns):
                # thetadot changes sign inside the step: the turning point is a
                # peak, or (moving towards an edge) may lie past the edge, an
                # impact that both step ends miss
                tm, xm, vm = _locate(x, v, s, ga, gb, u, prm, terms, l1, l2, zp, h, Fh, ov, False, 0.0, v, v1)
                if toward_edge and _outside(xm, s, prm, ov) != 0:
                    gb = ga + (gb - ga) * tm / u
                    u, x1, v1 = tm, xm, vm
                    ev = _outside(x1, s, prm, ov)
                elif ev == 0 or _outside(xm, s, prm, ov) == 0:
                    peak = max(peak, abs(xm))
                    if turns:
                        # a term that jumps at the turn: a new step from it, the other way, unless the
                        # term holds the wall there (it would turn back at once, endlessly)
                        tau = tau + tm
                        d = math.copysign(1.0, v1)
                        x, v = xm, d * TURNED
                        gt = ga0 + (ga1 - ga0) * (tau * ih)
                        if _accel(x, v, s, gt, prm, terms, 0.0) * d <= 0.0:
                            resting, held, rest_at, v = True, True, x, 0.0
                        continue
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
            tn, xm, vm = _locate(
                x, v, s, ga, gb, u, prm, terms, l1, l2, zp, h, Fh, ov, True, target, x - target, x1 - target
            )
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
                if one and gap > 0.0:
                    # a law of the impact speed acts on the excursion through the gap as a whole, on the
                    # speed of the landing that started it (wall_model.impact_speeds)
                    if s > 0:
                        v_entry = abs(vm)
                    else:
                        e = e * _excursion_factor(law, e * vm, v_entry, prm)
                        v_entry = 0.0
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
                # a landing slower than rest within rounding of the onset in
                # this step (ground held at the onset threshold) would lift
                # again at once, endlessly: the wall stays down to the end of
                # the step, then the onset is tested.  Any other landing may
                # lift at once, as the reference does: a wall coming back
                # slowly against a ground that turns and pushes it away
                hold = abs(vm) < prm[_P_VREST] and 0.0 <= t_lift and tau - t_lift <= 1e-9 * h
                resting, held = True, False
                rest_at = x
                v = 0.0
                v_entry = 0.0
            else:
                v = v_after
                if ev == 1:
                    s = 1.0 if v_after > 0.0 else -1.0
        # the end of the step (a wall at rest is where it rests)
        if k + 1 < n_record:
            record[k + 1] = x
    a_s = prm[_P_APOS] if s > 0 else prm[_P_ANEG]
    max_ratio = max(max_ratio, peak / a_s)
    return False, math.nan, max_ratio, n_imp


# The batch kernel lives beside run_history: numba's on-disk cache is per
# file and does not see changes in the functions a cached kernel calls.


@numba.njit(cache=True)
def _row(
    ag: FloatArray,
    ag_range: FloatArray,
    h: FloatArray,
    scale: FloatArray,
    n_tail: npt.NDArray[np.int64],
    to_rest: bool,
    prm: FloatArray,
    law: FloatArray,
    terms: FlightFunction,
    x0: FloatArray,
    v0: FloatArray,
    logs: FloatArray,
    out: tuple[npt.NDArray[np.bool_], FloatArray, FloatArray, npt.NDArray[np.int64]],
    i: int,
) -> None:
    # called from the prange body instead of run_history itself: inlined into
    # the parallel loop, run_history runs 4-8x slower (measured, numba 0.68)
    o, t, m, k = run_history(
        ag,
        ag_range,
        h[i],
        scale[i],
        n_tail[i],
        to_rest,
        prm[i],
        law[i],
        terms,
        x0[i],
        v0[i],
        logs[0, i],
        logs[1, i],
        logs[2, i],
        logs[3, i],
        logs[3, i, :0],
    )
    out[0][i], out[1][i], out[2][i], out[3][i] = o, t, m, k


@numba.njit(parallel=True, cache=True)
def batch_kernel(
    ag: FloatArray,
    h: FloatArray,
    scale: FloatArray,
    n_tail: npt.NDArray[np.int64],
    to_rest: bool,
    prm: FloatArray,
    law: FloatArray,
    terms: FlightFunction,
    x0: FloatArray,
    v0: FloatArray,
    max_log: int,
) -> tuple[
    npt.NDArray[np.bool_],
    FloatArray,
    FloatArray,
    npt.NDArray[np.int64],
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
]:
    """:func:`run_history` of every row (history) in parallel, ``terms`` the function of the terms in
    flight of every row (:func:`rocklab.simulation.flight_terms.flight_function`); the Python front ends are in
    :mod:`rocklab.simulation.batch`."""
    n = h.shape[0]
    over = np.zeros(n, np.bool_)
    t_over = np.full(n, np.nan)
    max_ratio = np.zeros(n)
    n_imp = np.zeros(n, np.int64)
    logs = np.full((4, n, max_log), np.nan)
    out = (over, t_over, max_ratio, n_imp)
    ag_range = _block_range(ag)
    for i in numba.prange(n):
        _row(ag, ag_range, h, scale, n_tail, to_rest, prm, law, terms, x0, v0, logs, out, i)
    return over, t_over, max_ratio, n_imp, logs[0], logs[1], logs[2], logs[3]


@numba.njit(cache=True)
def free_record(
    h: float, n: int, prm: FloatArray, law: FloatArray, terms: FlightFunction, x0: float, v0: float
) -> tuple[bool, FloatArray]:
    """:func:`run_history` of one wall rocking freely from ``x0`` [rad], ``v0`` [rad/s] over ``n``
    steps of ``h`` [s]: whether it overturned, and theta [rad] at 0, h, ..., n h (NaN after an overturning)."""
    ag = np.zeros(n)
    record = np.full(n + 1, np.nan)
    none = np.empty(0)
    over, _, _, _ = run_history(
        ag, _block_range(ag), h, 1.0, 0, False, prm, law, terms, x0, v0, none, none, none, none, record
    )
    return over, record
