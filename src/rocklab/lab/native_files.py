"""Readers of the native files of the lab's instruments: TDMS, C3D and video (``docs/raw-format.md``).

The ``file`` column of ``tests.csv`` may name what an instrument wrote
rather than a text record; its extension says what it is
(:data:`NATIVE_READERS`, looked up by :func:`native_reader`).  Each reader
gives the record of today's text reader of the same instrument, so that the
reduction and everything downstream run unchanged:

* ``.tdms`` (LabVIEW, read with npTDMS): the transducers of the test's
  setup, a :class:`~rocklab.lab.records.Record` (:func:`tdms_record`);
* ``.c3d`` (motion capture, read with the ``c3d`` package): theta from the
  wall's two markers, a :class:`~rocklab.lab.records.RotationRecord`
  (:func:`c3d_record`);
* ``.mp4``, ``.avi``, ``.mov`` (a filmed test, OpenCV): theta from the four
  markers tracked in every frame (:mod:`rocklab.lab.video_tracking`), a
  :class:`~rocklab.lab.records.RotationRecord` (:func:`video_record`).

:func:`read_test_file` is the door of every test's file, text or native.
Every reader follows the contract of :data:`rocklab.lab.records.READERS`:
called on a path past :func:`rocklab.lab.records.check_file` (the campaign's
path checks, :func:`rocklab.lab.raw_format.campaign_file`, come before), it
returns the record or raises :class:`~rocklab.lab.raw_format.RawFormatError`
naming the file and what is wrong: a file the library cannot parse (not of
its format, truncated, corrupt) is refused, never a crash.
"""

from __future__ import annotations

import hashlib
import warnings
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np

from rocklab.lab import marker_frame
from rocklab.lab.raw_format import RawFormatError
from rocklab.lab.records import InertialRecord, Record, RotationRecord, check_file, read_any_record

#: The group of a TDMS file that holds the transducers, one channel ``ch<n>`` each.
TDMS_GROUP = "displacements"
#: The unit of a TDMS channel (``unit_string``) when it gives one.
TDMS_UNIT = "mm"
#: The labels of the wall's two markers in a C3D file, lower then upper (trailing blanks ignored).
C3D_WALL_MARKERS = ("WALL_LO", "WALL_HI")
#: The label prefix of a marker on the fixed frame in a C3D file (:mod:`rocklab.lab.marker_frame`).
C3D_FRAME_PREFIX = "FRAME_"
#: The extensions of a filmed test.
VIDEO_SUFFIXES = (".mp4", ".avi", ".mov")


def file_sha256(path: Path) -> str:
    """Hash of a file as stored (provenance), read in blocks: a video may be large."""
    digest = hashlib.sha256()
    with path.open("rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _header(expected_test_id: str | None, record: str, source: str) -> dict[str, str]:
    """The ``# key: value`` header a text record of the same instrument would carry."""
    head = {"record": record, "source": source}
    if expected_test_id is not None:
        head["test_id"] = expected_test_id
    return head


#: What a TDMS file starts with: the tag of its first segment's lead-in.
TDMS_TAG = b"TDSm"
#: The second byte of a C3D file: the key of its header (ObsPy-style sniffing, not a parser).
C3D_KEY = 0x50


def _is_tdms(path: Path) -> bool:
    """Whether the file starts as a TDMS file does (npTDMS reads any other bytes as an empty file)."""
    with path.open("rb") as fh:
        return fh.read(4) == TDMS_TAG


def _is_c3d(path: Path) -> bool:
    """Whether the file starts as a C3D file does."""
    with path.open("rb") as fh:
        head = fh.read(2)
    return len(head) == 2 and head[1] == C3D_KEY


def tdms_record(path: Path, expected_test_id: str | None = None) -> Record:
    """A transducer record from a LabVIEW TDMS file (``docs/raw-format.md``, "``.tdms``").

    Group :data:`TDMS_GROUP`, one channel ``ch<n>`` per transducer, readings
    in mm, the sampling interval in ``wf_increment`` [s] and the first
    sample's time in ``wf_start_offset`` [s] (0 when absent); NaN is a lost
    sample.  Whether every channel of the setup is there is checked against
    ``setups.csv`` by :func:`check_setup_channels`.

    Raises
    ------
    RawFormatError
        Not a TDMS file (or truncated, corrupt), no group
        :data:`TDMS_GROUP`, no ``ch<n>`` channel, a channel without
        ``wf_increment`` or with another unit than mm, channels of different
        intervals, start times or lengths.
    """
    from nptdms import TdmsFile  # imported here: only campaigns with TDMS files need it

    if not _is_tdms(path):
        raise RawFormatError(path, None, f"not a TDMS file (it does not start with {TDMS_TAG!r})")
    try:
        tdms = TdmsFile.read(path)
        groups = {g.name: g for g in tdms.groups()}
        if TDMS_GROUP not in groups:
            raise RawFormatError(path, None, f"no group {TDMS_GROUP!r} (groups: {', '.join(groups) or 'none'})")
        chans = {c.name: c for c in groups[TDMS_GROUP].channels()}
        data = {name: np.asarray(c[:], float) for name, c in chans.items()}
    except RawFormatError:
        raise
    except Exception as exc:  # npTDMS raises what the broken bytes lead to: the file is refused, never a crash
        raise RawFormatError(path, None, f"not a readable TDMS file ({type(exc).__name__}: {exc})") from None
    names = [n for n in chans if n.startswith("ch") and n[2:].isdigit()]
    if not names:
        raise RawFormatError(path, None, f"group {TDMS_GROUP!r} has no channel ch0, ch1, ... (got {list(chans)})")
    steps, starts = [], []
    for name in names:
        props = chans[name].properties
        if "wf_increment" not in props:
            raise RawFormatError(path, None, f"channel {name} has no wf_increment (the sampling interval, s)")
        unit = str(props.get("unit_string", TDMS_UNIT)).strip()
        if unit != TDMS_UNIT:
            raise RawFormatError(path, None, f"channel {name} in {unit!r}: the transducers are read in mm")
        steps.append(float(props["wf_increment"]))
        starts.append(float(props.get("wf_start_offset", 0.0)))
    dt = steps[0]
    if not (np.isfinite(dt) and dt > 0):
        raise RawFormatError(path, None, f"wf_increment {dt!r} is not a positive interval (s)")
    if any(s != dt for s in steps) or any(s != starts[0] for s in starts):
        raise RawFormatError(path, None, "the channels differ in wf_increment or wf_start_offset")
    lengths = {len(data[n]) for n in names}
    if len(lengths) != 1:
        raise RawFormatError(path, None, f"channels of different lengths {sorted(lengths)} (a truncated file?)")
    n = lengths.pop()
    if n < 2:
        raise RawFormatError(path, None, "fewer than two samples")
    readings = np.column_stack([data[name] for name in names])
    if np.isinf(readings).any():
        raise RawFormatError(path, None, "a reading is infinite")
    channels = [int(name[2:]) for name in names]
    if len(set(channels)) != len(channels):
        raise RawFormatError(path, None, "a channel appears twice")
    time = starts[0] + np.arange(n) * dt
    head = {"sampling_rate_hz": f"{1.0 / dt:g}", "units": "s, mm", "source": "tdms"}
    if expected_test_id is not None:
        head["test_id"] = expected_test_id
    return Record(time, readings, channels, 1.0 / dt, head, file_sha256(path), str(path))


def check_setup_channels(rec: Record, setup_channels: Iterable[int]) -> None:
    """Refuse a TDMS record that lacks a transducer of its setup (``docs/raw-format.md``).

    A text record without a column of its setup loses that channel (the
    backup stands in); the TDMS format names every channel of the setup, so
    one missing is a file that is not the setup's.

    Raises
    ------
    RawFormatError
        Naming the file and the channels missing.
    """
    if rec.header.get("source") != "tdms":
        return
    missing = sorted(set(int(c) for c in setup_channels) - set(rec.channels))
    if missing:
        names = ", ".join(f"ch{c}" for c in missing)
        raise RawFormatError(rec.path, None, f"no channel {names} of the setup in group {TDMS_GROUP!r}")


def c3d_record(path: Path, expected_test_id: str | None = None) -> RotationRecord:
    """A rotation record from a motion-capture C3D file (``docs/raw-format.md``, "``.c3d``").

    theta is the angle of the line from ``WALL_LO`` to ``WALL_HI`` in the
    lab's Y-Z plane, zero when vertical, positive as the top moves towards
    +Y; a frame in which either marker's residual is negative (the C3D
    convention of a lost marker) is a lost sample, bridged or not by
    :func:`rocklab.lab.rotation.rotation_motion` as in a text rotation record.
    Two markers on a vertical line see no twist nor sliding: the record has
    theta only.  ``FRAME_*`` markers, where the file has them, must not move:
    a motion of theirs beyond noise (the cameras drifting) is removed from the
    wall's markers first, and ``attrs`` gives it and the wall markers' rigid
    length for ``qc.csv`` (:mod:`rocklab.lab.marker_frame`).

    Raises
    ------
    RawFormatError
        Not a C3D file (or truncated, corrupt), no point rate, no
        ``WALL_LO`` or ``WALL_HI`` marker, fewer frames than the header says.
    """
    import c3d  # imported here: only campaigns with C3D files need it

    if not _is_c3d(path):
        raise RawFormatError(path, None, "not a C3D file (its header's key is not 0x50)")
    try:
        with path.open("rb") as fh, warnings.catch_warnings():
            # a file without analog channels is usual for motion capture
            warnings.simplefilter("ignore")
            reader = c3d.Reader(fh)
            labels = [str(label).strip() for label in reader.point_labels]
            rate = float(reader.point_rate)
            expected = int(reader.last_frame) - int(reader.first_frame) + 1
            frames = [points[:, :4].copy() for _, points, _ in reader.read_frames(copy=False)]
    except Exception as exc:  # the c3d package raises what the broken bytes lead to: refused, never a crash
        raise RawFormatError(path, None, f"not a readable C3D file ({type(exc).__name__}: {exc})") from None
    missing = [m for m in C3D_WALL_MARKERS if m not in labels]
    if missing:
        raise RawFormatError(
            path, None, f"no marker {' nor '.join(missing)} (the wall's markers; labels: {', '.join(labels) or 'none'})"
        )
    if not (np.isfinite(rate) and rate > 0):
        raise RawFormatError(path, None, f"point rate {rate!r} is not a positive rate (Hz)")
    if len(frames) < max(expected, 2):
        raise RawFormatError(path, None, f"{len(frames)} frames of the {expected} the header gives (truncated?)")
    points = np.stack(frames)  # (frames, markers, x y z residual)
    wall = points[:, [labels.index(m) for m in C3D_WALL_MARKERS]]
    lost = (wall[:, 0, 3] < 0) | (wall[:, 1, 3] < 0)
    if lost.all():
        raise RawFormatError(path, None, "the wall's markers are lost in every frame")
    fixed = [i for i, label in enumerate(labels) if label.startswith(C3D_FRAME_PREFIX)]
    drift = marker_frame.frame_motion(points[:, fixed, :3], points[:, fixed, 3] >= 0, rate) if fixed else None
    lo, hi = (
        marker_frame.remove_frame_motion(wall[..., :3], drift) if drift and drift.named else wall[..., :3]
    ).transpose(1, 0, 2)
    theta = np.arctan2(hi[:, 1] - lo[:, 1], hi[:, 2] - lo[:, 2])
    theta[lost] = np.nan
    length = marker_frame.rigid_length(np.where(lost[:, None], np.nan, lo), hi)
    time = np.arange(len(theta)) / rate
    head = {**_header(expected_test_id, "rotation", "c3d"), "sampling_rate_hz": f"{rate:g}", "units": "s, rad"}
    attrs = marker_frame.qc_values(drift, length)
    return RotationRecord(time, {"theta": theta}, rate, head, file_sha256(path), str(path), attrs)


def video_record(path: Path, expected_test_id: str | None = None) -> RotationRecord:
    """A rotation record from a filmed test (``docs/raw-format.md``, "``.mp4``, ``.avi``, ``.mov``").

    The four markers tracked in every frame, theta the angle between the
    wall's and the post's marker lines, the container's frame rate the
    sampling rate (:func:`rocklab.lab.video_tracking.track_video`); a frame
    in which a marker is lost is a lost sample.  ``attrs`` carries the
    frames tracked and the tracking noise for ``qc.csv``.

    Raises
    ------
    RawFormatError
        As :func:`rocklab.lab.video_tracking.track_video`.
    """
    from rocklab.lab.video_tracking import track_video  # imported here: OpenCV costs a start-up

    tr = track_video(path)
    head = {**_header(expected_test_id, "rotation", "video"), "sampling_rate_hz": f"{tr.fs:g}", "units": "s, rad"}
    attrs = {"frames_tracked": tr.frames_tracked, "tracking_noise_rad": tr.noise_rad}
    return RotationRecord(tr.time, {"theta": tr.theta}, tr.fs, head, file_sha256(path), str(path), attrs)


#: The reader of each native file, by its extension (lower case).
NATIVE_READERS: dict[str, Callable[[Path, str | None], Record | RotationRecord]] = {
    ".tdms": tdms_record,
    ".c3d": c3d_record,
    **dict.fromkeys(VIDEO_SUFFIXES, video_record),
}


def native_reader(path: str | Path) -> Callable[[Path, str | None], Record | RotationRecord] | None:
    """The reader of a native file by its extension (any case), None for a text record."""
    return NATIVE_READERS.get(Path(path).suffix.lower())


def read_test_file(path: str | Path, expected_test_id: str | None = None) -> Record | RotationRecord | InertialRecord:
    """Read one test's file, the door of every record: a native file by its extension
    (:func:`native_reader`), a text record of any kind otherwise
    (:func:`rocklab.lab.records.read_any_record`).

    Raises
    ------
    RawFormatError
        Naming the file and the problem (and the line, in a text record).
    """
    native = native_reader(path)
    if native is None:
        return read_any_record(path, expected_test_id)
    return native(check_file(path), expected_test_id)
