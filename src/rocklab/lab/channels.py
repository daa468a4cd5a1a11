"""Health of displacement-transducer channels: find faults, repair what can be.

A transducer channel can be *lost* (dead, stuck, clipped, or dropping out
for longer than can be bridged) or carry *repairable* faults (isolated spikes,
short gaps).  The checks are relative to the channel's own noise and to its
peers recorded at the same instants, because a flat or still reading is only
suspicious while the other instruments show the wall moving or jittering.

Readings are in mm, one column per channel.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

#: Shortest run of identical readings that counts as frozen (stuck/clipped) [s].
FLAT_RUN_S = 0.25
#: Longest gap bridged by interpolation [s]; longer dropouts lose the channel.
MAX_GAP_S = 0.05
#: Span (robust range) under which a channel is dead [mm].
DEAD_SPAN_MM = 0.1
#: A spike exceeds this many noise sigmas and this many mm.
SPIKE_SIGMAS = 10.0
SPIKE_MIN_MM = 0.5
#: Out-of-plane channels held in reserve, each standing in for a lost one.
BACKUP_CHANNELS = (2,)
#: Out-of-plane channels of the kinematics: 'primary' (backups stand in) or 'all'.
CHANNEL_POLICY = "primary"
#: Statuses that lose a channel (the rest keep it, repaired or not).
LOST_STATUSES = ("dead", "stuck", "clipped", "dropout")


#: Defaults of the workflow config's ``channels`` section.
OPTIONS = {
    "flat_run_s": FLAT_RUN_S,
    "max_gap_s": MAX_GAP_S,
    "dead_span_mm": DEAD_SPAN_MM,
    "backup": list(BACKUP_CHANNELS),
    "policy": CHANNEL_POLICY,
}


@dataclass
class ChannelReport:
    """What was found on one channel and what was done to it."""

    channel: int
    status: str = "ok"  # ok | repaired | dead | stuck | clipped | dropout
    spikes: int = 0
    gap_samples_filled: int = 0
    lost_from_s: float | None = None
    noise_mm: float = float("nan")
    notes: list[str] = field(default_factory=list)

    @property
    def lost(self) -> bool:
        return self.status in LOST_STATUSES

    def describe(self) -> str:
        """What was found and done, in words (empty when nothing)."""
        parts = []
        if self.lost:
            when = f" from {self.lost_from_s:.2f} s" if self.lost_from_s is not None else ""
            parts.append(f"ch{self.channel} {self.status}{when}")
        if self.spikes:
            parts.append(f"ch{self.channel} {self.spikes} spike(s) repaired")
        if self.gap_samples_filled:
            parts.append(f"ch{self.channel} {self.gap_samples_filled} lost sample(s) interpolated")
        return "; ".join(parts)


def _runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start and stop indices of the True runs of a boolean vector."""
    edges = np.diff(np.r_[0, mask.astype(np.int8), 0])
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)


@functools.cache
def _residual_filter(window: int) -> tuple[np.ndarray, float]:
    """Weights of the residual from a local cubic over ``window`` samples, and their gain
    for white noise (read-only: shared by every call of :func:`noise_sigma`)."""
    # imported here: a job that imports the reduction for its tables only
    # (the QC table) would pay 1 s of scipy at start-up
    from scipy.signal import savgol_coeffs

    c = savgol_coeffs(window, 3)
    c[window // 2] -= 1.0
    c.flags.writeable = False
    return c, np.sqrt(np.sum(c**2))


def noise_sigma(x: np.ndarray, window: int = 9) -> float:
    """Robust noise standard deviation [mm] of a channel.

    The residual from a local cubic (Savitzky-Golay, ``window`` samples) keeps
    the white transducer noise and removes the rocking motion, whose curvature
    at 400 Hz is comparable to the noise itself; 1.4826 MAD of that residual,
    divided by the residual's exact gain for white noise, estimates sigma.
    """
    y = x[np.isfinite(x)]
    if y.size <= window:
        return float("nan")
    c, gain = _residual_filter(window)
    r = np.convolve(y, c, mode="valid")
    return float(1.4826 * np.median(np.abs(r - np.median(r))) / gain)


def flat_runs(x: np.ndarray, min_len: int) -> list[tuple[int, int]]:
    """(start, stop) of runs of at least ``min_len`` identical readings."""
    same = np.r_[False, x[1:] == x[:-1]]
    starts, stops = _runs(same)
    keep = stops - starts + 1 >= min_len
    return [(s - 1, e) for s, e in zip(starts[keep], stops[keep])]


def find_spikes(x: np.ndarray, sigma: float) -> np.ndarray:
    """Indices of isolated single-sample spikes.

    A spike jumps away and straight back: its residual from the mean of its
    neighbours is large and the neighbours' residuals are about half of it
    with the opposite sign.  The corner of a real impact also has a large
    residual at one sample, but its neighbours' residuals are near zero, so
    it is not taken for a spike.
    """
    r = np.full(x.shape, np.nan)
    r[1:-1] = x[1:-1] - 0.5 * (x[:-2] + x[2:])
    thr = max(SPIKE_SIGMAS * sigma, SPIKE_MIN_MM) if np.isfinite(sigma) else SPIKE_MIN_MM
    big = np.abs(r) > thr
    idx = np.flatnonzero(big[1:-1]) + 1
    left, mid, right = r[idx - 1], r[idx], r[idx + 1]
    isolated = (
        (left * mid < 0)
        & (right * mid < 0)
        & (np.abs(left) > 0.25 * np.abs(mid))
        & (np.abs(right) > 0.25 * np.abs(mid))
    )
    return idx[isolated]


def _peer_moving(readings: np.ndarray, col: int, start: int, stop: int) -> bool:
    """Do other channels show fresh readings over [start, stop)?"""
    seg = readings[start:stop]
    others = [c for c in range(readings.shape[1]) if c != col]
    for c in others:
        y = seg[:, c]
        y = y[np.isfinite(y)]
        if y.size > 2 and np.mean(y[1:] == y[:-1]) < 0.5:
            return True
    return False


def assess_channels(
    readings: ArrayLike,
    fs: float,
    channels: Sequence[int],
    flat_run_s: float = FLAT_RUN_S,
    max_gap_s: float = MAX_GAP_S,
    dead_span_mm: float = DEAD_SPAN_MM,
) -> tuple[np.ndarray, list[ChannelReport]]:
    """Find faults in every channel and repair spikes and short gaps.

    Parameters
    ----------
    readings : ndarray (N, nch)
        Raw elongations [mm]; NaN for samples the acquisition lost.
    fs : float
        Sampling rate [Hz].
    channels : sequence of int
        Channel numbers, in column order.
    flat_run_s, max_gap_s, dead_span_mm : float
        Thresholds (module constants of the same names give the defaults).

    Returns
    -------
    repaired : ndarray (N, nch)
        Readings with spikes and short gaps repaired, lost stretches set to NaN.
    reports : list of ChannelReport
        One per channel, in column order.
    """
    readings = np.asarray(readings, float)
    x = readings.copy()
    n, nch = x.shape
    t = np.arange(n) / fs
    flat_len = max(int(round(flat_run_s * fs)), 8)
    max_gap = max(int(round(max_gap_s * fs)), 1)
    reports: list[ChannelReport] = []
    for col, ch in enumerate(channels):
        rep = ChannelReport(int(ch))
        y = x[:, col]
        finite = np.isfinite(y)
        rep.noise_mm = noise_sigma(y)
        if finite.sum() < 10:
            rep.status, rep.lost_from_s = "dropout", 0.0
            x[:, col] = np.nan
            reports.append(rep)
            continue
        lo, hi = np.percentile(y[finite], [0.1, 99.9])
        if hi - lo < dead_span_mm:
            rep.status = "dead"
            rep.notes.append(f"span {hi - lo:.3f} mm")
            x[:, col] = np.nan
            reports.append(rep)
            continue

        ymax, ymin = np.nanmax(y), np.nanmin(y)
        # Noise makes even 2 % of a second of identical readings impossible, so
        # a short run at the channel's extreme is already clipping, while a run
        # elsewhere must last flat_run_s to count as stuck.
        for start, stop in flat_runs(y, max(flat_len // 10, 6)):
            value = y[start]
            at_limit = value in (ymax, ymin) and stop < n
            if not (at_limit or stop - start >= flat_len) or not _peer_moving(readings, col, start, stop):
                continue
            kind = "clipped" if at_limit else "stuck"
            if rep.status not in ("stuck", "clipped"):
                rep.status = kind
                rep.lost_from_s = float(t[start])
            elif kind == "stuck" and rep.status == "clipped":
                rep.status = "stuck"
            y[start:stop] = np.nan
            rep.notes.append(f"{kind} at {value:.3f} mm over {t[start]:.2f}-{t[stop - 1]:.2f} s")

        lost_samples = np.isnan(readings[:, col])
        gap_starts, gap_stops = _runs(lost_samples)
        long_gaps = [(a, b) for a, b in zip(gap_starts, gap_stops) if b - a > max_gap]
        if long_gaps and rep.status == "ok":
            rep.status = "dropout"
            rep.lost_from_s = float(t[long_gaps[0][0]])
            rep.notes.append(f"{len(long_gaps)} dropout(s), longest {max(b - a for a, b in long_gaps) / fs:.3f} s")

        spikes = find_spikes(y, rep.noise_mm)
        if spikes.size:
            y[spikes] = np.nan
            rep.spikes = int(spikes.size)

        holes = ~np.isfinite(y)
        fill = np.zeros(n, bool)
        for a, b in zip(*_runs(holes)):
            if b - a <= max_gap and a > 0 and b < n:
                fill[a:b] = True
        if fill.any():
            # imported here, as in noise_sigma
            from scipy.interpolate import PchipInterpolator

            good = np.isfinite(y)
            y[fill] = PchipInterpolator(t[good], y[good], extrapolate=False)(t[fill])
            rep.gap_samples_filled = int((fill & lost_samples).sum())
        if rep.status == "ok" and (rep.spikes or rep.gap_samples_filled):
            rep.status = "repaired"
        x[:, col] = y
        reports.append(rep)
    return x, reports
