"""The linearised flight fitted to a stretch of record: the derivative filter.

Velocities are never obtained by differentiating the record.  Each side of an
impact is fitted, by linear least squares on the *raw* samples, with the
local model

    theta(tau) = c0 + c1 sinh(p tau)/p + c2 (cosh(p tau) - 1)/p^2
                 + sum_f [a_f cos(2 pi f tau) + b_f sin(2 pi f tau)],

where the first three terms span exactly the solutions of the linearised
rocking equation theta'' = p^2 (theta -+ alpha) (Housner 1963) whatever the
effective alpha, and the sinusoids absorb the mains hum (50 Hz).  c1 is the
velocity and c2 the acceleration at tau = 0.  The window on each side
reaches at most ``0.6/p`` from the impact, stops ``pre_guard_s`` before it
(the impact instant is only known to a sample) and starts ``ring_guard_s``
after it, which drops the transducer ringing: on the campaign records the
post-impact transient is 0.05-0.1 mm at ~0.9 m (1e-4 rad) and dies out in
40-50 ms, hence the 60 ms default.

Why this and not a Savitzky-Golay (SG) or low-pass derivative.  Measured
on the exact two-sided record of tests/test_motion.py (p = 3.4 rad/s,
alpha = 0.075, 400 Hz, 1e-5 rad noise, 2e-5 rad hum, ringing), error of
thetadot^- at impacts 1 and 6:

* centred SG derivative (25 ms, order 2) at the last sample before the
  impact: -5 % and -6 % (it straddles the velocity jump and lets the hum
  through; moving it 12 ms earlier still gives -4 %, the wall accelerates
  by p^2 alpha ~ 0.9 rad/s^2);
* one-sided quadratic (constant acceleration) over the same 0.6/p window:
  -3 %; one-sided cubic: -0.3 % and -0.6 % (jerk p^2 thetadot, snap);
* this model: +0.005 % and +0.02 %; scatter over noise seeds 1.1e-4 rad/s,
  0.04 % of the 0.25 rad/s impact velocity.  The residual nonlinearity
  (sin x vs x, < alpha^2/6 = 0.4 % of the restoring moment at h/b = 6.5)
  is absorbed by the free c2.  Fitting the hum rather than notch-filtering
  it avoids smearing the impact kink over the notch's ~0.2 s response.

The same model, fitted over the fall from the hold, gives the release
(:mod:`rocklab.lab.release`); fitted over a flight, its extremum refines a
peak (:mod:`rocklab.lab.motion`).  Written as alpha + A e^{p tau} + B
e^{-p tau} (Housner's form of the fall), its asymptote alpha =
c0 - c2/p^2 is the instability angle of the fitted motion
(:func:`asymptote`, :func:`exponentials`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, overload

import numpy as np


def odd_samples(n: float, lo: int = 5) -> int:
    """Odd Savitzky-Golay window length nearest ``n`` samples, at least ``lo``."""
    k = max(int(round(n)), lo)
    return k + 1 - k % 2


def _design(tau: np.ndarray, p: float, hum_hz: Sequence[float], fs: float) -> np.ndarray:
    cols = [np.ones_like(tau), np.sinh(p * tau) / p, (np.cosh(p * tau) - 1.0) / p**2]
    span = tau[-1] - tau[0] if tau.size else 0.0
    for f in hum_hz:
        # A hum column is only separable from the motion over >= 1 period;
        # at exactly Nyquist the sine column vanishes and only cos is kept.
        if f <= fs / 2 and span >= 1.0 / f:
            cols.append(np.cos(2 * np.pi * f * tau))
            if f < fs / 2 - 1e-9:
                cols.append(np.sin(2 * np.pi * f * tau))
    return np.column_stack(cols)


def local_fit(
    t: np.ndarray,
    theta: np.ndarray,
    t_ref: float,
    t_lo: float,
    t_hi: float,
    p: float,
    fs: float,
    hum_hz: Sequence[float] = (50.0,),
    min_samples: int = 5,
) -> np.ndarray | None:
    """Least-squares fit of the linearised rocking solution on [t_lo, t_hi].

    Parameters
    ----------
    t, theta : ndarray
        Time [s] and rotation [rad].
    t_ref : float
        Origin of tau; the coefficients are value, velocity, acceleration
        at ``t_ref``.
    t_lo, t_hi : float
        Fit window [s].
    p : float
        Frequency parameter [rad/s].
    fs : float
        Sampling rate [Hz].
    hum_hz : sequence of float
        Mains frequencies fitted as nuisance sinusoids.

    Returns
    -------
    ndarray of shape (3,) or None
        (c0, c1, c2); None with fewer than ``min_samples`` samples.
    """
    i0, i1 = np.searchsorted(t, [t_lo, t_hi], side="left")
    i1 = min(i1 + (i1 < t.size and t[i1] <= t_hi), t.size)
    if i1 - i0 < min_samples:
        return None
    tau = t[i0:i1] - t_ref
    A = _design(tau, p, hum_hz, fs)
    if i1 - i0 < A.shape[1] + 2:
        A = A[:, :3]
    coef = np.linalg.lstsq(A, theta[i0:i1], rcond=None)[0]
    return coef[:3]


@overload
def model_value(c: np.ndarray, tau: float, p: float) -> float: ...
@overload
def model_value(c: np.ndarray, tau: np.ndarray, p: float) -> np.ndarray: ...
def model_value(c: np.ndarray, tau: float | np.ndarray, p: float) -> Any:
    """Value of the local model at tau [rad]."""
    return c[0] + c[1] * np.sinh(p * tau) / p + c[2] * (np.cosh(p * tau) - 1.0) / p**2


@overload
def model_velocity(c: np.ndarray, tau: float, p: float) -> float: ...
@overload
def model_velocity(c: np.ndarray, tau: np.ndarray, p: float) -> np.ndarray: ...
def model_velocity(c: np.ndarray, tau: float | np.ndarray, p: float) -> Any:
    """Velocity of the local model at tau [rad/s]."""
    return c[1] * np.cosh(p * tau) + c[2] * np.sinh(p * tau) / p


def stationary_tau(c: np.ndarray, p: float) -> float:
    """tau where the model velocity vanishes (NaN if it has none)."""
    if c[2] == 0.0:
        return np.nan
    r = -p * c[1] / c[2]
    return np.arctanh(r) / p if abs(r) < 1.0 else np.nan


def inflection_tau(c: np.ndarray, p: float) -> float:
    """tau where the model acceleration vanishes, i.e. theta = c0 - c2/p^2
    and the speed is least (NaN if it has none)."""
    if c[1] == 0.0:
        return np.nan
    r = -c[2] / (p * c[1])
    return np.arctanh(r) / p if abs(r) < 1.0 else np.nan


def root_tau(c: np.ndarray, p: float, tau0: float = 0.0) -> float:
    """Zero of the model nearest tau0 by Newton (NaN if it does not converge)."""
    tau = tau0
    for _ in range(30):
        v = model_velocity(c, tau, p)
        if v == 0.0:
            return np.nan
        step = model_value(c, tau, p) / v
        tau -= step
        if abs(step) < 1e-9:
            return tau
    return np.nan


def asymptote(c: np.ndarray, p: float) -> float:
    """Rotation the model departs from exponentially, c0 - c2 / p^2 [rad].

    The instability angle of the fitted motion: theta'' = p^2 (theta - alpha)
    is alpha + A e^{p tau} + B e^{-p tau} with alpha = c0 - c2 / p^2.
    """
    return c[0] - c[2] / p**2


def exponentials(c: np.ndarray, p: float) -> tuple[float, float]:
    """A, B of the model written as :func:`asymptote` + A e^{p tau} + B e^{-p tau} [rad]."""
    return 0.5 * (c[2] / p**2 + c[1] / p), 0.5 * (c[2] / p**2 - c[1] / p)
