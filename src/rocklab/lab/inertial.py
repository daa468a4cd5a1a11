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
  static tilt alike), a bias that changed during the test (the rate's
  mean at the final rest against the bias of the closure) and, where the
  gyroscope's gain was corrected, that gain's interval;
* the impacts: the spikes of the specific force (:func:`force_spikes`)
  are the instants at which the wall is on its base edge, theta = 0; the
  median of the integrated theta there is the offset that the
  accelerometer's bias gave the tilt at the anchor, and is removed
  (:func:`vertical_offset`) when no larger than that bias can make it (a
  larger one is a wall that settled askew, its base shifted, which the
  residual out-of-plumb must see: then flagged, not removed); the impacts
  are then found on theta as for any record (:mod:`rocklab.lab.motion`);
* their velocities from what the sensor measures directly
  (:func:`impacts_from_rate`, :func:`rate_steps`): the rate on either side
  of each impact, fitted with the flight's rate and extrapolated to the
  instant of the impact, which the centroid of the force's spike places to
  a fraction of a sample (:func:`spike_centroid`), and the jump of the rate
  also from the impulse of that spike (:func:`spike_impulse`); an impact
  whose spike is too small to place it, whose flight is too short to fit or
  whose rate was lost at it keeps the velocities of the flight fits of
  theta;
* a dead or clipped gyroscope or accelerometer loses the instrument
  (:func:`rocklab.lab.instrument.health`);
* the gains of both sensors against gravity, from the two rests
  (:mod:`rocklab.lab.sensor_gain`): a gyroscope whose gain disagrees has
  its rate divided by it before all of the above, an accelerometer's is
  named.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from rocklab.lab import sensor_gain
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
    flags = ["phi, v, w not measured: 0"]
    n_rest = rest_samples(fs, len(t))
    gyro, acc = (
        sensor_gain.gyroscope_gain(t, rate, tilt, n_rest, fs),
        sensor_gain.accelerometer_gain(acc_y, acc_z, n_rest),
    )
    if gyro.disagrees:
        # a scale error of the gyroscope is no motion: the rate a consistent one gives
        rate = rate / gyro.gain
        flags.append(f"gyroscope gain {gyro.gain:.4f} [{gyro.low:.4f}, {gyro.high:.4f}] against gravity: corrected")
    if acc.disagrees:
        flags.append(
            f"accelerometer gain {acc.gain:.4f} [{acc.low:.4f}, {acc.high:.4f}] against g: the tilt unaffected"
        )
    theta, bias, bias_end = integrated_rotation(t, rate, tilt, fs)
    spikes = force_spikes(t, acc_y, acc_z, fs)
    offset, offset_sigma = vertical_offset(t, theta, spikes, fs)
    if np.isfinite(offset) and abs(offset) <= ACC_BIAS_M_S2 / G + BOUND_SIGMAS * offset_sigma:
        theta = theta - offset
    elif np.isfinite(offset):
        flags.append(f"impacts {offset:.2g} rad off the accelerometer's vertical: the base shifted, not removed")
        offset_sigma = np.nan
    else:
        flags.append(f"{spikes.size} force spike(s): the vertical from the accelerometer alone")
    bound = error_bound(rate, tilt, fs, float(t[-1] - t[0]), bias, bias_end, offset_sigma)
    if gyro.disagrees:
        # the corrected gain is known to its interval: a scale error d of the rate leaves d (theta - the
        # closure's ramp), at most 2 d max|theta|
        bound += (gyro.high - gyro.low) / gyro.gain * float(np.max(np.abs(theta)))
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
            **sensor_gain.qc_values(gyro, acc),
        },
    )


#: Samples each side of an impact's instant that its step may have smeared: left out of
#: the rate's fits, the spike's centroid and impulse taken over them.  The virtual sensors
#: take the derivative of the sampled motion, which smears the rate's step over one
#: sample each side and the force's spike over two; a sensor with a slower filter needs more.
STEP_GUARD_SAMPLES = 2
#: Samples each side of the spike on which the force's smooth part under it is fitted.
SPIKE_BACKGROUND_SAMPLES = 5
#: A spike whose area is below this many standard deviations of its noise does not place the impact.
SPIKE_AREA_NOISES = 5.0
#: The spike's integral must exceed this many times the smooth force's step times a sample:
#: the centroid's correction for the step is of first order (at 200 Hz it lets through
#: impacts that the flights of theta measure better).
SPIKE_OVER_STEP = 1.0
#: Farthest a rate fit reaches from the impact, in units of 1/p (as the flight fits of theta).
STEP_WINDOW_P = 1.0
#: Fewest samples of a rate fit each side of an impact (two parameters, two degrees of freedom left).
STEP_MIN_SAMPLES = 4
#: Farthest a force spike may be from an impact found on theta to be its spike [s].
SPIKE_MATCH_S = 0.02


def _spike(
    time: np.ndarray, force: np.ndarray, t_c: float, fs: float
) -> tuple[np.ndarray, np.ndarray, float, float, float] | None:
    """The spike of the force about the instant ``t_c``, its smooth part removed.

    The smooth part is a line fitted to :data:`SPIKE_BACKGROUND_SAMPLES`
    samples each side of the :data:`STEP_GUARD_SAMPLES` samples of the spike
    about ``t_c``; the lines meet at ``t_c``, the sample that holds it split
    between them in proportion to its cell either side.

    Returns
    -------
    (tz, spike, step, sigma, spread) or None
        Time from ``t_c`` [s] and the spike [m/s^2] of the samples about it,
        the step of the smooth part at ``t_c`` [m/s^2], the noise of a sample
        [m/s^2] (the lines' residuals), and the standard deviation of the
        spike's sum in noises (its samples' and the lines'); None where the
        record ends.
    """
    half, side, h = STEP_GUARD_SAMPLES, SPIKE_BACKGROUND_SAMPLES, 1.0 / fs
    i = int(np.searchsorted(time, t_c - h / 2))
    if i - half - side < 0 or i + half + side >= time.size:
        return None
    tz = time[i - half : i + half + 1] - t_c
    w = np.clip(tz / h + 0.5, 0.0, 1.0)
    spike = force[i - half : i + half + 1].astype(float)
    Z = np.column_stack([tz, np.ones_like(tz)])
    rest, lines, spread2 = [], [], float(tz.size)
    for part, weight in ((slice(i - half - side, i - half), 1 - w), (slice(i + half + 1, i + half + 1 + side), w)):
        A = np.column_stack([time[part] - t_c, np.ones(side)])
        pinv = np.linalg.pinv(A)
        lines.append(pinv @ force[part])
        spike -= weight * (Z @ lines[-1])
        rest.append(force[part] - A @ lines[-1])
        # the spike's sum takes the line's error at each sample it covers
        spread2 += float(np.sum((weight @ Z @ pinv) ** 2))
    sigma = float(np.sqrt(np.mean(np.concatenate(rest) ** 2) * side / (side - 2)))
    return tz, spike, float(lines[1][1] - lines[0][1]), sigma, float(np.sqrt(spread2))


def spike_centroid(time: np.ndarray, force: np.ndarray, t_guess: float, fs: float) -> float:
    """Instant of the impulse of a force spike near ``t_guess``: the centroid of the spike [s].

    The impact is an impulse of theta'' (the force along y jumps by the
    angular velocity's jump times r_z); whatever smears it over a few samples
    (the sensor's filter, a derivative of the sampled motion) keeps its area
    A and, with a symmetric kernel, its centroid.  The smooth force under it
    (:func:`_spike`) steps by S at the instant (theta'' from -p^2 alpha to
    +p^2 alpha), smeared by the same kernel: that draws the centroid by
    -S var / (2 A), var the kernel's variance, which the spike's second
    moment gives (the step's part of it is odd).  The instant is moved by
    the centroid so corrected until it stays.  NaN when the spike's area is
    under :data:`SPIKE_AREA_NOISES` of its noise or :data:`SPIKE_OVER_STEP`
    times the step over a sample, the record ends or the instant runs away
    (more than two samples from the guess).

    Parameters
    ----------
    time, force : ndarray (N,)
        Time [s] and the specific force along y [m/s^2] (lost samples bridged).
    t_guess : float
        First guess of the instant [s], within a sample or two.
    fs : float
        Sampling rate [Hz].
    """
    h = 1.0 / fs
    t_c = t_guess
    for _ in range(12):
        got = _spike(time, force, t_c, fs)
        if got is None:
            return np.nan
        tz, spike, step, sigma, spread = got
        area = float(np.sum(spike))
        if not abs(area) > SPIKE_AREA_NOISES * sigma * spread:
            return np.nan
        if abs(step) > SPIKE_OVER_STEP * abs(area):
            return np.nan
        var = float(np.sum(tz**2 * spike)) / area
        # area in samples: the spike's integral is area h
        move = float(np.sum(tz * spike)) / area + step * var / (2.0 * area * h)
        t_c += float(np.clip(move, -h, h))
        if abs(t_c - t_guess) > 2 * h:
            return np.nan
        if abs(move) < 1e-4 * h:
            break
    return float(t_c)


def spike_impulse(time: np.ndarray, force: np.ndarray, t_c: float, fs: float) -> tuple[float, float]:
    """Impulse of the force spike at ``t_c`` and its standard deviation [m/s].

    The integral of the spike (:func:`_spike`): an impact's jump of the
    angular velocity times the sensor's height r_z, whatever smeared it.
    NaN where the record ends.
    """
    got = _spike(time, force, t_c, fs)
    if got is None:
        return np.nan, np.nan
    _, spike, _, sigma, spread = got
    return float(np.sum(spike)) / fs, sigma * spread / fs


def _rate_fit(tau: np.ndarray, rate: np.ndarray, p: float) -> tuple[float, float, float]:
    """The rate at tau = 0 of the linearised flight fitted to ``rate`` on ``tau`` [rad/s], and its spread.

    The rate of a flight obeys rate'' = p^2 rate (the derivative of the
    linearised rocking equation, whatever the effective alpha): c1 cosh(p tau)
    + c2 sinh(p tau) / p, c1 the rate at tau = 0.

    Returns
    -------
    (c1, var1, ss)
        c1 [rad/s]; its variance per unit variance of a sample's noise; the
        sum of the squared residuals [rad^2/s^2].
    """
    A = np.column_stack([np.cosh(p * tau), np.sinh(p * tau) / p])
    c, ss, *_ = np.linalg.lstsq(A, rate, rcond=None)
    return float(c[0]), float(np.linalg.inv(A.T @ A)[0, 0]), float(ss[0]) if ss.size else 0.0


def rate_steps(
    time: np.ndarray,
    rate: np.ndarray,
    force_y: np.ndarray,
    fs: float,
    p: float,
    r_z: float,
    t_before: ArrayLike,
    t_after: ArrayLike,
    spikes: ArrayLike = (),
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The impacts' instants and the rate just before and just after each, from the steps of the rate.

    The gyroscope measures theta' itself: an impact is a step of the rate
    between two flights.  Each side is fitted with the linearised flight
    (:func:`_rate_fit`) over at most :data:`STEP_WINDOW_P` / p within its
    flight, leaving out :data:`STEP_GUARD_SAMPLES` samples each side of the
    instant, which the step smeared, and extrapolated to the instant: the
    rate before, and a first measure of the step.  The accelerometer
    measures the step too, as the impulse of its spike over r_z
    (:func:`spike_impulse`), with less noise: a rate fitted over n samples
    is known to 2 sigma / sqrt(n), the impulse to the noise of a few samples
    of force; the step is the mean of the two weighted by their variances,
    and the rate after is the rate before plus the step.  e = 1 + step /
    rate before then takes the error of the instant only through the rate
    before, a (1 - e) / 2 part of it: the rate changes by p^2 alpha either
    side of the impact, in opposite senses, and a millisecond off would
    otherwise be 1 % of e at 0.3 rad/s.  The instant is the centroid of the
    force spike (:func:`spike_centroid`), guessed from the nearest spike
    found (:func:`force_spikes`) within :data:`SPIKE_MATCH_S`, else from the
    arrival found on theta; an impact whose spike cannot place it is left
    unmeasured (NaN).  A one-sided wall that swung into the gap (``t_after`` beyond the
    guard) keeps its two instants, each side extrapolated to its own, and
    the gyroscope's step alone.

    Parameters
    ----------
    time : ndarray (N,)
        Time [s], uniform sampling.
    rate : ndarray (N,)
        Gyroscope rate, its bias removed [rad/s] (NaN: lost).
    force_y : ndarray (N,)
        Specific force along y [m/s^2] (lost samples bridged).
    fs : float
        Sampling rate [Hz].
    p : float
        Frequency parameter of the wall [rad/s].
    r_z : float
        Height of the sensor above the base [m].
    t_before, t_after : array_like (K,)
        Arrival at and departure from theta = 0 of each impact, as found on theta [s].
    spikes : array_like
        Times of the force spikes [s] (:func:`force_spikes`).

    Returns
    -------
    t_impact, thetadot_before, thetadot_after : ndarray (K,)
        The instant of each step [s] and the rate on either side of it
        [rad/s]; NaN where the spike could not place the impact (the instant
        too), where a side has fewer than :data:`STEP_MIN_SAMPLES` samples
        or where the rate was lost within the guard.
    """
    t_b, t_a = np.asarray(t_before, float), np.asarray(t_after, float)
    spikes = np.sort(np.asarray(spikes, float))
    g, reach = STEP_GUARD_SAMPLES / fs, STEP_WINDOW_P / p
    ok = np.isfinite(rate)
    # the instants that bound the flights: the impacts on theta and the spikes (the next impact of the last)
    bounds = np.sort(np.r_[t_b, t_a, spikes])
    t_out, v_b, v_a = t_b.copy(), np.full(t_b.size, np.nan), np.full(t_b.size, np.nan)
    for k, (tb, ta) in enumerate(zip(t_b, t_a)):
        gap = ta - tb > 2 * g
        if not gap:
            near = spikes[np.abs(spikes - tb) <= SPIKE_MATCH_S]
            t_c = spike_centroid(time, force_y, float(near[np.argmin(np.abs(near - tb))]) if near.size else tb, fs)
            if np.isnan(t_c):
                t_out[k] = np.nan
                continue
            tb = ta = t_c
        t_out[k] = tb
        prev, nxt = bounds[bounds < tb - SPIKE_MATCH_S], bounds[bounds > ta + SPIKE_MATCH_S]
        lo = max(tb - reach, prev[-1] + g) if prev.size else tb - reach
        hi = min(ta + reach, nxt[0] - g) if nxt.size else ta + reach
        sb, sa = ok & (time >= lo) & (time < tb - g), ok & (time > ta + g) & (time <= hi)
        if min(sb.sum(), sa.sum()) < STEP_MIN_SAMPLES or not ok[(time >= tb - g) & (time <= ta + g)].all():
            continue
        vb, var_b, ss_b = _rate_fit(time[sb] - tb, rate[sb], p)
        va, var_a, ss_a = _rate_fit(time[sa] - ta, rate[sa], p)
        v_b[k], v_a[k] = vb, va
        if gap:
            continue
        noise2 = (ss_b + ss_a) / max(sb.sum() + sa.sum() - 4, 1)
        impulse, sigma = spike_impulse(time, force_y, tb, fs)
        var_gyro, var_acc = noise2 * (var_b + var_a), (sigma / r_z) ** 2
        if np.isfinite(impulse) and var_acc > 0 and var_gyro > 0:
            step = ((va - vb) / var_gyro + impulse / r_z / var_acc) / (1 / var_gyro + 1 / var_acc)
            v_a[k] = vb + step
    return t_out, v_b, v_a


def impacts_from_rate(ds: Any, impacts: pd.DataFrame) -> pd.DataFrame:
    """The impacts found on theta with their velocities and e taken from the rate's steps (:func:`rate_steps`).

    Parameters
    ----------
    ds : xarray.Dataset
        A reduced inertial test: ``gyro_x_rad_s``, ``acc_y_m_s2``,
        ``acc_z_m_s2`` as recorded on ``time``, ``gyro_bias_rad_s`` (of the rate
        divided by :func:`rocklab.lab.sensor_gain.applied_gyro_gain`),
        ``sampling_rate_hz`` and ``p`` [rad/s] in its attributes.
    impacts : DataFrame
        :attr:`rocklab.lab.motion.Motion.impacts` of its theta.

    Returns
    -------
    DataFrame
        ``impacts`` with ``thetadot_before``, ``thetadot_after`` [rad/s] and
        ``e_velocity`` from the rate's steps where they give both velocities;
        elsewhere (a spike too small to place the impact, a flight too short
        to fit, a rate lost within the guard) those of the flight fits of
        theta; the instants are those found on theta.  ``sensor_mm`` [mm]
        gives the sensor's height r_z.
    """
    t, fs, p = ds.time.values, float(ds.attrs["sampling_rate_hz"]), float(ds.attrs["p"])
    rate = ds.gyro_x_rad_s.values / sensor_gain.applied_gyro_gain(ds.attrs) - float(ds.attrs["gyro_bias_rad_s"])
    acc_y, acc_z = (bridge(t, x, np.isnan(x)) for x in (ds.acc_y_m_s2.values, ds.acc_z_m_s2.values))
    spikes = force_spikes(t, acc_y, acc_z, fs)
    r_z = float(np.asarray(ds.attrs["sensor_mm"], float).ravel()[2]) / 1e3
    _, v_b, v_a = rate_steps(t, rate, acc_y, fs, p, r_z, impacts.t_s, impacts.t_after_s, spikes)
    out = impacts.copy()
    got = np.isfinite(v_b) & np.isfinite(v_a)
    out.loc[got, "thetadot_before"], out.loc[got, "thetadot_after"] = v_b[got], v_a[got]
    with np.errstate(invalid="ignore", divide="ignore"):
        out["e_velocity"] = out.thetadot_after / out.thetadot_before
    return out
