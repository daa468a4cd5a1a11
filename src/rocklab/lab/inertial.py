"""From an inertial record (a gyroscope and an accelerometer on the wall) to the wall's motion.

The sensor gives the rate of theta and the specific force in the body frame
(``docs/raw-format.md``, "record: inertial"); its offsets were zeroed on the
vertical wall at rest, and what remains is a small bias and white noise.
Here, from what the record itself says:

* the tilt at rest, from the accelerometer: a wall at rest reads
  (f_y, f_z) = (-g sin theta, g cos theta), so theta = atan2(-f_y, f_z)
  (:func:`static_tilt`); the release angle is that of the hold before the
  release;
* theta by integrating the rate, with the gyroscope's bias removed by the
  two rests: the wall is held before the release and at rest at the end, so
  the integral of the rate between the two rests must equal the change of
  the static tilt between them, whatever the screw's creep during the hold;
  the bias is the difference over the time between them
  (:func:`integrated_rotation`), and the accelerometer's own bias cancels
  from that difference;
* the bound on the angle error this leaves (:func:`error_bound`): the random
  walk of the rate's noise pinned at both rests (a Brownian bridge), the
  tilt's noise at the anchor, the accelerometer's bias (which shifts every
  static tilt alike) and a bias that changed during the test (the rate's
  mean at the final rest against the bias of the closure);
* the impacts: the spikes of the specific force (:func:`force_spikes`)
  are the instants at which the wall is on its base edge, theta = 0; the
  median of the integrated theta there is the offset that the
  accelerometer's bias gave the tilt at the anchor, and is removed
  (:func:`vertical_offset`) when no larger than that bias can make it (a
  larger one is a wall that settled askew, its base shifted, which the
  residual out-of-plumb must see: then flagged, not removed); the impacts' velocities are then found on theta
  as for any record (:mod:`rocklab.lab.motion`), whose flight fits on an
  integrated rate are fits of the rate;
* a dead or clipped gyroscope or accelerometer loses the instrument
  (:func:`rocklab.lab.instrument.health`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from rocklab.lab.instrument import InstrumentMotion, health
from rocklab.lab.records import InertialRecord
from rocklab.lab.rotation import bridge
from rocklab.physics.constants import G

#: Stretch at each end of the record taken as rest (the hold, the final rest) [s].
REST_S = 0.5
#: Largest accelerometer bias left after the zeroing [m/s^2] ("a few mm/s^2", docs/raw-format.md).
ACC_BIAS_M_S2 = 0.005
#: Standard deviations of the bound on the random part of the error.
BOUND_SIGMAS = 3.0
#: A spike of the specific force exceeds this many noise levels.
SPIKE_NOISES = 8.0
#: Fewest force spikes that fix the vertical (:func:`vertical_offset`).
MIN_SPIKES = 3


def static_tilt(acc_y: ArrayLike, acc_z: ArrayLike) -> np.ndarray:
    """Tilt theta of a wall at rest from its specific force [rad]: atan2(-f_y, f_z)."""
    return np.arctan2(-np.asarray(acc_y, float), np.asarray(acc_z, float))


def rest_samples(fs: float, n: int) -> int:
    """Samples of each rest window (:data:`REST_S`; a quarter of the record at most)."""
    return max(2, min(int(round(REST_S * fs)), n // 4))


def integrated_rotation(
    time: np.ndarray, rate: np.ndarray, tilt: np.ndarray, fs: float
) -> tuple[np.ndarray, float, float]:
    """Theta from the rate, its bias removed by the two rests (module docstring).

    Parameters
    ----------
    time : ndarray (N,)
        Time [s].
    rate : ndarray (N,)
        Gyroscope rate [rad/s] (lost samples bridged).
    tilt : ndarray (N,)
        Static tilt of the accelerometer [rad] (:func:`static_tilt`).
    fs : float
        Sampling rate [Hz].

    Returns
    -------
    theta : ndarray (N,)
        Rotation [rad], at the hold's tilt over the first rest window.
    bias : float
        Gyroscope bias of the closure between the rests [rad/s].
    bias_end : float
        Mean rate over the final rest [rad/s] (the bias at the end, on its own).
    """
    from scipy.integrate import cumulative_trapezoid  # imported here: scipy costs 1 s at start-up

    n = rest_samples(fs, len(time))
    a, b = slice(0, n), slice(len(time) - n, len(time))
    turned = cumulative_trapezoid(rate, time, initial=0.0)
    t_a, t_b = time[a].mean(), time[b].mean()
    bias = ((turned[b].mean() - turned[a].mean()) - (tilt[b].mean() - tilt[a].mean())) / (t_b - t_a)
    theta = tilt[a].mean() + (turned - turned[a].mean()) - bias * (time - t_a)
    return theta, float(bias), float(np.mean(rate[b]))


def vertical_offset(time: np.ndarray, theta: np.ndarray, spikes: np.ndarray, fs: float) -> tuple[float, float]:
    """Offset of theta at the impacts, where the wall is on its base edge (theta = 0), and its uncertainty [rad].

    The median of theta half a sample before each force spike (the jump of
    the force is between two samples); its uncertainty is 1.2533 times the
    spread (1.4826 MAD) over sqrt(n), the standard error of a median.  NaN
    with fewer than :data:`MIN_SPIKES` spikes.
    """
    if len(spikes) < MIN_SPIKES:
        return np.nan, np.nan
    at = np.interp(np.asarray(spikes) - 0.5 / fs, time, theta)
    offset = float(np.median(at))
    return offset, float(1.2533 * 1.4826 * np.median(np.abs(at - offset)) / np.sqrt(at.size))


def error_bound(
    rate: np.ndarray,
    tilt: np.ndarray,
    fs: float,
    duration: float,
    bias: float,
    bias_end: float,
    offset_sigma: float = np.nan,
) -> float:
    """Bound on |theta - true theta| that :func:`integrated_rotation` leaves [rad].

    ``BOUND_SIGMAS`` standard deviations of the random part, the rate's white
    noise integrated and pinned at both rests (a Brownian bridge, largest
    halfway: sigma_rate sqrt(T / (4 fs))) and the anchor: the tilt's noise
    averaged over the first rest, or, where the impacts fixed the vertical
    (:func:`vertical_offset`), the uncertainty of that offset; without them
    the accelerometer's bias too (:data:`ACC_BIAS_M_S2` / g, every static
    tilt alike).  Plus a bias that changed linearly during the test
    (|bias_end - bias| T / 4 at most halfway).  The noises come from the
    final rest of the record.
    """
    n = rest_samples(fs, len(rate))
    sigma_rate = float(np.std(rate[-n:]))
    sigma_tilt = float(np.std(tilt[-n:]))
    bridge = sigma_rate * np.sqrt(duration / (4.0 * fs))
    fixed = np.isfinite(offset_sigma)
    anchor = offset_sigma if fixed else sigma_tilt / np.sqrt(n)
    systematic = 0.0 if fixed else ACC_BIAS_M_S2 / G
    return float(BOUND_SIGMAS * np.hypot(bridge, anchor) + systematic + abs(bias_end - bias) * duration / 4.0)


def force_spikes(
    time: np.ndarray, acc_y: np.ndarray, acc_z: np.ndarray, fs: float, min_gap_s: float = 0.05
) -> np.ndarray:
    """Times of the spikes of the specific force [s]: impacts.

    The jump of the force vector from one sample to the next (mostly along
    y: an impact is a jump of theta'', tangential), against its median level
    (the noise), above :data:`SPIKE_NOISES` noise levels; spikes closer than
    ``min_gap_s`` are one impact, at its largest jump.
    """
    from scipy.signal import find_peaks  # imported here: scipy costs 1 s at start-up

    jump = np.hypot(np.diff(acc_y, prepend=acc_y[0]), np.diff(acc_z, prepend=acc_z[0]))
    level = 1.4826 * np.median(jump) / np.sqrt(2.0) if jump.size else 0.0
    if not level > 0:
        return np.array([])
    peaks, _ = find_peaks(jump, height=SPIKE_NOISES * level, distance=max(int(min_gap_s * fs), 1))
    return time[peaks]


def inertial_motion(rec: InertialRecord, alpha: float, p: float) -> InstrumentMotion:
    """The wall's motion from an inertial record (module docstring).

    Parameters
    ----------
    rec : InertialRecord
    alpha : float
        Slenderness angle of the wall [rad].
    p : float
        Frequency parameter of the wall [rad/s]: its release from about alpha
        gives the rate a span of about p alpha.
    """
    t, fs = rec.time, rec.fs
    spans: dict[str, tuple[np.ndarray, float]] = {
        "gyro_x_rad_s": (rec.rate, p * alpha),
        "acc_y_m_s2": (rec.acc_y, G * np.sin(alpha)),
        "acc_z_m_s2": (rec.acc_z, G * (1 - np.cos(alpha))),
    }
    faults, malfunction = health(spans, fs)
    lost = np.isnan(rec.rate) | np.isnan(rec.acc_y) | np.isnan(rec.acc_z)
    rate, acc_y, acc_z = (bridge(t, x, np.isnan(x)) for x in (rec.rate, rec.acc_y, rec.acc_z))
    tilt = static_tilt(acc_y, acc_z)
    theta, bias, bias_end = integrated_rotation(t, rate, tilt, fs)
    spikes = force_spikes(t, acc_y, acc_z, fs)
    offset, offset_sigma = vertical_offset(t, theta, spikes, fs)
    flags = ["phi, v, w not measured: 0"]
    if np.isfinite(offset) and abs(offset) <= ACC_BIAS_M_S2 / G + BOUND_SIGMAS * offset_sigma:
        theta = theta - offset
    elif np.isfinite(offset):
        flags.append(f"impacts {offset:.2g} rad off the accelerometer's vertical: the base shifted, not removed")
        offset_sigma = np.nan
    else:
        flags.append(f"{spikes.size} force spike(s): the vertical from the accelerometer alone")
    bound = error_bound(rate, tilt, fs, float(t[-1] - t[0]), bias, bias_end, offset_sigma)
    if lost.any():
        flags.append(f"{int(lost.sum())} lost sample(s) bridged")
    unit = {"gyro_x_rad_s": "rad/s", "acc_y_m_s2": "m/s2", "acc_z_m_s2": "m/s2"}
    variables: dict[str, tuple[str, np.ndarray, dict[str, str]]] = {
        name: ("time", x, {"units": unit[name], "long_name": f"{name} as recorded (NaN: lost)"})
        for name, (x, _) in spans.items()
    }
    variables["static_tilt"] = ("time", tilt, {"units": "rad", "long_name": "atan2(-acc_y, acc_z): theta at rest"})
    zero = np.zeros_like(t)
    return InstrumentMotion(
        theta,
        zero,
        zero,
        zero,
        lost,
        malfunction,
        flags,
        faults,
        variables,
        {
            "samples_bridged": int(lost.sum()),
            "theta_error_bound_rad": bound,
            "gyro_bias_rad_s": bias,
            "gyro_bias_end_rad_s": bias_end,
            "force_spikes": int(spikes.size),
            "vertical_offset_rad": offset,
            "sensor_mm": rec.sensor_mm,
        },
    )
