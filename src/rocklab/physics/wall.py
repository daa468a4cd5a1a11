"""Geometry and rigid-body constants of a rocking wall.

A homogeneous rectangular wall of height ``h`` and thickness ``b`` rocking
about one base edge (Fig. 1 of Sorrentino, Masiani & Griffith, hereafter
"the paper").  All functions are pure and vectorise over NumPy arrays.
Lengths may be in any unit as long as they are consistent; the frequency
parameter needs metres because it involves gravity.
"""

from __future__ import annotations

import numpy as np

from rocklab.physics.constants import G
from rocklab.physics.flight import Floats, potential


def slenderness_angle(height: Floats, thickness: Floats) -> Floats:
    """Nominal slenderness angle alpha = arctan(b/h) [rad] (Fig. 1).

    Parameters
    ----------
    height, thickness : array_like
        Wall height h and thickness b, same length unit.
    """
    return np.arctan2(np.asarray(thickness, float), np.asarray(height, float))


def half_diagonal(height: Floats, thickness: Floats) -> Floats:
    """Distance R of the centre of mass from the rocking edge (Fig. 1).

    R = sqrt(h^2 + b^2) / 2, in the unit of the inputs.
    """
    return 0.5 * np.hypot(height, thickness)


def thickness(R: Floats, alpha: Floats) -> Floats:
    """Wall thickness b = 2 R sin alpha from the half diagonal and the slenderness angle (Fig. 1).

    The inverse of :func:`half_diagonal` and :func:`slenderness_angle` for
    the thickness, in the unit of ``R``.
    """
    return 2.0 * np.asarray(R, float) * np.sin(np.asarray(alpha, float))


def inertia_ratio() -> float:
    """m R^2 / I_O of a homogeneous rectangle about its base edge [-].

    I_O = 4/3 m R^2, so the ratio is 3/4: it turns Eq. 1 into Eq. 2 and
    Eq. 12 into Eq. 13.
    """
    return 0.75


def frequency_parameter(R: Floats, mR2_over_Io: float | None = None, g: float = G) -> Floats:
    """Housner's frequency parameter p = sqrt(m g R / I_O) [rad/s].

    Parameters
    ----------
    R : array_like
        Half diagonal [m].
    mR2_over_Io : float, optional
        m R^2 / I_O; defaults to the homogeneous rectangle (3/4).
    g : float
        Gravity [m/s^2].
    """
    ratio = inertia_ratio() if mR2_over_Io is None else mR2_over_Io
    return np.sqrt(ratio * g / np.asarray(R, float))


def overturning_velocity(alpha: Floats, p: Floats) -> Floats:
    """Angular velocity that overturns a wall at rest, Eq. 16 [rad/s].

    thetadot_r^2 = 2 (m g R / I_O) (1 - cos alpha) = 2 p^2 (1 - cos alpha),
    the kinetic energy that lifts the centre of mass from theta = 0 to the
    instability rotation theta = alpha.
    """
    return np.sqrt(2.0 * potential(alpha, alpha, np.asarray(p, float)))


def no_sliding_friction(zeta: Floats) -> Floats:
    """Least static friction coefficient that prevents sliding, Eq. 9 [-].

    mu_s >= 3 zeta / (1 + 4 zeta^2) (Shenton 1996) for free rocking of a
    rectangle of slenderness zeta = h/b.
    """
    z = np.asarray(zeta, float)
    return 3.0 * z / (1.0 + 4.0 * z**2)
