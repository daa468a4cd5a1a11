"""Readers of one test's record in the lab's raw format (``docs/raw-format.md``), of each kind.

A record is ``tests/<id>.csv.gz`` (plain ``.csv`` too): ``# key: value``
header lines (``sampling_rate_hz``, ``test_id``, ``units``, and ``record``
for the instruments other than transducers), a header row and one row per
sample.  Three kinds (:data:`RECORD_KINDS`): transducer readings [mm]
(``time_s,ch0,ch1,...``, :func:`read_record`), rotations of the wall
(``# record: rotation``, :func:`rotation_record`) and a gyroscope with an
accelerometer (``# record: inertial``, :func:`inertial_record`).  The door
checks are one for all kinds (:func:`read_text`, :func:`check_header`,
:func:`read_rows`): every problem is a
:class:`~rocklab.lab.raw_format.RawFormatError` naming the file and the
line.  The campaign's tables are read by :mod:`rocklab.lab.campaign`.
"""

from __future__ import annotations

import gzip
import hashlib
import io
import re
import zlib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rocklab.lab.raw_format import CONTROL, RawFormatError, holds_any

#: Relative tolerance between the declared sampling rate and the time column.
RATE_TOLERANCE = 1e-3
#: The ``# units:`` of a record: time in seconds, readings in mm.
UNITS = ("s", "mm")


@dataclass
class Record:
    """One test's transducer record, as read, in mm.

    Attributes
    ----------
    time : ndarray (N,)
        Time [s].
    readings : ndarray (N, nch)
        Elongation of each channel [mm]; NaN where the acquisition lost the sample.
    channels : list of int
        Channel numbers, in column order.
    fs : float
        Sampling rate [Hz] from the header (checked against the time column).
    header : dict
        The ``# key: value`` comment lines.
    sha256 : str
        Hash of the file as stored (provenance).
    """

    time: np.ndarray
    readings: np.ndarray
    channels: list[int]
    fs: float
    header: dict[str, str]
    sha256: str
    path: str


def _decompress(path: Path) -> tuple[str, str]:
    blob = path.read_bytes()
    digest = hashlib.sha256(blob).hexdigest()
    try:
        text = gzip.decompress(blob).decode("utf-8") if path.suffix == ".gz" else blob.decode("utf-8")
    except (EOFError, zlib.error, gzip.BadGzipFile) as exc:
        raise RawFormatError(path, None, f"truncated or corrupt gzip stream ({exc})") from None
    except UnicodeDecodeError as exc:
        raise RawFormatError(path, None, f"not UTF-8 text ({exc})") from None
    return text, digest


#: Text that can only hold decimal numbers and separators: no ``nan``, ``inf``, hex or word.
PLAIN_NUMBERS = re.compile(r"[^0-9.eE+\-,\s]")


def _numbers(body: str, columns: list[str], path: Path, first_data: int) -> np.ndarray:
    """The data rows as finite floats, NaN where a field is empty.

    Parsed as floats by pandas' C reader when the text holds plain decimal
    numbers only (a record of the lab: ten times faster); anything else, or
    a field that reader refuses or makes infinite, goes field by field
    through ``pandas.to_numeric``, which also names the first field that is
    not a (finite) number.  Both read a number as Python's ``float`` does
    (tests/test_campaign.py).
    """
    if not holds_any(PLAIN_NUMBERS, body):
        try:
            values = pd.read_csv(
                io.StringIO(body), header=None, names=columns, dtype=float, na_values=[""], keep_default_na=False
            )
        except ValueError:  # a malformed number: found and named below
            pass
        else:
            data = values.to_numpy(float)
            if not np.isinf(data).any():
                return data
    table = pd.read_csv(io.StringIO(body), header=None, names=columns, dtype=str, keep_default_na=False)
    fields = table.apply(lambda s: s.str.strip())
    values = fields.apply(lambda s: pd.to_numeric(s.replace("", np.nan), errors="coerce"))
    nonnum = (values.isna() & fields.ne("")).to_numpy()
    if nonnum.any():
        i, j = np.argwhere(nonnum)[0]
        raise RawFormatError(path, first_data + int(i), f"{columns[j]}: {table.iat[i, j]!r} is not a number")
    data = values.to_numpy(float)
    infinite = np.isinf(data)
    if infinite.any():
        i, j = np.argwhere(infinite)[0]
        raise RawFormatError(path, first_data + int(i), f"{columns[j]}: {table.iat[i, j]!r} is not a finite number")
    return data


@dataclass
class RecordText:
    """A record past the door checks that every kind shares, before its columns are read.

    Attributes
    ----------
    path : Path
    lines : list of str
        The decoded lines (byte-order mark removed).
    header : dict
        The ``# key: value`` comment lines.
    n_comment : int
        Number of comment lines (the header row is the next line).
    sha256 : str
        Hash of the file as stored.
    """

    path: Path
    lines: list[str]
    header: dict[str, str]
    n_comment: int
    sha256: str

    @property
    def kind(self) -> str:
        """The record's kind (:data:`RECORD_KINDS`): its ``# record:`` line, transducers without one."""
        return self.header.get("record", TRANSDUCERS)

    def error(self, problem: str) -> RawFormatError:
        """A :class:`RawFormatError` of the header (line 1, where it starts)."""
        return RawFormatError(self.path, 1, problem)


#: The kind of a record without a ``# record:`` line.
TRANSDUCERS = "transducers"
#: The kinds of record of the lab's format (``docs/raw-format.md``): the ``# record:`` values, and the default.
RECORD_KINDS = (TRANSDUCERS, "rotation", "inertial")


def check_file(path: str | Path) -> Path:
    """The first door check of every record, text or native: ``path`` is a regular file.

    Raises
    ------
    RawFormatError
        Naming the file: not found, or not a regular file.
    """
    path = Path(path)
    if not path.exists():
        raise RawFormatError(path, None, "file not found")
    if not path.is_file():
        raise RawFormatError(path, None, "not a regular file")
    return path


def read_text(path: str | Path) -> RecordText:
    """The door checks of every record: a regular file, whole gzip (or plain) UTF-8 text
    without control characters, its ``#`` header, and a known ``# record:`` kind.

    Raises
    ------
    RawFormatError
        Naming the file and, where there is one, the line.
    """
    path = check_file(path)
    text, digest = _decompress(path)
    # a byte-order mark and CRLF line ends are harmless
    lines = text.removeprefix("\ufeff").splitlines()
    # line by line only when the text holds one (a CR of CRLF does, and ends a line)
    bad = None
    if holds_any(CONTROL, text):
        bad = next((n for n, ln in enumerate(lines, start=1) if CONTROL.search(ln)), None)
    if bad is not None:
        raise RawFormatError(path, bad, "a control character in the line")
    header, n_comment = {}, 0
    for line in lines:
        if not line.startswith("#"):
            break
        n_comment += 1
        key, sep, value = line[1:].partition(":")
        if sep:
            header[key.strip()] = value.strip()
    if n_comment >= len(lines):
        raise RawFormatError(path, n_comment + 1, "no header row and no data")
    rec = RecordText(path, lines, header, n_comment, digest)
    if rec.kind not in RECORD_KINDS[1:] and "record" in header:
        raise rec.error(f"record {header['record']!r} is not one of {', '.join(RECORD_KINDS[1:])} (none: transducers)")
    return rec


def check_header(
    rec: RecordText, expected_test_id: str | None, units: tuple[str, ...], required: tuple[str, ...] = ()
) -> float:
    """The sampling rate [Hz] of a record, its header checked.

    The keys ``required`` are there, ``sampling_rate_hz`` is a positive
    number, ``test_id`` (when given) is the log's and ``units`` (the kind's
    ``units`` when absent) are the kind's.

    Raises
    ------
    RawFormatError
        At line 1, where the header starts.
    """
    header, path = rec.header, rec.path
    for key in ("sampling_rate_hz", *required):
        if key not in header:
            raise RawFormatError(path, 1, f"missing '# {key}:' header line")
    try:
        fs = float(header["sampling_rate_hz"])
    except ValueError:
        raise rec.error(f"sampling_rate_hz {header['sampling_rate_hz']!r} is not a number") from None
    if not fs > 0 or not np.isfinite(fs):
        raise rec.error("sampling_rate_hz must be positive")
    if expected_test_id is not None and header.get("test_id", expected_test_id) != expected_test_id:
        raise rec.error(f"header test_id {header['test_id']!r} but tests.csv says {expected_test_id!r}")
    got = tuple(u.strip() for u in header.get("units", ", ".join(units)).split(","))
    if got != units:
        raise rec.error(f"units {header['units']!r}: the format of a {rec.kind} record is {', '.join(units)!r}")
    return fs


def read_rows(rec: RecordText, columns: list[str], fs: float) -> np.ndarray:
    """The data rows of a record under the header row ``columns``, as floats (NaN: empty field).

    Every row has the header's number of fields and only (finite) numbers;
    ``time_s`` is never empty, increases and agrees with ``fs``.

    Raises
    ------
    RawFormatError
        Naming the first row at fault.
    """
    path, lines, n_comment = rec.path, rec.lines, rec.n_comment
    body = lines[n_comment + 1 :]
    first_data = n_comment + 2
    if not body:
        raise RawFormatError(path, first_data, "no data rows")
    ncol = len(columns)
    counts = np.fromiter((ln.count(",") for ln in body), int, len(body))
    bad = np.flatnonzero(counts != ncol - 1)
    if bad.size:
        i = int(bad[0])
        what = "truncated row" if counts[i] < ncol - 1 else "too many fields"
        raise RawFormatError(path, first_data + i, f"{what}: {counts[i] + 1} fields, expected {ncol}")
    data = _numbers("\n".join(body), columns, path, first_data)
    time = data[:, 0]
    if np.isnan(time).any():
        i = int(np.flatnonzero(np.isnan(time))[0])
        raise RawFormatError(path, first_data + i, "empty time_s")
    step = np.diff(time)
    if (step <= 0).any():
        i = int(np.flatnonzero(step <= 0)[0]) + 1
        what = "repeats the previous row's" if step[i - 1] == 0 else "goes back"
        raise RawFormatError(path, first_data + i, f"time_s {time[i]:g} {what} ({time[i - 1]:g}): time must increase")
    if time.size > 1:
        dt = 1.0 / fs
        off = np.abs(step - dt) > max(RATE_TOLERANCE * dt, 1.5e-4)
        if off.any():
            i = int(np.flatnonzero(off)[0]) + 1
            raise RawFormatError(
                path,
                first_data + i,
                f"time step {step[i - 1]:.6g} s disagrees with sampling_rate_hz {fs:g} (expected {dt:.6g} s)",
            )
    return data


def header_row(rec: RecordText) -> list[str]:
    """The names of the header row (the line after the comments), blanks stripped."""
    return [c.strip() for c in rec.lines[rec.n_comment].split(",")]


def read_record(path: str | Path, expected_test_id: str | None = None) -> Record:
    """Read one transducer record and check it against the format.

    Parameters
    ----------
    path : path-like
        ``tests/<id>.csv.gz`` (plain ``.csv`` is accepted too).
    expected_test_id : str, optional
        The test_id the log gives for this file; a different ``# test_id``
        header is an error.

    Raises
    ------
    RawFormatError
        Truncated/corrupt file, missing header keys, a header row that is not
        ``time_s,ch0,...``, a row with the wrong number of fields, a value that
        is not a number, a time column that does not increase, or a sampling
        rate that disagrees with the time column; a record of another kind.
    """
    return transducer_record(read_text(path), expected_test_id)


def transducer_record(rec: RecordText, expected_test_id: str | None = None) -> Record:
    """:func:`read_record` of a record past :func:`read_text`."""
    if rec.kind != TRANSDUCERS:
        raise rec.error(f"a {rec.kind} record, not a transducer record")
    head_line = rec.n_comment + 1
    columns = header_row(rec)
    if (
        columns[0] != "time_s"
        or len(columns) < 2
        or not all(c.startswith("ch") and c[2:].isdigit() for c in columns[1:])
    ):
        raise RawFormatError(
            rec.path, head_line, f"header row must be time_s,ch0,ch1,... (got {rec.lines[rec.n_comment]!r})"
        )
    channels = [int(c[2:]) for c in columns[1:]]
    if len(set(channels)) != len(channels):
        raise RawFormatError(rec.path, head_line, "a channel appears twice in the header row")
    fs = check_header(rec, expected_test_id, UNITS)
    data = read_rows(rec, columns, fs)
    return Record(data[:, 0], data[:, 1:], channels, fs, rec.header, rec.sha256, str(rec.path))


#: The ``# units:`` of a rotation record: time in s, rotations in rad (sliding, when given, in mm).
ROTATION_UNITS = ("s", "rad")
#: The columns a rotation record may add after ``time_s,theta_rad``, in this order.
ROTATION_OPTIONAL = ("phi_rad", "v_mm", "w_mm")
#: The ``# units:`` of an inertial record.
INERTIAL_UNITS = ("s", "rad/s", "m/s2")
#: The columns of an inertial record after ``time_s``.
INERTIAL_COLUMNS = ("gyro_x_rad_s", "acc_y_m_s2", "acc_z_m_s2")
#: Header keys every record of the other instruments gives.
INSTRUMENT_KEYS = ("test_id", "record", "units")


@dataclass
class RotationRecord:
    """One test's rotation record (motion capture, inclinometer, video), as read.

    Attributes
    ----------
    time : ndarray (N,)
        Time [s].
    dof : dict
        ``theta`` [rad] and, where the record gives them, ``phi`` [rad],
        ``v``, ``w`` [mm]; NaN where a marker was lost.
    fs, header, sha256, path
        As :class:`Record`.
    attrs : dict
        What the instrument's own reader measured, for ``qc.csv``
        (a video's ``frames_tracked`` and ``tracking_noise_rad``).
    """

    time: np.ndarray
    dof: dict[str, np.ndarray]
    fs: float
    header: dict[str, str]
    sha256: str
    path: str
    attrs: dict[str, Any] = field(default_factory=dict)


@dataclass
class InertialRecord:
    """One test's inertial record (a gyroscope and an accelerometer on the wall), as read.

    Attributes
    ----------
    time : ndarray (N,)
        Time [s].
    rate : ndarray (N,)
        Angular rate about the body x axis [rad/s], positive as theta grows.
    acc_y, acc_z : ndarray (N,)
        Specific force along the body y and z axes [m/s^2], gravity included.
    sensor_mm : ndarray (3,)
        Where the sensor is fixed on the wall (body frame) [mm].
    fs, header, sha256, path
        As :class:`Record`.
    """

    time: np.ndarray
    rate: np.ndarray
    acc_y: np.ndarray
    acc_z: np.ndarray
    sensor_mm: np.ndarray
    fs: float
    header: dict[str, str]
    sha256: str
    path: str


def _no_empty_column(rec: RecordText, columns: list[str], data: np.ndarray) -> None:
    """Refuse a record with a measured column that holds no sample at all."""
    empty = [c for j, c in enumerate(columns) if j and np.isnan(data[:, j]).all()]
    if empty:
        raise RawFormatError(rec.path, rec.n_comment + 1, f"column {empty[0]}: every sample is empty")


def rotation_record(rec: RecordText, expected_test_id: str | None = None) -> RotationRecord:
    """A ``# record: rotation`` record past :func:`read_text` (``docs/raw-format.md``).

    Raises
    ------
    RawFormatError
        A missing header key, other units than ``s, rad``, a header row that
        is not ``time_s,theta_rad`` optionally followed by ``phi_rad``,
        ``v_mm``, ``w_mm`` in that order, a column that is all empty, and
        every fault :func:`read_rows` finds.
    """
    fs = check_header(rec, expected_test_id, ROTATION_UNITS, INSTRUMENT_KEYS)
    columns = header_row(rec)
    extra = columns[2:]
    if columns[:2] != ["time_s", "theta_rad"] or extra != [c for c in ROTATION_OPTIONAL if c in extra]:
        raise RawFormatError(
            rec.path,
            rec.n_comment + 1,
            f"header row must be time_s,theta_rad then any of {','.join(ROTATION_OPTIONAL)} in that order"
            f" (got {rec.lines[rec.n_comment]!r})",
        )
    data = read_rows(rec, columns, fs)
    _no_empty_column(rec, columns, data)
    dof = {c.split("_")[0]: data[:, j] for j, c in enumerate(columns) if j}
    return RotationRecord(data[:, 0], dof, fs, rec.header, rec.sha256, str(rec.path))


def inertial_record(rec: RecordText, expected_test_id: str | None = None) -> InertialRecord:
    """A ``# record: inertial`` record past :func:`read_text` (``docs/raw-format.md``).

    Raises
    ------
    RawFormatError
        A missing header key, other units than ``s, rad/s, m/s2``, a
        ``sensor_mm`` that is not three numbers, a header row that is not
        ``time_s`` and :data:`INERTIAL_COLUMNS`, a column that is all empty,
        and every fault :func:`read_rows` finds.  Whether the sensor is on
        the wall is checked against the specimen (:func:`check_sensor`).
    """
    fs = check_header(rec, expected_test_id, INERTIAL_UNITS, (*INSTRUMENT_KEYS, "sensor_mm"))
    try:
        sensor = np.array([float(x) for x in rec.header["sensor_mm"].split(",")])
    except ValueError:
        sensor = np.array([])
    if sensor.shape != (3,) or not np.isfinite(sensor).all():
        raise rec.error(f"sensor_mm {rec.header['sensor_mm']!r} is not three numbers x, y, z [mm]")
    columns = header_row(rec)
    if columns[0] != "time_s" or sorted(columns[1:]) != sorted(INERTIAL_COLUMNS):
        raise RawFormatError(
            rec.path,
            rec.n_comment + 1,
            f"header row must be time_s,{','.join(INERTIAL_COLUMNS)} (got {rec.lines[rec.n_comment]!r})",
        )
    data = read_rows(rec, columns, fs)
    _no_empty_column(rec, columns, data)
    col = {c: data[:, j] for j, c in enumerate(columns)}
    rate, acc_y, acc_z = (col[c] for c in INERTIAL_COLUMNS)
    return InertialRecord(data[:, 0], rate, acc_y, acc_z, sensor, fs, rec.header, rec.sha256, str(rec.path))


def check_sensor(rec: InertialRecord, length_mm: float, height_mm: float, thickness_mm: float) -> None:
    """Refuse an inertial record whose ``sensor_mm`` is not on the wall (body frame, ``docs/raw-format.md``).

    Raises
    ------
    RawFormatError
        At line 1 (the header), naming the point and the wall's extent.
    """
    x, y, z = rec.sensor_mm
    tol = 1.0  # mm: a sensor glued on a face is written on it, give or take the rounding
    if abs(x) > length_mm / 2 + tol or abs(y) > thickness_mm / 2 + tol or not -tol <= z <= height_mm + tol:
        raise RawFormatError(
            rec.path,
            1,
            f"sensor_mm {x:g}, {y:g}, {z:g} is outside the wall (x within +-{length_mm / 2:g},"
            f" y within +-{thickness_mm / 2:g}, z within 0-{height_mm:g} mm)",
        )


#: The reader of each kind of record past :func:`read_text`.
READERS: dict[str, Callable[[RecordText, str | None], Record | RotationRecord | InertialRecord]] = {
    TRANSDUCERS: transducer_record,
    "rotation": rotation_record,
    "inertial": inertial_record,
}


def read_any_record(path: str | Path, expected_test_id: str | None = None) -> Record | RotationRecord | InertialRecord:
    """Read one test's record of whatever kind its header declares (``# record:``, :data:`RECORD_KINDS`).

    The door checks are the same for all (:func:`read_text`, :func:`check_header`, :func:`read_rows`);
    the native files of the instruments come through the same door in
    :func:`rocklab.lab.native_files.read_test_file`.

    Raises
    ------
    RawFormatError
        Naming the file, the line and the problem.
    """
    rec = read_text(path)
    return READERS[rec.kind](rec, expected_test_id)
