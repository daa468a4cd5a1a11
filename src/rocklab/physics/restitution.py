"""Coefficients of restitution of rocking walls: analytic and experimental.

The analytic coefficients follow from conservation of angular momentum about
the new rocking edge (Housner 1963) and, for one-sided rocking, the paper's
three-impact model (Fig. 12).  The experimental ones invert the peak
rotations of a free-rocking record.  Equation numbers refer to the paper.
All functions are pure and vectorise over NumPy arrays; angles in rad.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from rocklab.physics.boundary import Boundary
from rocklab.physics.flight import Floats, potential
from rocklab.physics.wall import inertia_ratio

#: e_exp / e_an,2s of the two-sided walls, the outlier series left out
#: (Sect. 3, "about 0.95"): the calibrated law of Fig. 21b.
CALIBRATED_RATIO_TWO_SIDED = 0.95
#: e_exp / e_an,1s of the one-sided walls over the complete histories
#: (Table 3): the calibrated law of Fig. 23b.
CALIBRATED_RATIO_ONE_SIDED = 1.05
#: (a, b) of the paper's amplitude law of the one-sided walls, e/e_an,1s = a - b (thetadot^-/thetadot_r)^2
#: (Eq. 17, Fig. 15b).
AMPLITUDE_LAW_ONE_SIDED = (1.18, 0.473)


def two_sided(alpha: Floats, mR2_over_Io: float | None = None) -> Floats:
    """Housner's analytic coefficient of restitution e_an,2s, Eqs. 1-2.

    e = 1 - 2 (m R^2 / I_O) sin^2 alpha; for a homogeneous rectangle
    (m R^2 / I_O = 3/4) this is Eq. 2, 1 - 3/2 sin^2 alpha.

    Parameters
    ----------
    alpha : array_like
        Slenderness angle [rad].
    mR2_over_Io : float, optional
        m R^2 / I_O; defaults to the homogeneous rectangle.
    """
    ratio = inertia_ratio() if mR2_over_Io is None else mR2_over_Io
    return 1.0 - 2.0 * ratio * np.sin(alpha) ** 2


def two_sided_asymmetric(b_leave: Floats, b_land: Floats, height: Floats, gyration_radius: Floats) -> Floats:
    """Coefficient of restitution of an asymmetric planar rigid body, Eq. 1 generalised.

    Angular momentum about the edge the body lands on is conserved through the
    impact (the impulse acts there).  Before it, the body turns at thetadot^-
    about the edge it leaves; after it, at thetadot^+ about the new edge:

    (I_G + m h^2 - m b_1 b_2) thetadot^- = (I_G + m h^2 + m b_2^2) thetadot^+,

    so e = thetadot^+ / thetadot^- = 1 - m b_2 (b_1 + b_2) / I_O,new, with
    I_O,new = I_G + m (h^2 + b_2^2).  For b_1 = b_2 = R sin alpha this is
    Eq. 1, 1 - 2 (m R^2 / I_O) sin^2 alpha (:func:`two_sided`).

    Parameters
    ----------
    b_leave : array_like
        Horizontal distance b_1 [m] from the centre of mass to the edge the
        body leaves.
    b_land : array_like
        Horizontal distance b_2 [m] from the centre of mass to the edge it
        lands on.
    height : array_like
        Height h [m] of the centre of mass above the base (both edges).
    gyration_radius : array_like
        Radius of gyration k_G [m] about the centre of mass in the rocking
        plane, I_G = m k_G^2.

    Returns
    -------
    ndarray or float
        e [-] of the impact that passes from the edge left to the edge landed on.
    """
    b1, b2 = np.asarray(b_leave, float), np.asarray(b_land, float)
    io_over_m = np.asarray(gyration_radius, float) ** 2 + np.asarray(height, float) ** 2 + b2**2
    out = 1.0 - b2 * (b1 + b2) / io_over_m
    return out if out.ndim else float(out)


def energy_ratio_asymmetric(b_leave: Floats, b_land: Floats, height: Floats, gyration_radius: Floats) -> Floats:
    """Kinetic energy kept by the impact of :func:`two_sided_asymmetric`, T^+ / T^- [-].

    T^+ / T^- = (I_O,new / I_O,old) e^2 = (I_G + m h^2 - m b_1 b_2)^2 / (I_O,old I_O,new),
    with I_O,old = I_G + m (h^2 + b_1^2) about the edge left: symmetric in
    b_1 and b_2, so the two impacts of an asymmetric body keep the same
    share of their energy though their velocity ratios e differ (a body
    lands on its far edge with a smaller e, but turns about it with a
    larger moment of inertia).  e^2 for b_1 = b_2 (Eq. 1).

    Parameters
    ----------
    b_leave, b_land, height, gyration_radius : array_like
        As :func:`two_sided_asymmetric` [m].
    """
    b1, b2 = np.asarray(b_leave, float), np.asarray(b_land, float)
    k2h2 = np.asarray(gyration_radius, float) ** 2 + np.asarray(height, float) ** 2
    out = (k2h2 - b1 * b2) ** 2 / ((k2h2 + b1**2) * (k2h2 + b2**2))
    return out if out.ndim else float(out)


def two_sided_from_slenderness(zeta: Floats) -> Floats:
    """Eq. 2 in terms of zeta = h/b: (2 zeta^2 - 1) / (2 (zeta^2 + 1))."""
    z2 = np.asarray(zeta, float) ** 2
    return (2.0 * z2 - 1.0) / (2.0 * (z2 + 1.0))


def transverse(alpha: Floats, mR2_over_Io: float | None = None) -> Floats:
    """Analytic coefficient of the impact on the transverse walls, Eqs. 12-13.

    e_an,tr = 1 - 2 (m R^2 / I_O) cos^2 alpha, the impulse passing through
    the upper corner A of Fig. 12.  Negative (a rebound) for h/b > sqrt(2).
    """
    ratio = inertia_ratio() if mR2_over_Io is None else mR2_over_Io
    return 1.0 - 2.0 * ratio * np.cos(alpha) ** 2


def transverse_from_slenderness(zeta: Floats) -> Floats:
    """Eq. 13 in terms of zeta = h/b: (2 - zeta^2) / (2 (zeta^2 + 1))."""
    z2 = np.asarray(zeta, float) ** 2
    return (2.0 - z2) / (2.0 * (z2 + 1.0))


def one_sided(alpha: Floats, mR2_over_Io: float | None = None) -> Floats:
    """Analytic coefficient of one-sided rocking e_an,1s, Eq. 14.

    Base impact, transverse-wall impact, base impact:
    e_an,1s = e_an,2s^2 e_an,tr.  It is negative: the wall rebounds and keeps
    rotating on the same (outer) edge.
    """
    return two_sided(alpha, mR2_over_Io) ** 2 * transverse(alpha, mR2_over_Io)


def analytic(boundary: npt.ArrayLike, alpha: Floats, mR2_over_Io: float | None = None) -> Floats:
    """Analytic coefficient of restitution of a boundary condition [-].

    Eq. 2 for ``"two-sided"`` rocking, Eq. 14 (negative: a rebound off the
    transverse walls) for ``"one-sided"``; ``boundary`` may be an array of
    those names, broadcast against ``alpha``.
    """
    b = np.asarray(boundary)
    unknown = set(np.unique(b)) - set(Boundary)
    if unknown:
        raise ValueError(f"unknown boundary {sorted(unknown)[0]!r}")
    out: Floats = np.where(b == Boundary.ONE_SIDED, one_sided(alpha, mR2_over_Io), two_sided(alpha, mR2_over_Io))
    return out if out.ndim else float(out)


def peak_energy_ratio(theta_peak: Floats, alpha: Floats) -> Floats:
    """Squared impact velocity reached from a peak, over that from alpha.

    Exact energy balance, (cos(alpha - |theta|) - cos alpha) / (1 - cos alpha);
    it equals (thetadot^- / thetadot_r)^2 of Eq. 17 for the impact that
    follows a peak |theta| (the numerator of Eq. 11, normalised by Eq. 16).
    """
    th = np.abs(np.asarray(theta_peak, float))
    return potential(th, alpha, 1.0) / potential(alpha, alpha, 1.0)


def _nth_root(ratio: Floats, n: Floats) -> Floats:
    n = np.asarray(n, float)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where((ratio >= 0) & (n > 0), np.abs(ratio) ** (1.0 / (2.0 * n)), np.nan)


def experimental_housner(theta_n: Floats, theta_0: Floats, alpha_ind: Floats, n: Floats) -> Floats:
    """Experimental coefficient after n impacts, Eq. 10 (piecewise linear).

    e_exp = [ (1 - (1 - |theta_n|/alpha)^2) / (1 - (1 - |theta_0|/alpha)^2) ]^(1/2n)

    Parameters
    ----------
    theta_n : array_like
        Peak |rotation| after the n-th impact [rad].
    theta_0 : array_like
        Release rotation [rad].
    alpha_ind : array_like
        Angle used for the normalisation, alpha_ind = theta_0 in the paper.
    n : array_like of int
        Number of impacts between theta_0 and theta_n.

    Returns
    -------
    ndarray
        e_exp (magnitude; NaN where n <= 0 or the ratio is not positive).
    """
    a = np.asarray(alpha_ind, float)
    num = 1.0 - (1.0 - np.abs(theta_n) / a) ** 2
    den = 1.0 - (1.0 - np.abs(theta_0) / a) ** 2
    return _nth_root(num / den, n)


def experimental_pena(theta_n: Floats, theta_0: Floats, alpha_ind: Floats, n: Floats) -> Floats:
    """Experimental coefficient after n impacts, Eq. 11 (Pena et al. 2007).

    e_exp = [ (cos(alpha - |theta_n|) - cos alpha) /
              (cos(alpha - |theta_0|) - cos alpha) ]^(1/2n),
    exact for any slenderness (the exact energy balance of a rigid block).
    """
    a = np.asarray(alpha_ind, float)
    return _nth_root(potential(np.abs(theta_n), a, 1.0) / potential(np.abs(theta_0), a, 1.0), n)


def ratio_peak_law(peak_over_alpha: Floats, a: float = 1.17, b: float = 0.453) -> Floats:
    """Amplitude law of one-sided rocking in peak rotation, Eq. 15.

    e_exp / e_an,1s = a - b |theta^-| / alpha, with the paper's fit
    a = 1.17, b = 0.453 as default.
    """
    return a - b * np.asarray(peak_over_alpha, float)


def ratio_velocity_law(
    velocity_ratio: Floats, a: float = AMPLITUDE_LAW_ONE_SIDED[0], b: float = AMPLITUDE_LAW_ONE_SIDED[1]
) -> Floats:
    """Amplitude law of one-sided rocking in impact velocity, Eq. 17.

    e_exp / e_an,1s = a - b (thetadot^- / thetadot_r)^2, thetadot_r from
    Eq. 16; the paper's fit a = 1.18, b = 0.473 as default.
    """
    return a - b * np.asarray(velocity_ratio, float) ** 2
