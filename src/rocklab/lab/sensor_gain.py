"""A gyroscope or an accelerometer whose gain disagrees with gravity: found from the rests of an inertial record.

Instrument errors are not physics (issue 42, item 1).  An inertial record
(``docs/raw-format.md``, "record: inertial") carries a redundancy of its
own: the accelerometer's gravity gives the tilt at rest, theta = atan2(-f_y,
f_z), independently of the gyroscope, at the two rests of every test (the
hold before the release, the rest at the end).

Gyroscope.  A rate read with a gain k (reading = k theta' + bias + noise)
integrates between the rests to k times the change of the tilt, plus the
bias times the time between them.  The bias is taken from the final rest
alone, where the wall is still (over its last :data:`BIAS_REST_S`): during
the hold the screw creeps (``docs/raw-format.md``), so the rate there is not
the bias.  So

    k = (int_a^b rate dt - b_end (t_b - t_a)) / (tilt_b - tilt_a),

against 1 for a gyroscope whose scale agrees with gravity
(:func:`gyroscope_gain`).  Its noise is that of the end bias times the
time between the rests (the largest part), of the tilts at both rests and
the rate's random walk; the interval is the ratio estimator's of
:func:`rocklab.lab.channel_gain.ratio_interval` over :data:`N_BLOCKS`
pairs of blocks, block j of the hold with block j of the final rest (a
batch-means interval), widened by the rate's random walk between the rests
(sigma_rate sqrt(T / fs), common to every pair, which their scatter does not
see; a third of the bias' part for a 20 s test).  What it
cannot tell apart: a bias that changed between the rests by d reads as a
gain 1 + d (t_b - t_a) / (2 (tilt_b - tilt_a)); the stated bound on theta
(:func:`rocklab.lab.inertial.error_bound`) keeps that term.  A gyroscope
that disagrees (:func:`rocklab.lab.channel_gain.outside_margin`) has its
rate divided by its gain before theta is integrated and the impacts'
velocities are taken from its steps (:func:`applied_gyro_gain`): the
diagnosis sees the motion a consistent gyroscope gives.

Accelerometer.  At rest the specific force is gravity alone: |f| = g, so
the accelerometer's gain is the mean |f| over both rests over g
(:func:`accelerometer_gain`), its interval over :data:`N_BLOCKS` blocks of
the rests.  The tilt is a ratio of the two axes, so a gain common to both
does not bias it and nothing is corrected: a disagreement is named in
``qc.csv`` (a sensor out of calibration, or the wrong range setting), not
acted on.  Gains that differ between the axes would bias the tilt but
|f| at two tilts 0.1 rad apart does not separate them.

Gains dimensionless, rates in rad/s, forces in m/s^2.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rocklab._imports import lazy_module
from rocklab.lab.channel_gain import LEVEL, N_BLOCKS, block_starts, outside_margin, ratio_interval
from rocklab.physics.constants import G

integrate = lazy_module("scipy.integrate")
stats = lazy_module("scipy.stats")


#: Stretch at the end of the record over which the gyroscope's bias is taken for its gain [s]: the record
#: ends a few seconds after the wall has come to rest (``docs/raw-format.md``), and the bias' noise over
#: the time between the rests is the largest part of the gain's.
BIAS_REST_S = 1.5


@dataclass(frozen=True)
class SensorGain:
    """The gain of an inertial sensor against gravity, with its interval at :data:`~rocklab.lab.channel_gain.LEVEL`.

    Attributes
    ----------
    gain, low, high : float
        Estimate and interval [-] (1: agrees; NaN: no estimate).
    """

    gain: float = np.nan
    low: float = np.nan
    high: float = np.nan

    @property
    def disagrees(self) -> bool:
        """The interval excludes 1 -+ :data:`~rocklab.lab.channel_gain.MARGIN`."""
        return outside_margin(self.low, self.high)


def _block_means(x: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """Mean of ``x`` over each block that starts at ``starts``."""
    return np.add.reduceat(x, starts) / np.diff(np.r_[starts, x.size])


def _ratio(num: np.ndarray, den: np.ndarray, level: float, common: float = 0.0) -> SensorGain:
    """:class:`SensorGain` of the ratio sum(num) / sum(den) over blocks; ``common``: the standard deviation of
    the ratio's part that every block shares (which the blocks' scatter does not see), added in quadrature."""
    k, half = ratio_interval(num[:, None], den[:, None], level)
    quantile = float(stats.t.ppf(0.5 + level / 2, max(num.size - 1, 1)))
    # a negative denominator (a tilt that decreased) turns the half-width's sign
    half = np.hypot(half, quantile * common)
    return SensorGain(float(k[0]), float(k[0] - half[0]), float(k[0] + half[0]))


def gyroscope_gain(
    time: np.ndarray,
    rate: np.ndarray,
    tilt: np.ndarray,
    n_rest: int,
    fs: float,
    n_blocks: int = N_BLOCKS,
    level: float = LEVEL,
) -> SensorGain:
    """The gyroscope's gain against the change of the accelerometer's tilt between the rests (module docstring).

    Parameters
    ----------
    time : ndarray (N,)
        Time [s].
    rate : ndarray (N,)
        Gyroscope rate as recorded, lost samples bridged [rad/s].
    tilt : ndarray (N,)
        Static tilt of the accelerometer [rad] (:func:`rocklab.lab.inertial.static_tilt`).
    n_rest : int
        Samples of each rest window (:func:`rocklab.lab.inertial.rest_samples`).
    fs : float
        Sampling rate [Hz]: the bias is taken over the last :data:`BIAS_REST_S`.
    n_blocks : int
        Pairs of blocks of the interval.
    level : float
        Confidence level.

    Returns
    -------
    SensorGain
        NaN where the rests are shorter than two samples per block.
    """
    if n_rest < 2 * n_blocks:
        return SensorGain()
    turned = integrate.cumulative_trapezoid(rate, time, initial=0.0)
    a, b = slice(0, n_rest), slice(len(time) - n_rest, len(time))
    starts = block_starts(n_rest, n_blocks)
    n_bias = max(n_rest, min(int(round(BIAS_REST_S * fs)), len(time) // 4))
    bias = _block_means(rate[len(time) - n_bias :], block_starts(n_bias, n_blocks))

    def change(x: np.ndarray) -> np.ndarray:
        return _block_means(x[b], starts) - _block_means(x[a], starts)

    # the bias of the still final rest, over the time between the pair's blocks
    num = change(turned) - bias * change(time)
    den = change(tilt)
    # the rate's random walk between the rests, common to every pair: sigma^2 T / fs
    walk = float(np.std(rate[len(time) - n_bias :])) * np.sqrt((time[b].mean() - time[a].mean()) / fs)
    return _ratio(num, den, level, walk / abs(float(den.mean())))


def accelerometer_gain(
    acc_y: np.ndarray, acc_z: np.ndarray, n_rest: int, n_blocks: int = N_BLOCKS, level: float = LEVEL
) -> SensorGain:
    """The accelerometer's gain: |f| at both rests over g (module docstring).

    Parameters
    ----------
    acc_y, acc_z : ndarray (N,)
        Specific force as recorded, lost samples bridged [m/s^2].
    n_rest : int
        Samples of each rest window (:func:`rocklab.lab.inertial.rest_samples`).
    n_blocks : int
        Blocks of the interval (over both rests).
    level : float
        Confidence level.
    """
    if n_rest < n_blocks:
        return SensorGain()
    f = np.hypot(acc_y, acc_z)
    rests = np.r_[f[:n_rest], f[len(f) - n_rest :]]
    starts = block_starts(rests.size, n_blocks)
    return _ratio(np.add.reduceat(rests, starts), G * np.diff(np.r_[starts, rests.size]), level)


#: Columns of ``qc.csv`` of an inertial record's sensor gains (:func:`qc_values`).
QC_COLUMNS = (
    "gyro_gain_estimate",
    "gyro_gain_low",
    "gyro_gain_high",
    "gyro_gain_action",
    "acc_gain_estimate",
    "acc_gain_low",
    "acc_gain_high",
    "acc_gain_action",
)
#: Their values where no inertial sensor was checked (another instrument).
NO_VALUES: dict[str, str | float] = {c: "" if c.endswith("_action") else np.nan for c in QC_COLUMNS}


def qc_values(gyro: SensorGain, acc: SensorGain) -> dict[str, str | float]:
    """The :data:`QC_COLUMNS` of an inertial record.

    Every estimate and its interval; ``gyro_gain_action`` ``corrected`` (the rate
    divided by the gain) and ``acc_gain_action`` ``disagrees`` (named, not
    acted on: the tilt is a ratio) where the interval excludes 1 -+ the margin.
    """
    return {
        "gyro_gain_estimate": gyro.gain,
        "gyro_gain_low": gyro.low,
        "gyro_gain_high": gyro.high,
        "gyro_gain_action": "corrected" if gyro.disagrees else "",
        "acc_gain_estimate": acc.gain,
        "acc_gain_low": acc.low,
        "acc_gain_high": acc.high,
        "acc_gain_action": "disagrees" if acc.disagrees else "",
    }


def applied_gyro_gain(attrs: Mapping[str, Any]) -> float:
    """The gain a reduced inertial test's rate was divided by (1 where none was), from its attributes."""
    return float(attrs["gyro_gain_estimate"]) if attrs.get("gyro_gain_action") == "corrected" else 1.0
