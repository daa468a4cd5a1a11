"""Closed forms of one flight of a rigid rocking wall (Sect. 1, Fig. 1).

A flight is the free motion between two impacts on one hinge of rocking
angle ``a``: from theta = 0 up to an apex A and back.  Energies are per unit
polar moment I_O (rad^2/s^2); the exact (nonlinear) forms are integrated by
Gauss-Legendre quadrature after a substitution that keeps the integrands
smooth, the work of dry friction and drag is in closed form, the linearised
ones are Housner's (1963) closed forms.  Vectorised over tests and impacts,
computed on the flights only (a stack of tests is padded with NaN), each
Newton solve flight by flight: a fit of the losses in flight evaluates them
on every flight of a series thousands of times, so the quadratures and the
Newton passes are compiled loops over the flights (numba), each flight's
sum over the nodes in the order :func:`numpy.sum` takes (the results are
those of the array forms to the last bit, but where libm's expm1 rounds
otherwise than numpy's: with drag, some 1e-15 apart).  The diagnosis, the
dissipation analysis and the tests of the simulators all take their flights
from here.

Beside the losses of :func:`loss_deceleration` (keywords zeta, mu, kappa),
the closed forms take the terms in flight of other laws as they declare
them (keyword ``terms``: ``(term, values)`` pairs of a
:class:`rocklab.physics.law.FlightTerm` and its parameters), by the work
each declares over the rise and over the fall: exact for a term whose
work does not depend on the speed (a moment), beside dry friction and a
viscous loss; beside drag, first order in it.

Size: the closed forms and the compiled loops they call, in one file:
numba's on-disk cache is per file and does not see a change in a function of
another file that a cached loop calls; every function with its types.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any, TypeAlias

import numba
import numpy as np
import numpy.typing as npt

FloatArray: TypeAlias = npt.NDArray[np.float64]
#: A float or an array_like of floats, broadcast against the other arguments (one value per test or
#: impact), and what such a broadcast returns: Any, as numpy takes and gives back scalars and arrays
#: alike (a float in, a numpy float out) and the callers hand over what they hold (lists, Series).
Floats: TypeAlias = Any
#: ``(term, values)`` pairs: a :class:`rocklab.physics.law.FlightTerm` and its parameters (the term
#: Any: law imports this module, the other way round would be a cycle).
Terms: TypeAlias = Sequence[tuple[Any, Sequence[Floats]]]

# 8 points: the flight integrals, made smooth by their substitutions, to 1e-8
_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)
_GL_S = 0.5 * (_GL_X + 1.0)
_GL_W = 0.5 * _GL_W
_GL24_X, _GL24_W = np.polynomial.legendre.leggauss(24)
_GL24_S = 0.5 * (_GL24_X + 1.0)
_GL24_W = 0.5 * _GL24_W


def _some(x: Floats) -> bool | np.bool_:
    """Whether any of x (a scalar or an array) is nonzero: :func:`numpy.any`, at a sixth of its
    cost on the small arrays of the diagnosis's hot path."""
    return np.count_nonzero(x) > 0


def _flat(*xs: Floats) -> tuple[tuple[int, ...], list[FloatArray]]:
    """The shape of xs broadcast together and each of xs broadcast to it, as a flat contiguous float array.

    :func:`numpy.broadcast_arrays` then ``ravel``, the same values, at a quarter of its cost on the small
    arrays of the diagnosis's hot path: an array of the full shape is its own ravel (a view where it is
    contiguous), only the others are copied out.
    """
    arrays = [np.asarray(x, float) for x in xs]
    shape = np.broadcast(*arrays).shape
    flat = []
    for x in arrays:
        if x.shape != shape:
            full = np.empty(shape)
            full[...] = x
            x = full
        flat.append(x.ravel())
    return shape, flat


def potential(theta: Floats, a: Floats, p: Floats) -> Floats:
    """Energy per unit I_O of a wall at rest at |theta| on a hinge of angle a [rad^2/s^2].

    p^2 (cos(a - |theta|) - cos a), the exact energy balance behind Eq. 11.
    """
    return p**2 * (np.cos(a - theta) - np.cos(a))


def potential_linear(theta: Floats, a: Floats, p: Floats) -> Floats:
    """:func:`potential` of Housner's linearised equation theta'' = p^2 (theta - a) [rad^2/s^2].

    p^2 (a |theta| - theta^2 / 2), the energy balance behind Eq. 10.
    """
    return p**2 * (a * theta - 0.5 * theta**2)


def energy(theta: Floats, thetadot: Floats, a: Floats, p: Floats, linear: bool = False) -> Floats:
    """Energy per unit I_O of a wall at |theta| with speed thetadot on hinge a [rad^2/s^2].

    1/2 thetadot^2 plus :func:`potential` (or :func:`potential_linear`): the
    kinetic energy it would have at theta = 0, conserved in free undamped
    flight; the wall overturns if it exceeds the potential at theta = a.
    """
    return 0.5 * thetadot**2 + (potential_linear if linear else potential)(theta, a, p)


def flight_angle(A: Floats, a: Floats, k: Floats = 0.0) -> Floats:
    """Rocking angle [rad] of a flight of apex A on a hinge whose angle depends on the amplitude.

    a (1 - k) + k min(A, a): a rounded or crushing hinge (the three-branch
    moment-rotation of Doherty et al. 2002, Sect. 3, taken flight by flight)
    on which a flight released at the instability angle a rocks on a, and
    smaller flights on an angle closer to a (1 - k): k > 0 the smaller
    flights rock on a smaller angle (a rounded hinge: the pivot moves inwards
    as the amplitude falls), k < 0 on a larger one.  k = 0 is the rigid
    hinge of constant angle a.

    Parameters
    ----------
    A : array_like
        Apex of the flight [rad].
    a : array_like
        Instability angle of the hinge [rad].
    k : array_like
        Dependence on the amplitude [-], -1 < k < 1.
    """
    if not _some(k):
        return a
    return a - k * (a - np.minimum(A, a))


def _apex_on_flight_angle(E: Floats, a: Floats, p: Floats, k: Floats) -> Floats:
    """Apex [rad] of a flight of energy E on the angle :func:`flight_angle` of its own apex.

    Solves potential(A, a (1 - k) + k A, p) = E: the linearised balance
    (Eq. 10's potential) is the quadratic (k - 1/2) A^2 + (1 - k) a A = E / p^2,
    whose root starts Newton's iteration on the exact one (4 steps: 1e-12
    of alpha at the amplitudes of the tests).  A wall with the energy of the
    instability rotation overturns (A = a), as :func:`apex`.
    """
    E, a, p, k = np.broadcast_arrays(*(np.asarray(x, float) for x in (E, a, p, k)))
    c = np.maximum(E, 0.0) / p**2
    b = (1.0 - k) * a
    disc = b**2 - 2.0 * (1.0 - 2.0 * k) * c
    with np.errstate(invalid="ignore", divide="ignore"):
        A = np.where(disc > 0, 2.0 * c / (b + np.sqrt(np.maximum(disc, 0.0))), a)
    A = np.clip(np.nan_to_num(A, nan=0.0), 0.0, a)
    for _ in range(4):
        u, w = (1.0 - k) * (a - A), a - k * (a - A)
        f = np.cos(u) - np.cos(w) - c
        df = (1.0 - k) * np.sin(u) + k * np.sin(w)
        with np.errstate(invalid="ignore", divide="ignore"):
            A = np.clip(A - np.where(df > 0, f / df, 0.0), 0.0, a)
    return np.where(c >= 1.0 - np.cos(a), a, A)


def apex(E: Floats, a: Floats, p: Floats) -> Floats:
    """|theta| at which a wall with energy E per unit I_O stops on hinge a [rad] (a if it overturns)."""
    c = np.cos(a) + np.maximum(E, 0.0) / p**2
    return np.where(c >= 1.0, a, a - np.arccos(np.minimum(c, 1.0)))


def _on_flights(
    integral: Callable[[FloatArray, FloatArray, FloatArray], FloatArray], A: Floats, a: Floats, p: Floats
) -> Floats:
    """``integral`` (a quadrature of flat arrays) of the flights of apex A on hinge a, broadcast.

    Computed on the flights only: a stack of tests is padded with NaN (NaN
    here, as the quadrature gives it) or, read as 0, with flights of no
    apex (0: both integrals from 0 to A).
    """
    shape, (A, a, p) = _flat(A, a, p)
    out = A * a * p * 0.0
    flown = np.flatnonzero(np.isfinite(out) & (A != 0.0))
    out[flown] = integral(A[flown], a[flown], p[flown])
    return out.reshape(shape)[()]


def path_integral(A: Floats, a: Floats, p: Floats) -> Floats:
    """int_0^A |thetadot| dtheta of the undamped flight with apex A on hinge a [rad^2/s].

    The energy a viscous loss -2 zeta p thetadot takes over half a flight is
    2 zeta p times this (first order in zeta).
    """
    return _on_flights(_path_nodes, A, a, p)


@numba.njit(cache=True)
def _sum8(r: FloatArray) -> float:
    """Sum of 8 nodes in :func:`numpy.sum`'s pairwise order."""
    # numba compiles no cast: the nodes are floats
    return ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))  # type: ignore[no-any-return]


@numba.njit(cache=True)
def _node_speeds(A: float, a: float, p: float, v: FloatArray) -> None:
    """|thetadot| of the undamped flight of apex A on hinge a at the nodes theta = A (1 - s^2), into ``v``."""
    c0, pp = math.cos(a - A), 2.0 * (p * p)
    for j in range(_GL_S.size):
        th = A * (1.0 - _GL_S[j] * _GL_S[j])
        v[j] = math.sqrt(max(pp * (c0 - math.cos(a - th)), 0.0))


@numba.njit(cache=True)
def _path_sum(A: float, v: FloatArray, r: FloatArray) -> float:
    """:func:`path_integral` of one flight from its :func:`_node_speeds` ``v`` (``r``: room for the terms)."""
    for j in range(_GL_S.size):
        r[j] = _GL_W[j] * v[j] * 2.0 * A * _GL_S[j]
    return _sum8(r)


@numba.njit(cache=True)
def _path_nodes(A: FloatArray, a: FloatArray, p: FloatArray) -> FloatArray:
    out = np.empty(A.size)
    v, r = np.empty(_GL_S.size), np.empty(_GL_S.size)
    for i in range(A.size):
        _node_speeds(A[i], a[i], p[i], v)
        out[i] = _path_sum(A[i], v, r)
    return out


def quarter_period(A: Floats, a: Floats, p: Floats) -> Floats:
    """Flight time from an apex A [rad] to theta = 0 on hinge a, exact rigid block [s].

    int_0^A dtheta / |thetadot|; Housner's arccosh(1/(1 - A/a)) / p is its
    small-alpha limit.
    """
    return _on_flights(_quarter_period_nodes, A, a, p)


@numba.njit(cache=True)
def _quarter_period_nodes(A: FloatArray, a: FloatArray, p: FloatArray) -> FloatArray:
    out = np.empty(A.size)
    r = np.empty(_GL_S.size)
    for i in range(A.size):
        Ac = min(A[i], a[i] * (1 - 1e-9))
        c0 = math.cos(a[i] - Ac)
        pp = 2.0 * (p[i] * p[i])
        for j in range(_GL_S.size):
            s = _GL_S[j]
            th = Ac * (1.0 - s * s)
            # thetadot^2 = 2 p^2 [cos(a - A) - cos(a - th)] vanishes like s^2: the ratio stays finite
            g = math.sqrt(max(pp * (c0 - math.cos(a[i] - th)), 1e-300)) / max(s, 1e-300)
            r[j] = _GL_W[j] * 2.0 * Ac / g
        out[i] = _sum8(r)
    return out


def loss_deceleration(
    thetadot: Floats,
    p: Floats,
    zeta: Floats = 0.0,
    mu: Floats = 0.0,
    kappa: Floats = 0.0,
    sign: Callable[[Floats], Floats] = np.sign,
) -> Floats:
    """Deceleration of the losses in flight, by their dependence on the angular velocity [rad/s^2].

    2 zeta p thetadot + mu p^2 sign(thetadot) + kappa thetadot |thetadot|: a viscous
    loss (zeta [-], proportional to thetadot), dry friction at the hinge (a
    constant moment mu m g R, mu [-] its ratio to the weight's moment arm R)
    and quadratic drag (kappa [1/rad], -kappa thetadot |thetadot|).  At small
    amplitude (A << alpha, a near-constant restoring p^2 alpha) the speed a
    flight loses, relative to its speed v, is of order mu / alpha (dry
    friction: constant), 4 zeta v / (3 p alpha) (viscous: proportional to v)
    and kappa v^2 / (2 p^2 alpha) (drag: proportional to v^2).  ``sign``:
    :func:`numpy.sign`, or a scalar one where speed matters.
    """
    return 2.0 * zeta * p * thetadot + mu * p**2 * sign(thetadot) + kappa * thetadot * abs(thetadot)


@numba.njit(cache=True)
def _moments(A: float, a: float, c: float) -> tuple[float, float, float]:
    """:func:`_exponential_moments` of one flight."""
    h = 0.5 * A
    sh, ch, sm, cm = math.sin(h), math.cos(h), math.sin(a - h), math.cos(a - h)
    # sin and cos of a - A from those of a - A/2 and A/2
    sA, cA = sm * ch - cm * sh, cm * ch + sm * sh
    m = math.expm1(c * A)
    q = 1.0 + c * c
    sin_m = (m * (c * sA + cA) + 2.0 * sh * (sm - c * cm)) / q
    cos_m = (m * (c * cA - sA) + 2.0 * sh * (c * sm + cm)) / q
    return sin_m, cos_m, (A if c == 0.0 else m / c)


@numba.njit(cache=True)
def _moments_of(
    A: FloatArray, a: FloatArray, c: FloatArray, sin_m: FloatArray, cos_m: FloatArray, one: FloatArray
) -> None:
    for i in range(A.size):
        sin_m[i], cos_m[i], one[i] = _moments(A[i], a[i], c[i])


def _exponential_moments(A: Floats, a: Floats, c: Floats) -> tuple[Floats, ...]:
    """int_0^A sin(a - s) e^(c s) ds, int_0^A cos(a - s) e^(c s) ds and int_0^A e^(c s) ds, closed forms.

    d/ds [e^(c s) (c sin(a - s) + cos(a - s))] = (1 + c^2) e^(c s) sin(a - s), and
    likewise with c cos(a - s) - sin(a - s) for the cosine; each difference between
    0 and A is written through expm1(c A) and sin(A/2), which keep their relative
    precision for the short flights of a wall at rest.
    """
    shape, args = _flat(A, a, c)
    out = [np.empty(args[0].size) for _ in range(3)]
    _moments_of(*args, *out)
    return tuple(x.reshape(shape)[()] for x in out)


def _work(A: Floats, a: Floats, p: Floats, mu: Floats, kappa: Floats, rise: bool) -> Floats:
    """int_0^A p^2 (sin(a - s) +- mu) exp(+-2 kappa s) ds [rad^2/s^2] (+ on the rise, - on the fall).

    The exact energy balance of a flight with dry friction and drag: on the
    rise d(thetadot^2/2)/dtheta = -p^2 (sin(a - theta) + mu) - kappa thetadot^2,
    linear in thetadot^2, so the take-off energy that reaches the apex A is
    this integral (and on the fall the landing energy from A, with the signs
    of mu and kappa turned), in closed form (:func:`_exponential_moments`).
    """
    sgn = 1.0 if rise else -1.0
    sin_m, _, one = _exponential_moments(A, a, sgn * 2.0 * np.asarray(kappa, float))
    return p**2 * (sin_m + sgn * np.asarray(mu, float) * one)


@numba.njit(cache=True)
def _rise_balance(
    A: float, a: float, p: float, zeta: float, mu: float, kappa: float, k: float, viscous: bool | np.bool_
) -> tuple[float, float]:
    """The rise's take-off energy to the apex A (:func:`_work` and the viscous loss) and its d/dA [rad^2/s^2, rad/s^2].

    On the angle :func:`flight_angle` of the apex: the integrand at A plus,
    the angle moving with the apex (d a / d A = k below a), k int_0^A p^2
    cos(a - s) exp(2 kappa s) ds; the viscous loss 2 zeta p
    :func:`path_integral` grows with A by 2 zeta p^3 sin(a - A) times the
    quarter period (the time the undamped flight takes, int dtheta /
    |thetadot|), on the same nodes (its change with the angle, k times a
    term of the order of zeta, is left out: a slope for Newton's passes).
    One flight; ``viscous``: whether any flight of the solve has a viscous loss.
    """
    if k != 0.0:
        a = a - k * (a - min(A, a))
    sin_m, cos_m, one = _moments(A, a, 2.0 * kappa)
    p2 = p * p
    energy = p2 * (sin_m + mu * one)
    slope = p2 * ((math.sin(a - A) + mu) * math.exp(2.0 * kappa * A) + (k if A < a else 0.0) * cos_m)
    if viscous:
        # the speeds on the nodes, shared by the path and the time
        v, r = np.empty(_GL_S.size), np.empty(_GL_S.size)
        _node_speeds(A, a, p, v)
        energy = energy + 2.0 * zeta * p * _path_sum(A, v, r)
        for j in range(_GL_S.size):
            r[j] = _GL_W[j] * 2.0 * A * _GL_S[j] / max(v[j], 1e-300)
        slope = slope + 2.0 * zeta * math.pow(p, 3.0) * math.sin(a - A) * _sum8(r)
    return energy, slope


# apex_after's Newton passes on the losses' work: at most, and the step [of the hinge's angle] that ends them
_NEWTON_MAX, _NEWTON_TOL = 40, 1e-12


def _viscous(zeta: Floats, p: Floats, A: Floats, a: Floats) -> Floats:
    # first order in zeta: the loss along the undamped path
    return 2.0 * zeta * p * (path_integral(A, a, p) if _some(zeta) else 0.0)


def _terms_work(terms: Terms, A: Floats, a: Floats, p: Floats, rise: bool) -> Floats:
    """The energy the terms in flight ``terms`` take over the rise to A or the fall from it [rad^2/s^2]."""
    return sum(term.work(A, a, p, rise, *values) for term, values in terms)


def landing_speed(
    A: Floats,
    a: Floats,
    p: Floats,
    zeta: Floats = 0.0,
    *,
    mu: Floats = 0.0,
    kappa: Floats = 0.0,
    k: Floats = 0.0,
    terms: Terms = (),
) -> Floats:
    """|thetadot| on arrival at theta = 0 from an apex A on hinge a [rad/s], with the losses in flight.

    The losses of :func:`loss_deceleration`: dry friction and drag exact
    (:func:`_work`), the viscous loss 2 zeta p int |thetadot| to first order
    in zeta; ``terms``, those of other laws, by their work over the fall
    (module docstring).  A wall whose restoring moment at its apex is below the
    friction moment (sin(a - A) <= mu) stays there: landing speed 0.
    ``k``: the hinge's angle depends on the amplitude, the whole flight
    rocks on the angle of its apex (:func:`flight_angle`), so the losses
    act on that angle, exactly as on a rigid hinge.
    """
    a = flight_angle(A, a, k)
    if not (_some(mu) or _some(kappa)):
        E = potential(A, a, p) - _viscous(zeta, p, A, a)
        if terms:
            E = E - _terms_work(terms, A, a, p, rise=False)
        return np.sqrt(2.0 * np.maximum(E, 0.0))
    E = _work(A, a, p, mu, kappa, rise=False) - _viscous(zeta, p, A, a)
    if terms:
        E = E - _terms_work(terms, A, a, p, rise=False)
    return np.where(np.sin(a - A) > mu, np.sqrt(2.0 * np.maximum(E, 0.0)), 0.0)


def _apex_with_losses(
    E: Floats, A: Floats, a: Floats, p: Floats, zeta: Floats, mu: Floats, kappa: Floats, k: Floats
) -> Floats:
    """:func:`apex_after` with dry friction or drag: Newton on the rise's balance from the undamped apex A.

    Each flight's Newton passes stop at its own root (a step of less than
    :data:`_NEWTON_TOL` of a): the flights still moving are the only ones
    computed, and the padding of a stack of tests (NaN) none.
    """
    shape, (E, A, a, p, zeta, mu, kappa, k) = _flat(E, A, a, p, zeta, mu, kappa, k)
    out = A.copy()
    live = np.flatnonzero(np.isfinite(E) & np.isfinite(A))
    E, A, a, p, zeta, mu, kappa, k = (x[live] for x in (E, A, a, p, zeta, mu, kappa, k))
    # the instability rotation rocks on the hinge's own angle whatever k (flight_angle(a, a, k) = a)
    over = E >= _work(a, a, p, mu, kappa, rise=True) + _viscous(zeta, p, a, a)
    out[live[over]] = a[over]
    live = live[~over]
    # Newton from the undamped apex, above the damped one, kept inside the bracket [lo, hi] of
    # the root (the work grows with A, convex or concave with the drag: a bare step may leave it)
    E, A, a, p, zeta, mu, kappa, k = (x[~over] for x in (E, A, a, p, zeta, mu, kappa, k))
    out[live] = _newton_apex(E, A, a, p, zeta, mu, kappa, k, _some(zeta))
    return out.reshape(shape)


@numba.njit(cache=True)
def _newton_apex(
    E: FloatArray,
    A: FloatArray,
    a: FloatArray,
    p: FloatArray,
    zeta: FloatArray,
    mu: FloatArray,
    kappa: FloatArray,
    k: FloatArray,
    viscous: bool | np.bool_,
) -> FloatArray:
    """:func:`_apex_with_losses`'s Newton passes, flight by flight, each to its own root."""
    out = A.copy()
    for i in range(A.size):
        x, lo, hi = A[i], 0.0, A[i]
        floor = 1e-12 * (p[i] * p[i])
        for _ in range(_NEWTON_MAX):
            energy, slope = _rise_balance(x, a[i], p[i], zeta[i], mu[i], kappa[i], k[i], viscous)
            g = energy - E[i]
            if g < 0.0:
                lo = x
            elif g > 0.0:
                hi = x
            step = x - g / (slope if (slope >= floor or slope != slope) else floor)
            if not (step > lo and step < hi):
                step = 0.5 * (lo + hi)
            out[i] = step
            if not abs(step - x) > _NEWTON_TOL * a[i]:
                break
            x = step
    return out


def apex_after(
    v: Floats,
    a: Floats,
    p: Floats,
    zeta: Floats = 0.0,
    *,
    mu: Floats = 0.0,
    kappa: Floats = 0.0,
    k: Floats = 0.0,
    terms: Terms = (),
) -> Floats:
    """Apex [rad] reached on hinge a by a wall leaving theta = 0 at |thetadot| = v, with the losses in flight.

    The inverse of :func:`landing_speed`'s balance on the rise: the undamped
    apex, then a few Newton passes on the work of dry friction and drag
    (:func:`_work`) and the first-order viscous loss; a if it overturns.
    ``k``: the hinge's angle depends on the amplitude (:func:`flight_angle`),
    so the apex and the angle of the flight are solved together (the
    undamped apex by :func:`_apex_on_flight_angle`, the losses' work on the
    angle of the apex each Newton pass reaches, :func:`_rise_balance`).
    ``terms``, those of other laws, by their work over the rise: Newton
    passes from the apex without them (:func:`_apex_with_terms`).
    """
    E = 0.5 * np.asarray(v, float) ** 2

    def rise(E: Floats) -> Floats:
        return _apex_on_flight_angle(E, a, p, k) if _some(k) else apex(E, a, p)

    A = rise(E)
    if _some(mu) or _some(kappa):
        A = _apex_with_losses(E, A, a, p, zeta, mu, kappa, k)
    elif _some(zeta):
        # the loss of the rise depends on the apex it reaches: a few fixed-point passes
        for _ in range(3):
            A = rise(E - 2.0 * zeta * p * path_integral(A, flight_angle(A, a, k), p))
    return _apex_with_terms(E, A, a, p, zeta, mu, kappa, k, terms) if terms else A


def _takeoff_energy(
    A: Floats, a: Floats, p: Floats, zeta: Floats, mu: Floats, kappa: Floats, k: Floats, terms: Terms
) -> Floats:
    """The take-off energy that reaches the apex A [rad^2/s^2]: the rise's balance on the flight's angle."""
    a = flight_angle(A, a, k)
    E = _work(A, a, p, mu, kappa, rise=True) + _viscous(zeta, p, A, a)
    return E + _terms_work(terms, A, a, p, rise=True) if terms else E


def _apex_with_terms(
    E: Floats, A: Floats, a: Floats, p: Floats, zeta: Floats, mu: Floats, kappa: Floats, k: Floats, terms: Terms
) -> Floats:
    """:func:`apex_after` with the terms of other laws: Newton passes on the rise's balance
    (:func:`_takeoff_energy`) from the apex A without them, above the root (the terms take energy), kept
    inside the bracket of the root, each flight to its own (a step of less than :data:`_NEWTON_TOL` of a).

    The slope: the integrand of the rise's balance at the apex (dry friction and drag exact, the
    terms' declared ``work_slope``); that of the viscous loss and of an angle that moves with the apex
    are left out (a slope for Newton's passes).
    """
    flat = [np.asarray(x, float) for x in (E, A, a, p, zeta, mu, kappa, k, *(q for _, v in terms for q in v))]
    args = np.broadcast_arrays(*flat)
    shape = args[0].shape
    E, A, a, p, zeta, mu, kappa, k, *rest = (x.ravel() for x in args)
    values = []
    for _, vals in terms:
        values.append(tuple(rest[: len(vals)]))
        rest = rest[len(vals) :]
    out = A.copy()
    # the instability rotation rocks on the hinge's own angle whatever k (flight_angle(a, a, k) = a)
    live = np.isfinite(E) & np.isfinite(A)
    top = _takeoff_energy(a, a, p, zeta, mu, kappa, 0.0, [(t, v) for (t, _), v in zip(terms, values)])
    out[live & (E >= top)] = a[live & (E >= top)]
    live = np.flatnonzero(live & (E < top))
    lo, hi, x = np.zeros(live.size), A[live].copy(), A[live].copy()
    for _ in range(_NEWTON_MAX):
        if not live.size:
            break
        own = [(t, tuple(q[live] for q in v)) for (t, _), v in zip(terms, values)]
        ai, pi, ki = a[live], p[live], k[live]
        g = _takeoff_energy(x, ai, pi, zeta[live], mu[live], kappa[live], ki, own) - E[live]
        lo, hi = np.where(g < 0.0, x, lo), np.where(g > 0.0, x, hi)
        af = flight_angle(x, ai, ki)
        slope = pi**2 * (np.sin(af - x) + mu[live]) * np.exp(2.0 * kappa[live] * x)
        slope = slope + sum(t.work_slope(x, af, pi, *q) for t, q in own)
        step = x - g / np.maximum(slope, 1e-12 * pi**2)
        step = np.where((step > lo) & (step < hi), step, 0.5 * (lo + hi))
        out[live] = step
        moving = np.abs(step - x) > _NEWTON_TOL * ai
        live, lo, hi, x = live[moving], lo[moving], hi[moving], step[moving]
    return out.reshape(shape)


def takeoff_speed(
    A: Floats,
    a: Floats,
    p: Floats,
    zeta: Floats = 0.0,
    *,
    mu: Floats = 0.0,
    kappa: Floats = 0.0,
    k: Floats = 0.0,
    terms: Terms = (),
) -> Floats:
    """|thetadot| at theta = 0 that reaches the apex A on hinge a with the losses in flight [rad/s].

    The inverse of :func:`apex_after`: the rise's energy balance (:func:`_work`,
    the viscous loss to first order, the work of ``terms``) on the angle of
    the flight (:func:`flight_angle`).
    """
    return np.sqrt(2.0 * _takeoff_energy(A, a, p, zeta, mu, kappa, k, terms))


def speed_loss(
    A: Floats,
    a: Floats,
    p: Floats,
    zeta: Floats = 0.0,
    *,
    mu: Floats = 0.0,
    kappa: Floats = 0.0,
    k: Floats = 0.0,
    terms: Terms = (),
) -> Floats:
    """Speed a flight of apex A loses between take-off and the next impact, over its take-off speed [-].

    1 - :func:`landing_speed` / :func:`takeoff_speed`: the flight-loss curve
    whose dependence on the speed tells the losses of
    :func:`loss_deceleration` apart.
    """
    loss: dict[str, Any] = {"zeta": zeta, "mu": mu, "kappa": kappa, "k": k, "terms": terms}
    with np.errstate(invalid="ignore", divide="ignore"):
        return 1.0 - landing_speed(A, a, p, **loss) / takeoff_speed(A, a, p, **loss)


def transit_time(v: Floats, u: Floats, a: Floats, p: Floats) -> Floats:
    """Time to move from theta = 0 to depth u on hinge a starting at |thetadot| = v [s].

    int_0^u du' / sqrt(v^2 - 2 P(u')) with the exact potential P, through
    u' = u (1 - s^2), which keeps the integrand finite when u is the turning
    point (v^2 = 2 P(u)).  Used for the excursions into the gap of one-sided
    walls (:func:`excursion_time`).
    """
    return _transit_times((v,), u, a, p)[0]


def excursion_time(v_in: Floats, v_out: Floats, u: Floats, a: Floats, p: Floats) -> Floats:
    """Duration of an excursion from theta = 0 to depth u on hinge a and back [s]: in at |thetadot| = v_in,
    out at v_out, :func:`transit_time` of each (the potential on the nodes computed once for both)."""
    t_in, t_out = _transit_times((v_in, v_out), u, a, p)
    return t_in + t_out


def _transit_times(vs: Sequence[Floats], u: Floats, a: Floats, p: Floats) -> list[Floats]:
    """:func:`transit_time` at each speed of ``vs`` to the same depth, broadcast (:func:`_transit_nodes`)."""
    shape, flat = _flat(*vs, u, a, p)
    out = _transit_nodes(np.stack(flat[: len(vs)]), *flat[len(vs) :])
    return [t.reshape(shape)[()] for t in out]


@numba.njit(cache=True)
def _nan_max(x: float, y: float) -> float:
    """max(x, y) as :func:`numpy.maximum` takes it: NaN where x is NaN (``y`` is a number)."""
    return x if (x >= y or x != x) else y


@numba.njit(cache=True)
def _sum24(r: FloatArray) -> float:
    """Sum of 24 nodes in :func:`numpy.sum`'s pairwise order (8 running sums, then as :func:`_sum8`);
    the running sums are kept in ``r``'s first 8 places."""
    for j in range(8):
        r[j] = (r[j] + r[j + 8]) + r[j + 16]
    return _sum8(r)


@numba.njit(cache=True)
def _transit_nodes(v: FloatArray, u: FloatArray, a: FloatArray, p: FloatArray) -> FloatArray:
    """:func:`transit_time` of flat arrays at the speeds of each row of ``v`` (speeds, flights), flight by
    flight: a free run and a fit of the gap evaluate it on every impact of a series thousands of times,
    the array form's (flights, 24) temporaries cost more than the quadrature, and the way in and the way
    out of an excursion share its potential on the nodes.  Each node's terms in the array form's order
    of operations (NaN in, NaN out), each sum in :func:`numpy.sum`'s: the results are those of the
    array form to the last bit."""
    out = np.empty(v.shape)
    pot, r = np.empty(_GL24_S.size), np.empty(_GL24_S.size)
    for i in range(u.size):
        pp, ca = p[i] * p[i], math.cos(a[i])
        for j in range(_GL24_S.size):
            s = _GL24_S[j]
            # 2 potential(u (1 - s^2), a, p)
            pot[j] = 2.0 * (pp * (math.cos(a[i] - u[i] * (1.0 - s * s)) - ca))
        for m in range(v.shape[0]):
            vv = v[m, i] * v[m, i]
            for j in range(_GL24_S.size):
                g = math.sqrt(_nan_max(_nan_max(vv - pot[j], 0.0), 1e-300)) / max(_GL24_S[j], 1e-300)
                r[j] = _GL24_W[j] * 2.0 * u[i] / g
            out[m, i] = _sum24(r)
    return out


def quarter_period_linear(theta0_over_alpha: npt.ArrayLike, thetadot0_over_p_alpha: npt.ArrayLike = 0.0) -> FloatArray:
    """First quarter period p T_1/4 of the linearised rocking equation [-].

    Released at theta0 with speed thetadot0 towards the vertical, a wall
    obeying theta'' = p^2 (theta - alpha) (Housner 1963) reaches theta = 0
    when (1 - r) cosh(pT) + w sinh(pT) = 1, r = theta0 / alpha,
    w = thetadot0 / (p alpha), hence

        p T_1/4 = ln[(1 + sqrt(1 - (1 - r)^2 + w^2)) / (1 - r + w)],

    which is Housner's arccosh(1 / (1 - r)) from rest (w = 0,
    :func:`rocklab.physics.wall.quarter_period_housner`; Sect. 4, Fig. 17).

    Parameters
    ----------
    theta0_over_alpha : array_like
        Release rotation over the instability angle of the motion [-].
    thetadot0_over_p_alpha : array_like
        Release speed towards the vertical over p alpha [-], >= 0.

    Returns
    -------
    ndarray
        p T_1/4; NaN where the wall does not fall (1 - r + w <= 0).
    """
    a = 1.0 - np.asarray(theta0_over_alpha, float)
    w = np.asarray(thetadot0_over_p_alpha, float)
    den = a + w
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.log((1.0 + np.sqrt(1.0 - a**2 + w**2)) / den)
    return np.where(den > 0, out, np.nan)
