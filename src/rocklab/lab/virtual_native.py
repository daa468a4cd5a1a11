"""Virtual native files: a wall motion as LabVIEW's TDMS, a motion-capture C3D and a filmed video.

From the same true motion as the text records of
:mod:`rocklab.lab.virtual_record` and :mod:`rocklab.lab.virtual_instruments`
(the hold, the release, the free rocking and the rest of
:func:`rocklab.lab.virtual_record.record_from_motion`), the files the lab's
instruments write (``docs/raw-format.md``, "Native files of the
instruments"), each by the real library, so that the readers of
:mod:`rocklab.lab.native_files` are tested on what the instruments write:

* :func:`write_tdms`: the transducer readings as a TDMS file (npTDMS);
* :func:`write_c3d`: the wall's two markers (and up to three on the frame) as
  a C3D file (the ``c3d`` package), with marker noise, occlusions and the
  cameras' drift (:class:`MarkerEffects`);
* :func:`write_video`: a rendered film of the wall's end face and a plumb
  post, four bright markers, at any frame rate, with noise, motion blur, a
  tilted camera and markers hidden for a few frames
  (:class:`VideoEffects`), encoded by OpenCV.

Lengths in mm, rotations in rad, time in s.  Everything random comes from
the generator given.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from rocklab.lab.kinematics import lab_points
from rocklab.lab.native_files import C3D_WALL_MARKERS, TDMS_GROUP, TDMS_UNIT
from rocklab.lab.virtual_instruments import occluded

#: Heights of the wall's two markers (lower, upper) as fractions of the wall's height.
MARKER_HEIGHTS = (0.25, 0.9)
#: Where the frame markers are: (y from the wall's -y face [mm], z / h), FRAME_1 first.
FRAME_POINTS = ((-300.0, 0.5), (-300.0, 0.1), (-500.0, 0.95))
#: The video containers and the codec OpenCV writes each with.
CODECS = {".mp4": "mp4v", ".avi": "MJPG", ".mov": "mp4v"}


@dataclass(frozen=True)
class MarkerEffects:
    """What a motion-capture system does to its markers.

    Attributes
    ----------
    noise_mm : float
        Standard deviation of each coordinate's white noise [mm].
    occlusions : int
        Stretches in which a wall marker is lost (negative residual).
    max_occlusion_s : float
        Longest stretch lost [s] (each from one frame to this).
    frame_markers : int
        Markers on the fixed frame, ``FRAME_1`` ... (:data:`FRAME_POINTS`, at most three).
    frame_drift_rad : float
        Rotation of the cameras' coordinates about X reached at the end of the
        record, growing linearly from 0 at the start (a drifting system) [rad].
    frame_shift_mm : float
        Their translation along Y reached at the end, likewise [mm].
    """

    noise_mm: float = 0.03
    occlusions: int = 4
    max_occlusion_s: float = 0.08
    frame_markers: int = 1
    frame_drift_rad: float = 0.0
    frame_shift_mm: float = 0.0


@dataclass(frozen=True)
class VideoEffects:
    """How a filmed test looks: the frame, the markers and what the camera does to them.

    Attributes
    ----------
    height_px, width_px : int
        Frame size [pixels]; the wall's height fills 0.85 of the frame's.
    marker_px : float
        Diameter of the markers [pixels] (at least 6, the spec's).
    psf_px : float
        Standard deviation of the lens' blur (its point spread, Gaussian) [pixels].
    noise : float
        Standard deviation of the sensor's white noise [grey levels of 255].
    exposure : float
        Exposure over the frame period: the motion blur (0 is sharp).
    tilt_deg : float
        Roll of the camera [degrees]: its image is not level.
    occlusions : int
        Stretches in which a wall marker is hidden (a hand, a shadow).
    max_occlusion_s : float
        Longest stretch hidden [s].
    extension : str
        Container: ``.mp4``, ``.avi`` or ``.mov``.
    codec : str or None
        FourCC of the codec; None: the container's of :data:`CODECS`
        (``FFV1`` in ``.avi``: lossless, a film without compression's errors).
    """

    height_px: int = 320
    width_px: int = 240
    marker_px: float = 8.0
    psf_px: float = 0.8
    noise: float = 2.0
    exposure: float = 0.5
    tilt_deg: float = 2.0
    occlusions: int = 2
    max_occlusion_s: float = 0.03
    extension: str = ".mp4"
    codec: str | None = None


#: The film of the benchmarks: a phone's slow motion cropped to 480 x 360 pixels, markers 10 pixels across.
BENCH_FILM = VideoEffects(height_px=480, width_px=360, marker_px=10.0)


def _truncate(path: Path) -> None:
    """Cut a written file in the middle: a broken transfer."""
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def write_tdms(
    path: str | Path, t: np.ndarray, readings: np.ndarray, channels: list[int], unreadable: bool = False
) -> None:
    """Write transducer readings [mm] as LabVIEW does (``docs/raw-format.md``, "``.tdms``").

    Group :data:`~rocklab.lab.native_files.TDMS_GROUP`, one channel
    ``ch<n>`` each, ``unit_string`` mm, ``wf_increment`` and
    ``wf_start_offset`` [s]; NaN for lost samples.  With ``unreadable`` the
    file is cut in the middle.
    """
    from nptdms import ChannelObject, TdmsWriter

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    props = {"unit_string": TDMS_UNIT, "wf_increment": float(t[1] - t[0]), "wf_start_offset": float(t[0])}
    objects = [
        ChannelObject(TDMS_GROUP, f"ch{c}", np.ascontiguousarray(readings[:, j], float), properties=props)
        for j, c in enumerate(channels)
    ]
    with TdmsWriter(str(path)) as writer:
        writer.write_segment(objects)
    if unreadable:
        _truncate(path)


def marker_points(specimen: Any) -> np.ndarray:
    """The wall's two markers on its end face x = L/2, on its mid-plane (body frame) [mm], (2, 3)."""
    L, h = float(specimen["length_mm"]), float(specimen["height_mm"])
    return np.array([[L / 2, 0.0, f * h] for f in MARKER_HEIGHTS])


def write_c3d(
    path: str | Path,
    fs: float,
    theta: ArrayLike,
    phi: ArrayLike,
    v: ArrayLike,
    w: ArrayLike,
    specimen: Any,
    effects: MarkerEffects = MarkerEffects(),
    rng: np.random.Generator | int | None = None,
    unreadable: bool = False,
) -> None:
    """Write the markers of a motion as a motion-capture system does (``docs/raw-format.md``, "``.c3d``").

    ``WALL_LO`` and ``WALL_HI`` at :func:`marker_points`, moved by the
    motion, and ``effects.frame_markers`` ``FRAME_<k>`` fixed beside the wall
    (:data:`FRAME_POINTS`), in the lab frame [mm] at the point rate ``fs``,
    with white noise, all of them seen by cameras whose coordinates drift as
    ``effects`` says; a lost marker has residual -1.
    """
    import c3d

    rng = np.random.default_rng(rng)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    b, h = float(specimen["thickness_mm"]), float(specimen["height_mm"])
    wall = lab_points(theta, phi, v, w, marker_points(specimen), b)
    n = wall.shape[0]
    fixed = [[float(specimen["length_mm"]) / 2, -b / 2 + dy, f * h] for dy, f in FRAME_POINTS[: effects.frame_markers]]
    frame = np.broadcast_to(np.reshape(fixed, (1, -1, 3)), (n, len(fixed), 3))
    pts = np.concatenate([wall, frame], axis=1)
    # the cameras' coordinates drift: every point alike, a rotation about X and a shift along Y
    ramp = np.arange(n) / max(n - 1, 1)
    c, s = np.cos(effects.frame_drift_rad * ramp)[:, None], np.sin(effects.frame_drift_rad * ramp)[:, None]
    y, z = pts[..., 1].copy(), pts[..., 2].copy()
    pts[..., 1], pts[..., 2] = c * y - s * z + effects.frame_shift_mm * ramp[:, None], s * y + c * z
    k_all = pts.shape[1]
    pts = pts + rng.normal(0.0, effects.noise_mm, (n, k_all, 3))
    residual = np.full((n, k_all, 1), 0.5)
    for k, count in enumerate(((effects.occlusions + 1) // 2, effects.occlusions // 2)):
        residual[occluded(n, fs, count, effects.max_occlusion_s, rng), k] = -1.0
    cameras = np.zeros((n, k_all, 1))
    points = np.concatenate([pts, residual, cameras], axis=2).astype(np.float32)
    writer = c3d.Writer(point_rate=float(fs), analog_rate=float(fs))
    no_analog = np.zeros((0, 0), np.float32)
    writer.add_frames([(p, no_analog) for p in points])
    writer.set_point_labels([*C3D_WALL_MARKERS, *(f"FRAME_{k + 1}" for k in range(len(fixed)))])
    with path.open("wb") as fh, warnings.catch_warnings():
        warnings.simplefilter("ignore")  # no analog channels: usual for motion capture
        writer.write(fh)
    if unreadable:
        _truncate(path)


def _view(specimen: Any, effects: VideoEffects) -> tuple[float, np.ndarray, float]:
    """The camera: pixels per mm, the lab point (Y, Z) at the frame's centre [mm], and its roll [rad]."""
    h = float(specimen["height_mm"])
    scale = 0.85 * effects.height_px / h
    return scale, np.array([-0.12 * h, 0.5 * h]), np.radians(effects.tilt_deg)


def post_points(specimen: Any) -> np.ndarray:
    """The plumb post's two markers in the lab's Y-Z plane, beside the wall on its -y side [mm], (2, 2)."""
    b, h = float(specimen["thickness_mm"]), float(specimen["height_mm"])
    y = -b / 2 - 0.25 * h
    return np.array([[y, 0.2 * h], [y, 0.95 * h]])


def image_points(yz: np.ndarray, specimen: Any, effects: VideoEffects) -> np.ndarray:
    """Image position (x right, y down) [pixels] of lab points (Y, Z) [mm], (..., 2), by the camera of ``effects``.

    +Y is to the right of the image (the wall's top moves right as theta
    grows), +Z up; the camera is rolled by ``effects.tilt_deg``.
    """
    scale, centre, roll = _view(specimen, effects)
    d = (np.asarray(yz, float) - centre) * scale
    c, s = np.cos(roll), np.sin(roll)
    x = c * d[..., 0] - s * d[..., 1]
    y = s * d[..., 0] + c * d[..., 1]
    return np.stack([effects.width_px / 2 + x, effects.height_px / 2 - y], axis=-1)


#: Sub-samples per pixel side with which a marker's coverage of a pixel is measured.
SUPERSAMPLE = 6


def _disc(frame: np.ndarray, centre: np.ndarray, radius: float, level: float) -> None:
    """Add a disc of brightness ``level``, each pixel by the fraction of it the disc covers, in place.

    The fraction is counted on :data:`SUPERSAMPLE` x :data:`SUPERSAMPLE`
    points of each pixel: a cruder edge (a linear ramp of the distance)
    moves the disc's centroid with its position in the pixel by 0.02
    pixels, 1e-4 rad over the markers' spacing.
    """
    x0, y0 = int(np.floor(centre[0] - radius - 1)), int(np.floor(centre[1] - radius - 1))
    x1, y1 = int(np.ceil(centre[0] + radius + 2)), int(np.ceil(centre[1] + radius + 2))
    x0, y0 = max(x0, 0), max(y0, 0)
    x1, y1 = min(x1, frame.shape[1]), min(y1, frame.shape[0])
    if x1 <= x0 or y1 <= y0:
        return
    k = SUPERSAMPLE
    sub = (np.arange(k) + 0.5) / k - 0.5
    xs = (np.arange(x0, x1)[:, None] + sub).ravel() - centre[0]
    ys = (np.arange(y0, y1)[:, None] + sub).ravel() - centre[1]
    inside = (ys[:, None] ** 2 + xs[None, :] ** 2) <= radius**2
    cover = inside.reshape(y1 - y0, k, x1 - x0, k).mean(axis=(1, 3))
    frame[y0:y1, x0:x1] += level * cover


def _bar(frame: np.ndarray, p0: np.ndarray, p1: np.ndarray, width: float, level: float) -> None:
    """Add a straight bar of ``width`` [pixels] from p0 to p1, its edges weighted by coverage (sub-pixel), in place."""
    yy, xx = np.mgrid[0 : frame.shape[0], 0 : frame.shape[1]]
    axis = (p1 - p0) / np.linalg.norm(p1 - p0)
    along = (xx - p0[0]) * axis[0] + (yy - p0[1]) * axis[1]
    across = np.abs((xx - p0[0]) * axis[1] - (yy - p0[1]) * axis[0])
    inside = (along >= 0) & (along <= np.linalg.norm(p1 - p0))
    frame += level * inside * np.clip(width / 2 + 0.5 - across, 0.0, 1.0)


def render_frames(
    fs: float,
    theta: ArrayLike,
    w: ArrayLike,
    specimen: Any,
    effects: VideoEffects = VideoEffects(),
    rng: np.random.Generator | int | None = None,
) -> tuple[Iterator[np.ndarray], np.ndarray]:
    """Frames of a filmed test, one per sample, and which wall marker was hidden in each.

    The ground dark, the wall's end face and the post a little lighter, the
    four markers bright discs; each frame averages the scene over the
    exposure (motion blur, sub-frames at the motion's own samples
    interpolated), seen through the lens' blur, plus white noise.

    Returns
    -------
    frames : iterator of ndarray (H, W) of uint8
        Rendered one at a time: a long film does not fit in memory.
    hidden : ndarray (N, 2) of bool
        The lower and upper wall markers hidden.
    """
    import cv2

    rng = np.random.default_rng(rng)
    theta, w = np.asarray(theta, float), np.asarray(w, float)
    n = theta.size
    b, h = float(specimen["thickness_mm"]), float(specimen["height_mm"])
    X = marker_points(specimen)
    face = np.array([[0.0, -b / 2, 0.0], [0.0, b / 2, 0.0], [0.0, b / 2, h], [0.0, -b / 2, h]])
    post = post_points(specimen)
    hidden = np.column_stack([occluded(n, fs, effects.occlusions, effects.max_occlusion_s, rng) for _ in range(2)])
    shape = (effects.height_px, effects.width_px)
    still = np.full(shape, 20.0, np.float32)
    post_px = image_points(np.array([[post[0, 0], 0.0], [post[0, 0], h]]), specimen, effects)
    _bar(still, post_px[0], post_px[1], effects.marker_px, 25.0)
    for p in image_points(post, specimen, effects):
        _disc(still, p, effects.marker_px / 2, 210.0)
    n_sub = 4 if effects.exposure > 0 else 1
    # sub-frames over the exposure, the motion interpolated between its samples
    lag = np.linspace(-effects.exposure, 0.0, n_sub) if n_sub > 1 else np.zeros(1)
    idx = np.arange(n)[:, None] + lag[None, :]
    th_sub = np.interp(idx, np.arange(n), theta)
    w_sub = np.interp(idx, np.arange(n), w)
    zeros = np.zeros(th_sub.size)
    walls = lab_points(th_sub.ravel(), zeros, zeros, w_sub.ravel(), X, b)[..., 1:].reshape(n, n_sub, 2, 2)
    faces = lab_points(th_sub.ravel(), zeros, zeros, w_sub.ravel(), face, b)[..., 1:].reshape(n, n_sub, 4, 2)
    walls_px, faces_px = image_points(walls, specimen, effects), image_points(faces, specimen, effects)
    bank = rng.normal(0.0, effects.noise, (16, *shape)).astype(np.float32)
    pick = rng.integers(16, size=n)

    def frames() -> Iterator[np.ndarray]:
        for i in range(n):
            frame = np.zeros(shape, np.float32)
            for k in range(n_sub):
                sub = still.copy()
                cv2.fillPoly(sub, [np.round(faces_px[i, k] * 16).astype(np.int32)], 40.0, cv2.LINE_AA, shift=4)
                for m in range(2):
                    if not hidden[i, m]:
                        _disc(sub, walls_px[i, k, m], effects.marker_px / 2, 180.0)
                frame += sub
            seen = cv2.GaussianBlur(frame, (0, 0), effects.psf_px) if effects.psf_px > 0 else frame
            yield np.clip(np.round(seen / n_sub + bank[pick[i]]), 0, 255).astype(np.uint8)

    return frames(), hidden


def write_video(
    path: str | Path,
    fs: float,
    theta: ArrayLike,
    w: ArrayLike,
    specimen: Any,
    effects: VideoEffects = VideoEffects(),
    rng: np.random.Generator | int | None = None,
    unreadable: bool = False,
) -> np.ndarray:
    """Film a motion (:func:`render_frames`) and encode it with OpenCV at the frame rate ``fs``.

    Returns
    -------
    ndarray (N, 2) of bool
        The wall markers hidden in each frame.
    """
    import cv2

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    frames, hidden = render_frames(fs, theta, w, specimen, effects, rng)
    codec = effects.codec or CODECS[path.suffix.lower()]
    size = (effects.width_px, effects.height_px)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*codec), float(fs), size, False)
    try:
        for frame in frames:
            writer.write(frame)
    finally:
        writer.release()
    if unreadable:
        _truncate(path)
    return hidden
