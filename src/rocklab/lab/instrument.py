"""The wall's motion from an instrument that measures the wall as a whole, and its health.

Transducers between the wall and a fixed frame measure lengths, from which
:mod:`rocklab.lab.kinematics` solves the motion; a rotation record
(:mod:`rocklab.lab.rotation`) and an inertial record
(:mod:`rocklab.lab.inertial`) give the rotation theta itself, or its rate.
What they share is here: the motion they give (:class:`InstrumentMotion`,
in the variables of a reduced test), the checks of a signal that is dead or
clipped (:func:`signal_status`, the lab's rule of working instruments,
``docs/raw-format.md``) and the columns of ``qc.csv`` that only they fill
(:data:`QC_COLUMNS`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rocklab.lab import channel_gain, marker_frame, sensor_gain

#: The columns of ``qc.csv`` of the instruments: which one recorded the test,
#: how many lost samples were bridged, how many impacts fell on a lost
#: stretch, the bound on theta's error that an integrated rate leaves [rad],
#: the frames of a video in which the four markers were tracked and the
#: tracking noise (theta's scatter at rest) [rad]; of transducers, the
#: channel whose gain disagrees with the rigid body (:mod:`rocklab.lab.channel_gain`);
#: of an inertial record, its sensors' gains against gravity (:mod:`rocklab.lab.sensor_gain`);
#: of motion capture, the frame markers' motion and the wall markers' length
#: (:mod:`rocklab.lab.marker_frame`).
QC_COLUMNS = (
    "instrument",
    "samples_bridged",
    "impacts_unseen",
    "theta_error_bound_rad",
    "frames_tracked",
    "tracking_noise_rad",
    *channel_gain.QC_COLUMNS,
    *sensor_gain.QC_COLUMNS,
    *marker_frame.QC_COLUMNS,
)
#: The values of :data:`QC_COLUMNS` of a test whose instrument gives none of them.
NO_VALUES = {
    "samples_bridged": 0,
    "impacts_unseen": 0,
    "theta_error_bound_rad": np.nan,
    "frames_tracked": 0,
    "tracking_noise_rad": np.nan,
    **channel_gain.NO_VALUES,
    **sensor_gain.NO_VALUES,
    **marker_frame.NO_VALUES,
}
#: A signal whose whole span is below this fraction of what the wall's motion
#: must show (its release from about alpha) is dead.
DEAD_FRACTION = 0.1
#: Shortest run of identical samples at the signal's extreme that is a clipped range [s]
#: (three samples at least: two equal samples are a rounding).
CLIP_RUN_S = 0.005


@dataclass
class InstrumentMotion:
    """The wall's motion as an instrument other than transducers gives it.

    Attributes
    ----------
    theta, phi : ndarray (N,)
        Rotations [rad] (phi zero where not measured).
    v, w : ndarray (N,)
        Sliding [mm] (zero where not measured).
    lost : ndarray of bool (N,)
        Samples not measured whose theta was bridged.
    malfunction : str or None
        Why the instrument is lost (dead, clipped, a lost stretch that cannot be bridged).
    flags : list of str
        What was repaired or is degraded, in words.
    faults : dict
        ``channels_dead`` and ``channels_clipped`` of ``qc.csv``: the record's columns found so.
    variables : dict
        The record as measured: name -> (dims, values, attrs) on ``time``.
    attrs : dict
        :data:`QC_COLUMNS` and what else the instrument's reduction says.
    """

    theta: np.ndarray
    phi: np.ndarray
    v: np.ndarray
    w: np.ndarray
    lost: np.ndarray
    malfunction: str | None = None
    flags: list[str] = field(default_factory=list)
    faults: dict[str, str] = field(default_factory=dict)
    variables: dict[str, tuple[Any, ...]] = field(default_factory=dict)
    attrs: dict[str, Any] = field(default_factory=dict)


def signal_status(x: np.ndarray, fs: float, span_expected: float) -> str:
    """``dead``, ``clipped`` or ``ok``: the health of one measured signal.

    Dead: its robust span (1st to 99th percentile) is below
    :data:`DEAD_FRACTION` of ``span_expected``, what the wall's fall from its
    release must show.  Clipped: it stays on its largest or smallest value
    for :data:`CLIP_RUN_S` (three samples at least), as a sensor at the end
    of its range does; noise makes equal samples rare anywhere else.

    Parameters
    ----------
    x : ndarray
        The signal (NaN: lost sample, ignored).
    fs : float
        Sampling rate [Hz].
    span_expected : float
        Span the wall's motion must give the signal (its unit).
    """
    y = x[np.isfinite(x)]
    if y.size < 3:
        return "dead"
    lo, hi = np.percentile(y, [1, 99])
    if hi - lo < DEAD_FRACTION * span_expected:
        return "dead"
    run = max(3, int(round(CLIP_RUN_S * fs)))
    for extreme in (y.max(), y.min()):
        at = np.r_[False, y == extreme, False].astype(np.int8)
        edges = np.diff(at)
        if (np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1)).max() >= run:
            return "clipped"
    return "ok"


def health(signals: dict[str, tuple[np.ndarray, float]], fs: float) -> tuple[dict[str, str], str | None]:
    """The faults of ``qc.csv`` and the malfunction of a record's signals.

    Parameters
    ----------
    signals : dict
        Column name -> (values, span the wall's motion must give it).
    fs : float
        Sampling rate [Hz].

    Returns
    -------
    (dict, str or None)
        ``channels_dead`` and ``channels_clipped`` (the column names, separated
        by spaces), and the malfunction in words (None when every signal works).
    """
    status = {name: signal_status(x, fs, span) for name, (x, span) in signals.items()}
    faults = {f"channels_{s}": " ".join(n for n, v in status.items() if v == s) for s in ("dead", "clipped")}
    bad = [f"{n} {v}" for n, v in status.items() if v != "ok"]
    return faults, ("; ".join(bad) if bad else None)
