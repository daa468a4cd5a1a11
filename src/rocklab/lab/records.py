"""Reader of one test's transducer record in the lab's raw format (``docs/raw-format.md``).

A record is ``tests/<id>.csv.gz`` (plain ``.csv`` too): ``# key: value``
header lines (``sampling_rate_hz``, ``test_id``, ``units``), the row
``time_s,ch0,ch1,...`` and one row of readings [mm] per sample.  Every
problem is a :class:`~rocklab.lab.raw_format.RawFormatError` naming the file
and the line.  The campaign's tables are read by :mod:`rocklab.lab.campaign`.
"""

from __future__ import annotations

import gzip
import hashlib
import io
import re
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from rocklab.lab.raw_format import CONTROL, RawFormatError

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
    channels: list
    fs: float
    header: dict
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


def _numbers(body: str, columns: list, path: Path, first_data: int) -> np.ndarray:
    """The data rows as finite floats, NaN where a field is empty.

    Parsed as floats by pandas' C reader when the text holds plain decimal
    numbers only (a record of the lab: ten times faster); anything else, or
    a field that reader refuses or makes infinite, goes field by field
    through ``pandas.to_numeric``, which also names the first field that is
    not a (finite) number.  Both read a number as Python's ``float`` does
    (tests/test_campaign.py).
    """
    if not PLAIN_NUMBERS.search(body):
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


def read_record(path, expected_test_id=None) -> Record:
    """Read one test record and check it against the format.

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
        rate that disagrees with the time column.
    """
    path = Path(path)
    if not path.exists():
        raise RawFormatError(path, None, "file not found")
    if not path.is_file():
        raise RawFormatError(path, None, "not a regular file")
    text, digest = _decompress(path)
    # a byte-order mark and CRLF line ends are harmless
    lines = text.removeprefix("\ufeff").splitlines()
    # line by line only when the text holds one (a CR of CRLF does, and ends a line)
    bad = next((n for n, ln in enumerate(lines, start=1) if CONTROL.search(ln)), None) if CONTROL.search(text) else None
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
    head_line = n_comment + 1
    columns = [c.strip() for c in lines[n_comment].split(",")]
    if (
        columns[0] != "time_s"
        or len(columns) < 2
        or not all(c.startswith("ch") and c[2:].isdigit() for c in columns[1:])
    ):
        raise RawFormatError(path, head_line, f"header row must be time_s,ch0,ch1,... (got {lines[n_comment]!r})")
    channels = [int(c[2:]) for c in columns[1:]]
    if len(set(channels)) != len(channels):
        raise RawFormatError(path, head_line, "a channel appears twice in the header row")
    if "sampling_rate_hz" not in header:
        raise RawFormatError(path, 1, "missing '# sampling_rate_hz:' header line")
    try:
        fs = float(header["sampling_rate_hz"])
    except ValueError:
        raise RawFormatError(path, 1, f"sampling_rate_hz {header['sampling_rate_hz']!r} is not a number") from None
    if not fs > 0:
        raise RawFormatError(path, 1, "sampling_rate_hz must be positive")
    if expected_test_id is not None and header.get("test_id", expected_test_id) != expected_test_id:
        raise RawFormatError(path, 1, f"header test_id {header['test_id']!r} but tests.csv says {expected_test_id!r}")
    units = tuple(u.strip() for u in header.get("units", ", ".join(UNITS)).split(","))
    if units != UNITS:
        raise RawFormatError(
            path, 1, f"units {header['units']!r}: the format is time in s and readings in mm ('{', '.join(UNITS)}')"
        )

    body = lines[n_comment + 1 :]
    first_data = head_line + 1
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
    return Record(time, data[:, 1:], channels, fs, header, digest, str(path))
