"""Motion capture's own redundancy: frame markers that must not move, wall markers a rigid length apart.

Instrument errors are not physics (issue 42, item 1).  A C3D file
(``docs/raw-format.md``, "``.c3d``") may carry ``FRAME_*`` markers on the
fixed frame beside the wall.  They do not move, so whatever motion they show
is the measuring system's: the cameras drifting (a tripod settling, a warm
mount) or knocked, which moves every marker alike.  Theta is the angle of
the wall's markers in the lab's Y-Z plane, so what matters of that motion
is its part in the plane, a rotation psi about X and a translation (Y, Z);
a rotation about Y or Z changes theta to second order only.

* Per frame, the frame markers seen are fitted to where they were over the
  first :data:`WINDOW_S` of the record (the hold; the motion then taken from
  the first frame) by a rigid motion in the
  plane (:func:`frame_motion`, the two-dimensional Procrustes solution:
  psi = atan2(sum q x m, sum q . m) of the centred reference q and measured
  m points); one marker gives the translation only, two or more the rotation
  too.
* The per-frame fit carries the markers' noise (0.03 mm over a few hundred
  mm: 1e-4 rad, five times theta's own), a drift is slow: it is smoothed by
  a local line over :data:`WINDOW_S` (Savitzky-Golay, which follows a steady
  drift to the record's ends).
* It is named when its largest excursion exceeds :data:`DRIFT_NOISES` times
  the smoothed noise (the per-frame scatter about the smooth over the root
  of the window's frames), and only then removed from the wall's markers
  (:func:`remove_frame_motion`): a system within its noise reads as without
  frame markers.
* ``WALL_LO`` and ``WALL_HI`` are fixed on the rigid wall: their distance
  does not change.  Its median and robust scatter relative to it
  (:func:`rigid_length`) tell the system's scale error over the test (its
  calibration's, not known here against a true length, which the lab does
  not record).

Lengths in mm, angles in rad.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

#: Reference stretch at the start of the record and the smoothing window of the frame's motion [s].
WINDOW_S = 1.0
#: A frame motion whose largest excursion exceeds this many smoothed noises is named (and removed).
DRIFT_NOISES = 8.0


@dataclass(frozen=True)
class FrameMotion:
    """The motion of the frame markers in the lab's Y-Z plane, smoothed.

    Attributes
    ----------
    psi : ndarray (N,)
        Rotation about X of the frame markers from where they were in the first frame [rad]
        (zero with fewer than two markers).
    shift : ndarray (N, 2)
        Their translation (Y, Z) from there [mm]: p_t = R(psi_t) p_0 + shift_t.
    markers : int
        Frame markers in the file.
    drift_rad, shift_mm : float
        Largest |psi| [rad] (NaN: never two markers seen, the rotation unknown) and
        largest |shift| [mm] over the record.
    named : bool
        Either exceeds :data:`DRIFT_NOISES` smoothed noises: the motion is removed.
    """

    psi: np.ndarray
    shift: np.ndarray
    markers: int
    drift_rad: float
    shift_mm: float
    named: bool


def _smooth(x: np.ndarray, fs: float) -> tuple[np.ndarray, float]:
    """``x`` (N,) smoothed by a local line over :data:`WINDOW_S`, and the smooth's noise (robust scatter about it
    over the root of the window's frames); NaN frames interpolated first."""
    from scipy.signal import savgol_filter  # imported here: scipy costs 1 s at start-up

    ok = np.isfinite(x)
    idx = np.arange(x.size)
    x = np.interp(idx, idx[ok], x[ok])
    window = min(max(int(WINDOW_S * fs) | 1, 3), x.size - (1 - x.size % 2))
    smooth = savgol_filter(x, window, 1, mode="interp") if window >= 3 else x
    scatter = 1.4826 * float(np.median(np.abs(x - smooth)))
    return smooth, scatter / np.sqrt(window)


def frame_motion(points: np.ndarray, seen: np.ndarray, fs: float) -> FrameMotion:
    """The rigid motion of the frame markers in the Y-Z plane, smoothed (module docstring).

    Parameters
    ----------
    points : ndarray (N, M, 3)
        The M frame markers in every frame, lab frame [mm].
    seen : ndarray (N, M) of bool
        Marker seen (residual not negative).
    fs : float
        Point rate [Hz].

    Returns
    -------
    FrameMotion
        All zero (and not named) where no frame marker is seen at the start.
    """
    n, m = seen.shape
    head = slice(0, max(int(WINDOW_S * fs), 1))
    yz = np.where(seen[..., None], points[..., 1:], np.nan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a marker never seen at the start has no reference
        ref = np.nanmedian(yz[head], axis=0)  # (M, 2)
    use = seen & np.all(np.isfinite(ref), axis=1)
    count = use.sum(axis=1)
    none = FrameMotion(np.zeros(n), np.zeros((n, 2)), m, 0.0, 0.0, False)
    if not (count > 0).any():
        return none
    w = use[..., None].astype(float)
    meas = np.where(use[..., None], yz, 0.0)
    refs = np.where(use[..., None], ref[None], 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        c_ref = refs.sum(axis=1) / count[:, None]
        c_meas = meas.sum(axis=1) / count[:, None]
    q, p = (refs - c_ref[:, None]) * w, (meas - c_meas[:, None]) * w
    cross = np.sum(q[..., 0] * p[..., 1] - q[..., 1] * p[..., 0], axis=1)
    dot = np.sum(q[..., 0] * p[..., 0] + q[..., 1] * p[..., 1], axis=1)
    psi = np.where(count >= 2, np.arctan2(cross, dot), np.nan if (count >= 2).any() else 0.0)
    psi = np.where(count > 0, psi, np.nan)
    c, s = np.cos(np.nan_to_num(psi)), np.sin(np.nan_to_num(psi))
    # measured = R(psi) reference + shift, about the lab's origin
    rotated = np.column_stack([c * c_ref[:, 0] - s * c_ref[:, 1], s * c_ref[:, 0] + c * c_ref[:, 1]])
    shift = c_meas - rotated
    psi_s, psi_noise = _smooth(psi, fs)
    parts = [_smooth(shift[:, k], fs) for k in range(2)]
    shift_s = np.column_stack([x for x, _ in parts])
    shift_noise = float(np.hypot(parts[0][1], parts[1][1]))
    # from the first frame rather than the reference window's middle: the local line reaches the record's
    # start, so a steady drift counts from where the record begins (composing with the first frame's inverse)
    psi_s = psi_s - psi_s[0]
    c, s = np.cos(psi_s), np.sin(psi_s)
    shift_s = shift_s - np.column_stack([c * shift_s[0, 0] - s * shift_s[0, 1], s * shift_s[0, 0] + c * shift_s[0, 1]])
    drift, moved = float(np.max(np.abs(psi_s))), float(np.max(np.hypot(*shift_s.T)))
    named = drift > DRIFT_NOISES * psi_noise or moved > DRIFT_NOISES * shift_noise
    return FrameMotion(psi_s, shift_s, m, drift if (count >= 2).any() else np.nan, moved, bool(named))


def remove_frame_motion(points: np.ndarray, motion: FrameMotion) -> np.ndarray:
    """Markers (N, K, 3) [mm] with the frame's motion in the Y-Z plane undone: R(-psi) (p - shift)."""
    c, s = np.cos(motion.psi)[:, None], np.sin(motion.psi)[:, None]
    y = points[..., 1] - motion.shift[:, None, 0]
    z = points[..., 2] - motion.shift[:, None, 1]
    out = points.copy()
    out[..., 1], out[..., 2] = c * y + s * z, -s * y + c * z
    return out


def rigid_length(lo: np.ndarray, hi: np.ndarray) -> tuple[float, float]:
    """Median distance of two markers on the rigid wall [mm] and its robust scatter relative to it [-].

    ``lo``, ``hi`` (N, 3): NaN where lost.  NaN, NaN when never both seen.
    """
    d = np.linalg.norm(hi - lo, axis=1)
    d = d[np.isfinite(d)]
    if not d.size:
        return np.nan, np.nan
    med = float(np.median(d))
    return med, float(1.4826 * np.median(np.abs(d - med)) / med)


#: Columns of ``qc.csv`` of a motion-capture file (:func:`qc_values`).
QC_COLUMNS = (
    "frame_markers",
    "frame_drift_rad",
    "frame_shift_mm",
    "frame_action",
    "marker_length_mm",
    "marker_length_scatter",
)
#: Their values where the instrument was no motion capture.
NO_VALUES: dict[str, str | float | int] = {
    "frame_markers": 0,
    "frame_drift_rad": np.nan,
    "frame_shift_mm": np.nan,
    "frame_action": "",
    "marker_length_mm": np.nan,
    "marker_length_scatter": np.nan,
}


def qc_values(motion: FrameMotion | None, length: tuple[float, float]) -> dict[str, str | float | int]:
    """The :data:`QC_COLUMNS` of a C3D file: its frame's motion (None: no frame markers) and :func:`rigid_length`.

    ``frame_action``: ``corrected`` where the frame's motion was named and removed.
    """
    out: dict[str, str | float | int] = dict(NO_VALUES)
    out.update(marker_length_mm=length[0], marker_length_scatter=length[1])
    if motion is not None:
        out.update(
            frame_markers=motion.markers,
            frame_drift_rad=motion.drift_rad,
            frame_shift_mm=motion.shift_mm,
            frame_action="corrected" if motion.named else "",
        )
    return out
