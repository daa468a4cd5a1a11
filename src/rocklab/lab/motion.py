"""Free-rocking motion of one test: release, impacts, peaks, end of motion.

From a uniformly sampled rotation history theta(t) [rad] (Sect. 2.2, Eq. 8)
this module finds the quantities that Sects. 3-4 of the paper build on: the
release instant and the initial rotation theta0 (``alpha_ind = theta0``), the
impacts (base impacts at theta = 0; in one-sided rocking the rebound, which
includes the impact on the transverse walls), the peak |theta| between
impacts, the angular velocity just before and just after each impact and the
end of the motion.

Derivative filter
-----------------
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

Peaks and the release are refined with the same model (its extremum), the
peak with a local fit over +-0.6/p clipped to the flight between the two
impacts (a "local parabola" that stays exact away from the apex).  The
release instant is the zero-velocity point of the model fitted to the fall
(from the departure from the hold down to half the initial rotation): the
fall from rest is theta = a - C cosh(p (t - t_r)), so t_r and theta0 = a - C
come out of a linear fit instead of from a threshold.  When the hold is the
slow creep of the screw device (the wall leaves the screw with the screw's
speed) the release is where the fitted fall had that speed.

End of the motion
-----------------
The motion ends at the first extremum that is not the apex of a flight
above the noise: its refined value must exceed ``k_noise`` times the noise,
the raw record must reach that level in the flight (the smoother overshoots
where a wall stops dead at theta = 0, typically back from the gap of a
one-sided wall, and makes a bump that is not in the data), and the fitted
curvature must be that of a wall turning back under gravity, |theta''| >=
p^2 (theta0 - |theta|) / 2 (theta'' = -p^2 (alpha - |theta|) in flight),
which the slow residual drift of a settled wall is not.  The last flight's
fit stops where the wall is back at theta ~ 0, crossing or not: a wall that
lands and stops does not cross, and the rest beyond is no flight.  Without
these rules 234 of the 298 one-sided tests of the embedded campaign ended
on a spurious "impact" with e_k ~ 0.2, which hid the amplitude dependence
of Eq. 15, and 24 of the 154 two-sided tests on a mis-fitted last peak;
with them, none.  Take-off velocities are not used for this: those of the
short last flights are too uncertain and would cut real ones.

Release and first quarter period
--------------------------------
The paper does not define the release instant beyond "the wall was very
slowly pushed by means of a screw device" (Sect. 2.1), and T_1/4 is "the
first quarter of the first cycle" (Sect. 4, Fig.  17).  Here the release is
the instant the wall leaves the screw, not the instant its fall becomes
visible, and the choice matters.  Pushed just past its instability angle
alpha_fall with the screw's speed v_s, the wall falls as alpha_fall - theta
= x0 cosh(p t) + (v_s / p) sinh(p t), x0 = alpha_fall - theta0, so almost
the whole quarter period is spent on an exponential departure and p T_1/4 ~
ln(2 alpha_fall / (x0 + v_s / p)): 6.5-7 on the embedded campaign (theta0 /
alpha_fall = 0.998-0.999, v_s ~ 3e-4 rad/s; at the release the wall is
already on the exponential departure, x0 ~ v_s / p, so Housner's closed form
from rest at the same theta0 is longer by ln 2 ~ 0.7).  A clock started when
theta has dropped by a fraction f instead gives ln(1/f) whatever the wall
and its release: 4.6 for 1 %, 3.5 for 3 % (measured on the campaign: 4.4-4.5
and 3.4-3.5).  The paper's "close to or larger than 4" is what a visibility
threshold of 1-2 % gives.  Only the screw-departure instant makes T_1/4 a
property of the wall and of its release that Housner's closed form predicts,
so it is the one used; :class:`Motion` carries the instability angle of the
fitted fall (``alpha_fall``, the asymptote of the hyperbolic model) and the
velocity at the release, the inputs of that closed form
(:func:`rocklab.dissipation.analysis.quarter_period_linear`).

All angles are returned as magnitudes of the rotation measured on the side
of release (``sign`` gives that side); velocities keep the sign of the input.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.optimize import brentq
from scipy.signal import find_peaks, savgol_filter

#: Boundary conditions of Sect. 2.1.
BOUNDARIES = ("two-sided", "one-sided")


@dataclass(frozen=True)
class Motion:
    """Kinematic landmarks of one free-rocking test.

    Attributes
    ----------
    sign : int
        +1 if the wall was released at theta > 0, -1 otherwise.
    t_release : float
        Release instant [s] (zero velocity of the fitted fall).
    theta0 : float
        Initial rotation |theta0| [rad].
    noise_rad : float
        Robust rms of transducer noise plus hum [rad].
    peak_threshold : float
        Peaks below this [rad] are not used (``k_noise * noise_rad``).
    impacts : pandas.DataFrame
        One row per impact followed by a reliable peak: ``k``, ``t_s``
        (arrival at theta = 0), ``t_after_s`` (departure from theta = 0;
        later than ``t_s`` when a one-sided wall swings into the gap),
        ``thetadot_before``, ``thetadot_after`` [rad/s], ``e_velocity``
        (signed thetadot^+ / thetadot^-), ``peak_before``, ``peak_after``
        [rad, magnitudes], ``negative_excursion`` [rad, magnitude of the
        excursion past theta = 0 of a one-sided wall; 0 if none].
    peaks : numpy.ndarray
        |theta| of the reliable peaks after impacts 1..n [rad].
    t_first_impact : float
        First impact [s] (end of the first quarter period).
    t_end : float
        End of the motion [s]: the impact that follows the last reliable
        peak, or that peak when the record stops before the impact.
    n_negative_excursions : int
        One-sided only: impacts with an excursion past theta = 0 larger than
        the detection hysteresis (wall swinging into the gap).
    alpha_fall : float
        Instability angle of the fall [rad]: the asymptote of
        theta'' = p^2 (alpha_fall - theta) fitted from the release to half of
        theta0 (NaN when the fall could not be fitted).
    thetadot_release : float
        Speed towards the vertical with which the wall left its hold [rad/s]
        (the screw's creep; 0 from a plateau).
    """

    sign: int
    t_release: float
    theta0: float
    noise_rad: float
    peak_threshold: float
    impacts: pd.DataFrame
    peaks: np.ndarray
    t_first_impact: float
    t_end: float
    n_negative_excursions: int
    alpha_fall: float
    thetadot_release: float


def odd_samples(n, lo=5):
    """Odd Savitzky-Golay window length nearest ``n`` samples, at least ``lo``."""
    n = max(int(round(n)), lo)
    return n + 1 - n % 2


def noise_level(theta, fs):
    """Robust rms of the noise plus mains hum of a rotation record [rad].

    1.4826 MAD of the residual of a 0.1 s cubic Savitzky-Golay smoother: the
    rocking motion (a few Hz) passes the smoother, white noise and 50 Hz hum
    do not, and the median ignores the few samples around impacts.
    """
    theta = np.asarray(theta, float)
    win = odd_samples(0.1 * fs, 7)
    if theta.size <= win:
        return float(1.4826 * np.median(np.abs(np.diff(theta)))) / np.sqrt(2.0)
    r = theta - savgol_filter(theta, win, 3)
    return float(1.4826 * np.median(np.abs(r - np.median(r))))


def _design(tau, p, hum_hz, fs):
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


def local_fit(t, theta, t_ref, t_lo, t_hi, p, fs, hum_hz=(50.0,), min_samples=5):
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


def model_value(c, tau, p):
    """Value of the local model at tau [rad]."""
    return c[0] + c[1] * np.sinh(p * tau) / p + c[2] * (np.cosh(p * tau) - 1.0) / p**2


def model_velocity(c, tau, p):
    """Velocity of the local model at tau [rad/s]."""
    return c[1] * np.cosh(p * tau) + c[2] * np.sinh(p * tau) / p


def _stationary_tau(c, p):
    """tau where the model velocity vanishes (NaN if it has none)."""
    if c[2] == 0.0:
        return np.nan
    r = -p * c[1] / c[2]
    return np.arctanh(r) / p if abs(r) < 1.0 else np.nan


def _inflection_tau(c, p):
    """tau where the model acceleration vanishes, i.e. theta = c0 - c2/p^2
    and the speed is least (NaN if it has none)."""
    if c[1] == 0.0:
        return np.nan
    r = -c[2] / (p * c[1])
    return np.arctanh(r) / p if abs(r) < 1.0 else np.nan


def _root_tau(c, p, tau0=0.0):
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


def _crossings(u, lo, hi):
    """Indices i where u passes from >= 0 at i to < 0 at i+1 (or vice versa)."""
    s = np.signbit(u[lo:hi])
    return lo + np.flatnonzero(s[1:] != s[:-1])


def _arrival(us, i, level):
    """First index after i where the smoothed |rotation| us is back within
    ``level`` of zero (None if the record ends first)."""
    back = np.flatnonzero(us[i:] <= level)
    return i + int(back[0]) if back.size else None


def find_release(t, u, p, fs, noise, smooth_win):
    """Release instant and initial rotation of a record u = sign * theta.

    Returns (t_release, theta0, i_half, alpha_fall, v_release): ``i_half`` is
    the first sample below theta0 / 2 (the fall), ``alpha_fall`` the
    asymptote c0 - c2 / p^2 of the model fitted to the fall (NaN without a
    fit) and ``v_release`` the speed towards the vertical at the release.
    See the module docstring for the method.
    """
    us = savgol_filter(u, smooth_win, 2)
    i_max = int(np.argmax(us))
    below = np.flatnonzero(us[i_max:] < 0.5 * us[i_max])
    if below.size == 0:
        raise ValueError("no fall from the hold plateau: the wall was not released")
    i_half = i_max + int(below[0])
    # Hold velocity: zero on a plateau, the screw speed on a slow ramp (the
    # campaign records creep at ~3e-4 rad/s before the wall leaves the screw).
    vwin = odd_samples(0.1 * fs)
    vs = savgol_filter(u, vwin, 2, deriv=1, delta=1.0 / fs)
    drop = np.flatnonzero(us[i_max:i_half] < 0.98 * us[i_max])
    i_q = i_max + (int(drop[0]) if drop.size else 0)
    v_hold = float(np.median(vs[: max(i_q // 2, 3)])) if i_q > 2 * vwin else 0.0
    v_hold = min(v_hold, 0.0)
    # Departure: the last sample before the fall whose velocity is still the
    # hold's within 8 sigma of a 0.1 s slope estimate.
    sigma_v = noise * fs * np.sqrt(12.0 / (vwin * (vwin**2 - 1.0)))
    v_th = max(8.0 * sigma_v, 1e-3 * p * us[i_max])
    still = np.flatnonzero(vs[: i_half + 1] > v_hold - v_th)
    i_dep = int(still[-1]) if still.size else 0
    i_dep = min(i_dep, i_half - 5)
    c = local_fit(t, u, t[i_dep], t[i_dep], t[i_half], p, fs, hum_hz=())
    if c is not None:
        # Release: where the fitted fall had the hold velocity (zero from
        # rest).  A wall leaving the screw with the screw's speed passes its
        # instability angle moving, so the fit may have no zero-velocity
        # point: search from its slowest point instead, and take that point
        # when the fit never slows down to the hold's speed.  Extrapolating
        # further back would meet the unphysical branch on which the fitted
        # speed grows again.
        f = lambda tau: model_velocity(c, tau, p) - v_hold  # noqa: E731
        tau_lo = _stationary_tau(c, p)
        tau_lo = tau_lo if np.isfinite(tau_lo) else _inflection_tau(c, p)
        tau_lo = tau_lo if np.isfinite(tau_lo) and tau_lo > -3.0 / p else -3.0 / p
        tau_hi = 0.5 * (t[i_half] - t[i_dep])
        if f(tau_hi) < 0.0:
            tau_r = brentq(f, tau_lo, tau_hi, xtol=1e-7) if f(tau_lo) >= 0.0 else tau_lo
            return (
                t[i_dep] + tau_r,
                float(model_value(c, tau_r, p)),
                i_half,
                float(c[0] - c[2] / p**2),
                -float(model_velocity(c, tau_r, p)),
            )
    i0 = max(0, i_dep - int(0.05 * fs))
    return t[i_dep], float(np.median(u[i0 : i_dep + 1])), i_half, np.nan, -v_hold


def extract_motion(t, theta, fs, boundary, p, *, k_noise=10.0, ring_guard_s=0.06, window_p=0.6, hum_hz=(50.0,)):
    """Release, impacts, peaks and end of a free-rocking record.

    Parameters
    ----------
    t : ndarray
        Time [s], uniform sampling.
    theta : ndarray
        Rotation [rad], zero at the vertical.
    fs : float
        Sampling rate [Hz] (100 or 400 in the campaign).
    boundary : {"two-sided", "one-sided"}
        Two-sided: impacts are sign changes of theta.  One-sided: theta
        stays on the release side; an impact is a return to theta ~ 0 and a
        rebound, and excursions past zero (the gap towards the transverse
        walls) belong to that impact and are reported, not counted.
    p : float
        Frequency parameter [rad/s] (rocklab.physics.wall.frequency_parameter).
    k_noise : float
        Reliable peaks exceed ``k_noise`` times the noise rms; the motion
        ends at the first extremum that is not such a peak of a flight
        (module docstring, "End of the motion").
    ring_guard_s : float
        Samples this close after an impact are excluded from the fits.
    window_p : float
        Half-width of the fit windows in units of 1/p.
    hum_hz : sequence of float
        Mains frequencies fitted as nuisance terms.

    Returns
    -------
    Motion
    """
    if boundary not in BOUNDARIES:
        raise ValueError(f"boundary must be one of {BOUNDARIES}, got {boundary!r}")
    t = np.asarray(t, float)
    theta = np.asarray(theta, float)
    noise = noise_level(theta, fs)
    smooth_win = odd_samples(0.025 * fs)
    sm = savgol_filter(theta, smooth_win, 2)
    sign = 1 if sm[np.argmax(np.abs(sm))] >= 0 else -1
    u = sign * theta
    t_rel, theta0, i_half, alpha_fall, v_rel = find_release(t, u, p, fs, noise, smooth_win)
    us = sign * sm
    threshold = k_noise * noise
    hyst = 5.0 * noise
    W = window_p / p
    g_pre = 2.5 / fs

    # Flight extrema after the release: alternating signs in two-sided
    # rocking, positive only in one-sided rocking.
    pos = find_peaks(us[i_half:], prominence=hyst)[0] + i_half
    if boundary == "two-sided":
        neg = find_peaks(-us[i_half:], prominence=hyst)[0] + i_half
        ext = np.r_[pos, neg]
        ext.sort(kind="stable")
        # Keep one extremum per lobe: consecutive same-sign extrema are
        # noise-split lobes, the larger one is the peak.
        keep = []
        for i in ext:
            if keep and np.sign(us[i]) == np.sign(us[keep[-1]]):
                if abs(us[i]) > abs(us[keep[-1]]):
                    keep[-1] = i
            else:
                keep.append(i)
        ext = np.array([i for i in keep if abs(us[i]) > hyst], int)
        # The first lobe must be on the far side of the release.
        if ext.size and us[ext[0]] > 0:
            ext = ext[1:]
    else:
        ext = pos[us[pos] > hyst]

    # Impacts: between the fall (or previous peak) and the next peak.
    starts = np.r_[i_half, ext[:-1]] if ext.size else np.array([], int)
    rows = []
    prev_after = t_rel
    for k, (a, b) in enumerate(zip(starts, ext), start=1):
        seg = u[a : b + 1]
        if boundary == "two-sided":
            cr = _crossings(seg, 0, seg.size)
            if cr.size == 0:
                break
            ib = a + int(cr[0])
            ia = a + int(cr[-1])
            tb = t[ib] + (t[ib + 1] - t[ib]) * u[ib] / (u[ib] - u[ib + 1])
            ta = t[ia] + (t[ia + 1] - t[ia]) * u[ia] / (u[ia] - u[ia + 1])
            neg_exc = 0.0
        else:
            cr = _crossings(seg, 0, seg.size)
            if cr.size:
                ib, ia = a + int(cr[0]), a + int(cr[-1])
                tb = t[ib] + (t[ib + 1] - t[ib]) * u[ib] / (u[ib] - u[ib + 1])
                ta = t[ia] + (t[ia + 1] - t[ia]) * u[ia] / (u[ia] - u[ia + 1])
            else:
                tb = ta = t[a + int(np.argmin(seg))]
            neg_exc = float(max(0.0, -u[a : b + 1].min()))
        # Velocity before: flight since the previous impact, ringing excluded
        # (late flights are short: keep at least 60 % of them).
        lo = max(prev_after + min(ring_guard_s, 0.4 * (tb - prev_after)), tb - W)
        c_b = local_fit(t, u, tb, lo, tb - g_pre, p, fs, hum_hz)
        vb = np.nan
        if c_b is not None:
            r = _root_tau(c_b, p)
            tau = r if np.isfinite(r) and abs(r) < 4 * g_pre else 0.0
            tb = tb + tau
            vb = model_velocity(c_b, tau, p)
        # Velocity after: the next flight, from the end of the ringing.
        half_flight = t[b] - ta
        guard = min(ring_guard_s, 0.8 * half_flight)
        hi = min(ta + guard + W, t[b] + 0.8 * half_flight)
        c_a = local_fit(t, u, ta, ta + guard, hi, p, fs, hum_hz)
        va = np.nan
        if c_a is not None:
            r = _root_tau(c_a, p)
            tau = r if np.isfinite(r) and abs(r) < ring_guard_s else 0.0
            ta = ta + tau
            va = model_velocity(c_a, tau, p)
        rows.append((k, tb, ta, vb, va, neg_exc))
        prev_after = ta

    # Peaks: extremum of the local model within the flight after each impact,
    # and whether it is the apex of a flight (module docstring).
    peaks, flights = [], []
    for j, i in enumerate(ext[: len(rows)]):
        lo = rows[j][2] + min(ring_guard_s, 0.8 * (t[i] - rows[j][2]))
        if j + 1 < len(rows):
            hi = rows[j + 1][1] - g_pre
        else:
            # The last flight ends where the wall comes back to theta ~ 0,
            # crossing or not (a wall that lands and stops does not cross):
            # beyond it lies the rest, which a flight model cannot fit.
            i_back = _arrival(us, i, hyst)
            hi = t[i_back] - g_pre if i_back is not None else t[-1]
        lo, hi = max(lo, t[i] - W), min(hi, t[i] + W)
        c = local_fit(t, u, t[i], lo, hi, p, fs, hum_hz)
        val = abs(us[i])
        side = np.sign(us[i])
        flight = True
        if c is not None:
            tau = _stationary_tau(c, p)
            if np.isfinite(tau) and lo - t[i] <= tau <= hi - t[i]:
                val = abs(float(model_value(c, tau, p)))
            flight = -side * c[2] >= 0.5 * p**2 * (theta0 - val)
        i0, i1 = np.searchsorted(t, [lo, hi])
        raw = side * u[i0 : i1 + 1]
        peaks.append(val)
        flights.append(flight and raw.size > 0 and raw.max() >= threshold)
    peaks = np.asarray(peaks)

    reliable = (peaks >= threshold) & np.asarray(flights, bool)
    n_ok = int(np.argmin(reliable)) if not reliable.all() else peaks.size
    rows = rows[:n_ok] if n_ok < len(rows) else rows
    peaks = peaks[:n_ok]
    imp = pd.DataFrame(
        rows, columns=["k", "t_s", "t_after_s", "thetadot_before", "thetadot_after", "negative_excursion"]
    )
    imp["thetadot_before"] *= sign
    imp["thetadot_after"] *= sign
    with np.errstate(invalid="ignore", divide="ignore"):
        imp["e_velocity"] = imp.thetadot_after / imp.thetadot_before
    imp["peak_before"] = np.r_[theta0, peaks[:-1]] if n_ok else np.array([])
    imp["peak_after"] = peaks
    n_neg = int((imp.negative_excursion > hyst).sum())
    if n_ok:
        # End: the impact after the last reliable peak, if the record has it.
        i_last = ext[n_ok - 1]
        i_back = _arrival(us, i_last, hyst)
        t_end = float(t[i_back]) if i_back is not None else float(t[i_last])
        t_first = float(imp.t_s.iloc[0])
    else:
        t_end = t_first = np.nan
    return Motion(
        sign, float(t_rel), float(theta0), noise, threshold, imp, peaks, t_first, t_end, n_neg, alpha_fall, float(v_rel)
    )


def centre_amplification(disp_centre, disp_side_from_theta, i_first_impact):
    """Channel-5 amplification of one-sided tests (Fig. 20b) [-].

    Ratio of the maximum |displacement| after the first impact measured at
    the centre of the facade (channel 5) to the one predicted at the same
    height by the rigid rotation (Eq. 8).  Both series in the same unit.
    """
    c = np.abs(np.asarray(disp_centre, float)[i_first_impact:])
    s = np.abs(np.asarray(disp_side_from_theta, float)[i_first_impact:])
    return float(np.nanmax(c) / np.nanmax(s))
