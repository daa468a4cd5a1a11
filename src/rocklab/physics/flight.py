"""Closed forms of one flight of a rigid rocking wall (Sect. 1, Fig. 1).

A flight is the free motion between two impacts on one hinge of rocking
angle ``a``: from theta = 0 up to an apex A and back.  Energies are per unit
polar moment I_O (rad^2/s^2); the exact (nonlinear) forms are integrated by
Gauss-Legendre quadrature after a substitution that keeps the integrands
smooth, the linearised ones are Housner's (1963) closed forms.  Vectorised
over tests and impacts; the diagnosis, the dissipation analysis and the
tests of the simulators all take their flights from here.
"""

from __future__ import annotations

import numpy as np

# 8 points: the flight integrals, made smooth by their substitutions, to 1e-8
_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)
_GL_S = 0.5 * (_GL_X + 1.0)
_GL_W = 0.5 * _GL_W
_GL24_X, _GL24_W = np.polynomial.legendre.leggauss(24)
_GL24_S = 0.5 * (_GL24_X + 1.0)
_GL24_W = 0.5 * _GL24_W


def potential(theta, a, p):
    """Energy per unit I_O of a wall at rest at |theta| on a hinge of angle a [rad^2/s^2].

    p^2 (cos(a - |theta|) - cos a), the exact energy balance behind Eq. 11.
    """
    return p**2 * (np.cos(a - theta) - np.cos(a))


def potential_linear(theta, a, p):
    """:func:`potential` of Housner's linearised equation theta'' = p^2 (theta - a) [rad^2/s^2].

    p^2 (a |theta| - theta^2 / 2), the energy balance behind Eq. 10.
    """
    return p**2 * (a * theta - 0.5 * theta**2)


def energy(theta, thetadot, a, p, linear=False):
    """Energy per unit I_O of a wall at |theta| with speed thetadot on hinge a [rad^2/s^2].

    1/2 thetadot^2 plus :func:`potential` (or :func:`potential_linear`): the
    kinetic energy it would have at theta = 0, conserved in free undamped
    flight; the wall overturns if it exceeds the potential at theta = a.
    """
    return 0.5 * thetadot**2 + (potential_linear if linear else potential)(theta, a, p)


def flight_angle(A, a, k=0.0):
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
    if not np.any(k):
        return a
    return a - k * (a - np.minimum(A, a))


def _apex_on_flight_angle(E, a, p, k):
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


def apex(E, a, p):
    """|theta| at which a wall with energy E per unit I_O stops on hinge a [rad] (a if it overturns)."""
    c = np.cos(a) + np.maximum(E, 0.0) / p**2
    return np.where(c >= 1.0, a, a - np.arccos(np.minimum(c, 1.0)))


def path_integral(A, a, p):
    """int_0^A |thetadot| dtheta of the undamped flight with apex A on hinge a [rad^2/s].

    The energy a viscous loss -2 zeta p thetadot takes over half a flight is
    2 zeta p times this (first order in zeta).
    """
    A, a = np.asarray(A, float)[..., None], np.asarray(a, float)[..., None]
    th = A * (1.0 - _GL_S**2)
    f = np.sqrt(np.maximum(2.0 * np.asarray(p)[..., None] ** 2 * (np.cos(a - A) - np.cos(a - th)), 0.0))
    return np.sum(_GL_W * f * 2.0 * A * _GL_S, axis=-1)


def quarter_period(A, a, p):
    """Flight time from an apex A [rad] to theta = 0 on hinge a, exact rigid block [s].

    int_0^A dtheta / |thetadot|; Housner's arccosh(1/(1 - A/a)) / p is its
    small-alpha limit.
    """
    A, a, p = np.broadcast_arrays(np.asarray(A, float), np.asarray(a, float), np.asarray(p, float))
    Ac = np.minimum(A, a * (1 - 1e-9))[..., None]
    ac = a[..., None]
    s = _GL_S
    th = Ac * (1.0 - s**2)
    # thetadot^2 = 2 p^2 [cos(a - A) - cos(a - th)] vanishes like s^2: the ratio stays finite
    num = 2.0 * p[..., None] ** 2 * (np.cos(ac - Ac) - np.cos(ac - th))
    g = np.sqrt(np.maximum(num, 1e-300)) / np.maximum(s, 1e-300)
    return np.sum(_GL_W * 2.0 * Ac / g, axis=-1)


def landing_speed(A, a, p, zeta=0.0, k=0.0):
    """|thetadot| on arrival at theta = 0 from an apex A on hinge a [rad/s], loss 2 zeta p int |thetadot|.

    ``k``: the hinge's angle depends on the amplitude (:func:`flight_angle`).
    """
    a = flight_angle(A, a, k)
    E = potential(A, a, p) - 2.0 * zeta * p * (path_integral(A, a, p) if np.any(zeta) else 0.0)
    return np.sqrt(2.0 * np.maximum(E, 0.0))


def apex_after(v, a, p, zeta=0.0, k=0.0):
    """Apex [rad] reached on hinge a by a wall leaving theta = 0 at |thetadot| = v.

    ``k``: the hinge's angle depends on the amplitude (:func:`flight_angle`),
    so the apex and the angle of the flight are solved together.
    """
    E = 0.5 * np.asarray(v, float) ** 2

    def rise(E):
        return _apex_on_flight_angle(E, a, p, k) if np.any(k) else apex(E, a, p)

    A = rise(E)
    if np.any(zeta):
        # the loss of the rise depends on the apex it reaches: a few fixed-point passes
        for _ in range(3):
            A = rise(E - 2.0 * zeta * p * path_integral(A, flight_angle(A, a, k), p))
    return A


def transit_time(v, u, a, p):
    """Time to move from theta = 0 to depth u on hinge a starting at |thetadot| = v [s].

    int_0^u du' / sqrt(v^2 - 2 P(u')) with the exact potential P, through
    u' = u (1 - s^2), which keeps the integrand finite when u is the turning
    point (v^2 = 2 P(u)).  Used for the excursions into the gap of one-sided
    walls.
    """
    v, u, a, p = (np.asarray(x, float)[..., None] for x in np.broadcast_arrays(v, u, a, p))
    s = _GL24_S
    q = np.maximum(v**2 - 2.0 * potential(u * (1.0 - s**2), a, p), 0.0)
    g = np.sqrt(np.maximum(q, 1e-300)) / np.maximum(s, 1e-300)
    return np.sum(_GL24_W * 2.0 * u / g, axis=-1)


def quarter_period_linear(theta0_over_alpha, thetadot0_over_p_alpha=0.0):
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
