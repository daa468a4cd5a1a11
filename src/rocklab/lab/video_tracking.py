"""Tracking the four markers of a filmed test, and theta from them (``docs/raw-format.md``, a filmed test).

The video shows the wall's end face from the side: two round bright
markers on the wall on a line that is vertical when the wall is, and two on
a fixed plumb post, on a darker ground.  Here:

* each frame's markers are found as bright blobs (:func:`find_markers`):
  pixels above half way from the ground to the brightest pixel, joined
  into connected components (OpenCV), each located by its centroid weighted
  by brightness above its own surroundings (sub-pixel, free of the pull of
  the pixel grid that a threshold gives);
* the blobs are linked from frame to frame to the four markers
  (:func:`link_markers`), each predicted at constant velocity from its last
  two positions, the nearest blob within reach taken, the closest pairs
  first; a marker without a blob in reach is lost in that frame;
* which markers are the post's is read from the motion: the post is fixed,
  the two markers that move least are its (:func:`marker_roles`);
* theta is the angle from the post's line to the wall's line, positive as
  the wall's top moves to the right of the image (:func:`theta_from_markers`);
  it needs no scale and no level camera.

A video is refused, naming the file, when it cannot be decoded, gives no
frame rate, never shows four markers, when two markers meet (they may
swap or merge: who is who is lost) or when nothing moves (the wall's
markers cannot be told from the post's).  Time is the frame number over the
container's frame rate.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rocklab.lab.raw_format import RawFormatError

#: The markers of a filmed test, in the order of :attr:`Tracking.centroids`.
MARKERS = ("wall_low", "wall_high", "post_low", "post_high")
#: Smallest blob that is a marker [pixels]: a marker of 6 pixels across covers 28 above its half level.
MIN_AREA_PX = 9
#: Pixels around a blob's box in which its centroid is measured (its surroundings: the rim).
MARGIN_PX = 3
#: Two markers closer than this many diameters may swap or merge: the video is refused.
MEET_DIAMETERS = 1.5
#: A blob farther than this many diameters from a marker's prediction is not that marker.
REACH_DIAMETERS = 4.0
#: The wall's markers must move this many times more than the post's (the post is fixed).
ROLE_CONTRAST = 3.0
#: The rest at the end of a record over which the tracking noise is measured [s].
REST_S = 1.0
#: Frames of a video above which the tracking shows a progress bar.
PROGRESS_FRAMES = 2000


@dataclass
class Tracking:
    """The four markers tracked in a video, and theta.

    Attributes
    ----------
    time : ndarray (N,)
        Frame time [s]: frame number over the frame rate.
    theta : ndarray (N,)
        Angle from the post's marker line to the wall's [rad], positive as
        the wall's top moves right; NaN where a marker was lost.
    centroids : ndarray (N, 4, 2)
        Image position (x right, y down) of :data:`MARKERS` [pixels]; NaN where lost.
    fs : float
        Frame rate of the container [Hz].
    frames_tracked : int
        Frames in which all four markers were found.
    noise_rad : float
        Tracking noise: robust standard deviation of theta over the last
        :data:`REST_S` of the video, the wall at rest [rad].
    diameter_px : float
        Median diameter of the markers [pixels].
    """

    time: np.ndarray
    theta: np.ndarray
    centroids: np.ndarray
    fs: float
    frames_tracked: int
    noise_rad: float
    diameter_px: float


def find_markers(gray: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The bright round blobs of one frame, at sub-pixel precision.

    Parameters
    ----------
    gray : ndarray (H, W) of uint8
        The frame in grey levels.

    Returns
    -------
    centroids : ndarray (k, 2)
        Brightness-weighted centroid (x right, y down) of each blob [pixels].
    areas : ndarray (k,)
        Pixels of each blob above the level [pixels].
    """
    import cv2

    ground = float(np.median(gray[::8, ::8]))  # a subsample: the markers are a small part of the frame
    peak = float(gray.max())
    if peak - ground < 20:  # no contrast: nothing bright in the frame
        return np.empty((0, 2)), np.empty(0)
    level = ground + 0.5 * (peak - ground)
    mask = (gray > level).astype(np.uint8)
    _, _, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    stats = stats[1:]  # component 0 is the ground
    stats = stats[stats[:, cv2.CC_STAT_AREA] >= MIN_AREA_PX]
    centroids = np.array([_centroid(gray, *box) for box in stats[:, :4]]).reshape(-1, 2)
    return centroids, stats[:, cv2.CC_STAT_AREA].astype(float)


def _centroid(gray: np.ndarray, x: int, y: int, w: int, h: int) -> tuple[float, float]:
    """Centroid of a blob's brightness above its own surroundings, in its box widened by :data:`MARGIN_PX`.

    Weighing each pixel by its brightness above the blob's surroundings
    (the median of the window's rim) rather than above the detection level
    weighs an edge pixel by how much of it the marker covers: a threshold
    there would pull the centroid towards the pixel grid by a few hundredths
    of a pixel, which is 1e-4 rad over a hundred pixels.  Three times the
    rim's noise is taken off so that the noise of the ground weighs nothing.
    """
    x0, y0 = max(x - MARGIN_PX, 0), max(y - MARGIN_PX, 0)
    x1, y1 = min(x + w + MARGIN_PX, gray.shape[1]), min(y + h + MARGIN_PX, gray.shape[0])
    patch = gray[y0:y1, x0:x1].astype(float)
    rim = np.r_[patch[0], patch[-1], patch[1:-1, 0], patch[1:-1, -1]]
    ground = np.median(rim)
    noise = 1.4826 * np.median(np.abs(rim - ground))
    weight = np.clip(patch - ground - 3 * noise, 0.0, None)
    total = weight.sum()
    cx = (weight.sum(axis=0) @ np.arange(x0, x1)) / total
    cy = (weight.sum(axis=1) @ np.arange(y0, y1)) / total
    return float(cx), float(cy)


def link_markers(blobs: list[np.ndarray], areas: list[np.ndarray], path: str | Path) -> tuple[np.ndarray, float]:
    """The four markers' positions in every frame from the blobs found in each.

    The first frame with exactly four blobs sets the markers; before it
    they are lost.  Each marker is predicted at constant velocity from its
    last two positions and takes the nearest blob within
    :data:`REACH_DIAMETERS`, the closest pairs first.

    Returns
    -------
    centroids : ndarray (N, 4, 2)
        Positions [pixels], NaN where a marker was lost.
    diameter : float
        Median diameter of the markers [pixels].

    Raises
    ------
    RawFormatError
        No frame with four markers; two markers that meet (closer than
        :data:`MEET_DIAMETERS` diameters: they may swap or merge).
    """
    counts = np.array([len(b) for b in blobs])
    four = np.flatnonzero(counts == 4)
    if not four.size:
        most = int(counts.max(initial=0))
        if most < 4:
            raise RawFormatError(path, None, f"fewer than four markers found (at most {most} in a frame)")
        raise RawFormatError(
            path, None, f"no frame shows exactly four markers ({most} bright blobs): something else is as bright"
        )
    first = int(four[0])
    diameter = float(2 * np.sqrt(np.median(areas[first]) / np.pi))
    reach, meet = REACH_DIAMETERS * diameter, MEET_DIAMETERS * diameter
    out = np.full((len(blobs), 4, 2), np.nan)
    out[first] = blobs[first]
    last = blobs[first].copy()
    before = blobs[first].copy()
    for f in range(first + 1, len(blobs)):
        pred = 2 * last - before
        found = blobs[f]
        if len(found):
            dist = np.linalg.norm(pred[:, None, :] - found[None, :, :], axis=2)
            order = np.argsort(dist, axis=None)
            taken_m, taken_b = np.zeros(4, bool), np.zeros(len(found), bool)
            for k in order[dist.ravel()[order] < reach]:
                m, b = divmod(int(k), len(found))
                if not (taken_m[m] or taken_b[b]):
                    out[f, m] = found[b]
                    taken_m[m] = taken_b[b] = True
        seen = ~np.isnan(out[f, :, 0])
        # a marker not seen is predicted still: its velocity is unknown across the gap
        before = last
        last = np.where(seen[:, None], out[f], last)
        gap = np.linalg.norm(last[:, None, :] - last[None, :, :], axis=2)
        gap[np.diag_indices(4)] = np.inf
        if gap.min() < meet:
            raise RawFormatError(
                path,
                None,
                f"two markers meet in frame {f} ({gap.min():.1f} pixels apart, {diameter:.1f} across):"
                " they may swap or merge",
            )
    return out, diameter


def marker_roles(centroids: np.ndarray, path: str | Path) -> np.ndarray:
    """The order that puts the markers as :data:`MARKERS`: the two that move least are the post's.

    Raises
    ------
    RawFormatError
        When the wall's markers do not move :data:`ROLE_CONTRAST` times more than the post's.
    """
    motion = np.nansum(np.nanstd(centroids, axis=0), axis=1)
    by_motion = np.argsort(motion)
    post, wall = by_motion[:2], by_motion[2:]
    if not motion[wall].min() > ROLE_CONTRAST * max(motion[post].max(), 1e-3):
        raise RawFormatError(path, None, "no marker moves more than the others: the wall's markers are not found")
    first = np.flatnonzero(np.isfinite(centroids[:, :, 0]).all(axis=1))[0]
    y = centroids[first, :, 1]
    # image y grows downwards: the lower marker has the larger y
    return np.r_[sorted(wall, key=lambda m: -y[m]), sorted(post, key=lambda m: -y[m])]


def theta_from_markers(centroids: np.ndarray) -> np.ndarray:
    """Angle from the post's line to the wall's [rad], positive as the wall's top moves right.

    Parameters
    ----------
    centroids : ndarray (N, 4, 2)
        Positions of :data:`MARKERS` (x right, y down) [pixels].
    """
    wall = centroids[:, 1] - centroids[:, 0]
    post = centroids[:, 3] - centroids[:, 2]
    # y up: flip the image's y
    wx, wy, px, py = wall[:, 0], -wall[:, 1], post[:, 0], -post[:, 1]
    return np.arctan2(wx * py - wy * px, wx * px + wy * py)


def track_video(path: str | Path, progress: bool | None = None) -> Tracking:
    """Track the four markers of a filmed test in every frame, and theta (module docstring).

    Parameters
    ----------
    path : path-like
        The video (any container and codec OpenCV reads).
    progress : bool, optional
        Show a progress bar; by default on a terminal for a video of more
        than :data:`PROGRESS_FRAMES` frames.

    Raises
    ------
    RawFormatError
        Naming the file: not a video that can be decoded, no frame rate,
        fewer than four markers, markers that meet, nothing that moves.
    """
    import cv2
    from tqdm import tqdm

    path = Path(path)
    cap = cv2.VideoCapture(str(path))
    try:
        if not cap.isOpened():
            raise RawFormatError(path, None, "not a video that can be decoded (truncated or corrupt?)")
        fs = float(cap.get(cv2.CAP_PROP_FPS))
        if not (np.isfinite(fs) and fs > 0):
            raise RawFormatError(path, None, "no frame rate in the container: the sampling rate is unknown")
        hint = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
        show = hint > PROGRESS_FRAMES if progress is None else progress
        blobs, areas = [], []
        with tqdm(total=hint or None, unit="frame", desc=path.name, disable=not show or None) as bar:
            while True:
                ok, frame = cap.read()
                if not ok:
                    break
                gray = frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
                c, a = find_markers(gray)
                blobs.append(c)
                areas.append(a)
                bar.update()
    finally:
        cap.release()
    if len(blobs) < 2:
        raise RawFormatError(path, None, f"{len(blobs)} frame(s) decoded: not a record")
    raw, diameter = link_markers(blobs, areas, path)
    centroids = raw[:, marker_roles(raw, path)]
    theta = theta_from_markers(centroids)
    tracked = np.isfinite(theta)
    rest = theta[-max(int(REST_S * fs), 10) :]
    rest = rest[np.isfinite(rest)]
    noise = float(1.4826 * np.median(np.abs(rest - np.median(rest)))) if rest.size >= 5 else np.nan
    time = np.arange(len(theta)) / fs
    return Tracking(time, theta, centroids, fs, int(tracked.sum()), noise, diameter)


def first_frame(path: str | Path) -> np.ndarray:
    """The first frame of a video in grey levels, (H, W) uint8.

    Raises
    ------
    RawFormatError
        When no frame can be decoded.
    """
    import cv2

    cap = cv2.VideoCapture(str(path))
    try:
        ok, frame = cap.read()
    finally:
        cap.release()
    if not ok:
        raise RawFormatError(path, None, "not a video that can be decoded (truncated or corrupt?)")
    return frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
