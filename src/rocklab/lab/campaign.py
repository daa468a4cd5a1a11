"""Reader of the lab's raw campaign format (``docs/raw-format.md``).

A campaign folder holds ``specimens.csv``, ``setups.csv``, ``tests.csv`` and
one gzip-compressed record per test.  Every problem is reported as a
:class:`RawFormatError` naming the file, the row (1-based line number in the
file, header and comment lines included) and the problem, so that a lab
technician can open the file at that line.  Nothing here writes to the
campaign folder.
"""

from __future__ import annotations

import gzip
import hashlib
import io
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

SPECIMEN_COLUMNS = {
    "specimen": str,
    "wall": str,
    "unit": str,
    "length_mm": float,
    "height_mm": float,
    "thickness_mm": float,
    "unit_weight_kN_m3": float,
}
SETUP_COLUMNS = {
    "setup": str,
    "channel": int,
    "wall_x_mm": float,
    "wall_y_mm": float,
    "wall_z_mm": float,
    "frame_x_mm": float,
    "frame_y_mm": float,
    "frame_z_mm": float,
}
TEST_COLUMNS = {
    "test_id": str,
    "specimen": str,
    "boundary": str,
    "contact_depth_mm": float,
    "direction": str,
    "setup": str,
    "file": str,
    "note": str,
}
BOUNDARIES = ("two-sided", "one-sided")
DIRECTIONS = ("push", "pull")

#: Relative tolerance between the declared sampling rate and the time column.
RATE_TOLERANCE = 1e-3


class RawFormatError(ValueError):
    """A campaign file that does not follow the lab's format.

    Attributes
    ----------
    path : str
        The offending file.
    row : int or None
        1-based line number in that file (None when the whole file is at fault).
    problem : str
        What is wrong, in words.
    """

    def __init__(self, path, row, problem):
        self.path, self.row, self.problem = str(path), row, problem
        where = f"{self.path}:{row}" if row is not None else self.path
        super().__init__(f"{where}: {problem}")


def _read_table(path: Path, columns: dict, optional=()) -> pd.DataFrame:
    """Read a campaign table as strings and convert column by column."""
    if not path.exists():
        raise RawFormatError(path, None, "file not found")
    try:
        raw = pd.read_csv(path, dtype=str, keep_default_na=False, skipinitialspace=True)
    except (pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise RawFormatError(path, None, f"not a readable CSV table ({exc})") from None
    missing = [c for c in columns if c not in raw.columns and c not in optional]
    if missing:
        raise RawFormatError(path, 1, f"missing column(s) {', '.join(missing)}")
    out = {}
    for col, kind in columns.items():
        values = raw[col].str.strip() if col in raw.columns else pd.Series([""] * len(raw))
        if kind is str:
            out[col] = values
            continue
        num = pd.to_numeric(values.replace("", np.nan), errors="coerce")
        bad = values.ne("") & num.isna()
        if bad.any():
            i = int(np.flatnonzero(bad.to_numpy())[0])
            raise RawFormatError(path, i + 2, f"column {col}: {values.iloc[i]!r} is not a number")
        if kind is int:
            if num.isna().any() or (num % 1 != 0).any():
                i = int(np.flatnonzero((num.isna() | (num % 1 != 0)).to_numpy())[0])
                raise RawFormatError(path, i + 2, f"column {col}: {values.iloc[i]!r} is not an integer")
            num = num.astype(int)
        out[col] = num
    return pd.DataFrame(out)


def _require(path, df, col, allowed):
    bad = ~df[col].isin(allowed)
    if bad.any():
        i = int(np.flatnonzero(bad.to_numpy())[0])
        raise RawFormatError(path, i + 2, f"{col} {df[col].iloc[i]!r} is not one of {', '.join(allowed)}")


def _require_unique(path, df, cols):
    dup = df.duplicated(cols, keep="first")
    if dup.any():
        i = int(np.flatnonzero(dup.to_numpy())[0])
        key = ", ".join(str(df[c].iloc[i]) for c in cols)
        raise RawFormatError(path, i + 2, f"duplicated {'/'.join(cols)} {key}")


def read_specimens(campaign_dir) -> pd.DataFrame:
    """Specimens table, one row per specimen, dimensions in mm."""
    path = Path(campaign_dir) / "specimens.csv"
    df = _read_table(path, SPECIMEN_COLUMNS)
    _require_unique(path, df, ["specimen"])
    for col in ("length_mm", "height_mm", "thickness_mm", "unit_weight_kN_m3"):
        bad = ~(df[col] > 0)
        if bad.any():
            i = int(np.flatnonzero(bad.to_numpy())[0])
            raise RawFormatError(path, i + 2, f"{col} must be a positive number")
    return df


def read_setups(campaign_dir) -> pd.DataFrame:
    """Transducer geometry, one row per (setup, channel), in mm."""
    path = Path(campaign_dir) / "setups.csv"
    df = _read_table(path, SETUP_COLUMNS)
    _require_unique(path, df, ["setup", "channel"])
    length = np.hypot.reduce(
        df[["frame_x_mm", "frame_y_mm", "frame_z_mm"]].to_numpy()
        - df[["wall_x_mm", "wall_y_mm", "wall_z_mm"]].to_numpy(),
        axis=1,
    )
    if (length <= 0).any():
        i = int(np.flatnonzero(length <= 0)[0])
        raise RawFormatError(path, i + 2, "wall and frame points coincide")
    return df


@dataclass
class TestLog:
    """The test log, with the rows that cannot be reduced set apart.

    ``tests`` holds every row of ``tests.csv`` (duplicates included);
    ``errors`` maps a test_id to the :class:`RawFormatError` that makes it
    unreadable, so one bad row never stops the campaign.
    """

    tests: pd.DataFrame
    errors: dict = field(default_factory=dict)


def read_tests(campaign_dir, specimens=None, setups=None) -> TestLog:
    """Test log with every row checked against specimens and setups.

    A row whose specimen, setup, boundary or direction is unknown, or whose
    test_id repeats an earlier row, is kept but recorded in
    :attr:`TestLog.errors`.  A malformed table as a whole raises.
    """
    campaign_dir = Path(campaign_dir)
    path = campaign_dir / "tests.csv"
    df = _read_table(path, TEST_COLUMNS, optional=("note", "contact_depth_mm"))
    specimens = read_specimens(campaign_dir) if specimens is None else specimens
    setups = read_setups(campaign_dir) if setups is None else setups
    known_spec, known_setup = set(specimens.specimen), set(setups.setup)
    errors = {}
    seen = set()
    for i, row in enumerate(df.itertuples(index=False)):
        line = i + 2
        problem = None
        if not row.test_id:
            problem = "empty test_id"
        elif row.test_id in seen:
            problem = f"duplicated test_id {row.test_id}"
        elif row.specimen not in known_spec:
            problem = f"unknown specimen {row.specimen!r} (not in specimens.csv)"
        elif row.setup not in known_setup:
            problem = f"unknown setup {row.setup!r} (not in setups.csv)"
        elif row.boundary not in BOUNDARIES:
            problem = f"boundary {row.boundary!r} is not one of {', '.join(BOUNDARIES)}"
        elif row.direction not in DIRECTIONS:
            problem = f"direction {row.direction!r} is not one of {', '.join(DIRECTIONS)}"
        elif row.boundary == "one-sided" and not row.contact_depth_mm > 0:
            problem = "one-sided test without a positive contact_depth_mm"
        elif not row.file:
            problem = "empty file"
        if problem:
            # A repeated id must not disqualify the first row that carries it.
            first_use = row.test_id and row.test_id not in seen and row.test_id not in errors
            key = row.test_id if first_use else f"{row.test_id or 'row'}@{line}"
            errors[key] = RawFormatError(path, line, problem)
        seen.add(row.test_id)
    return TestLog(df, errors)


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
    text, digest = _decompress(path)
    lines = text.splitlines()
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
    table = pd.read_csv(io.StringIO("\n".join(body)), header=None, names=columns, dtype=str, keep_default_na=False)
    fields = table.apply(lambda s: s.str.strip())
    values = fields.apply(lambda s: pd.to_numeric(s.replace("", np.nan), errors="coerce"))
    nonnum = (values.isna() & fields.ne("")).to_numpy()
    if nonnum.any():
        i, j = np.argwhere(nonnum)[0]
        raise RawFormatError(path, first_data + int(i), f"{columns[j]}: {table.iat[i, j]!r} is not a number")
    data = values.to_numpy(float)
    time = data[:, 0]
    if np.isnan(time).any():
        i = int(np.flatnonzero(np.isnan(time))[0])
        raise RawFormatError(path, first_data + i, "empty time_s")
    step = np.diff(time)
    if (step <= 0).any():
        i = int(np.flatnonzero(step <= 0)[0]) + 1
        raise RawFormatError(path, first_data + i, "time_s does not increase")
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


@dataclass
class Campaign:
    """A campaign folder: its three tables and where its records are."""

    root: Path
    specimens: pd.DataFrame
    setups: pd.DataFrame
    log: TestLog

    @property
    def tests(self) -> pd.DataFrame:
        return self.log.tests

    def test_row(self, test_id) -> pd.Series:
        rows = self.tests[self.tests.test_id == test_id]
        return rows.iloc[0]

    def record_path(self, test_id) -> Path:
        return self.root / self.test_row(test_id).file

    def specimen(self, name) -> pd.Series:
        return self.specimens.set_index("specimen").loc[name]

    def setup(self, name) -> pd.DataFrame:
        return self.setups[self.setups.setup == name].sort_values("channel").reset_index(drop=True)


def row_series(row) -> str:
    """Series of a row of tests.csv (:func:`series_id`)."""
    return series_id(row.specimen, row.boundary, row.contact_depth_mm if row.boundary == "one-sided" else np.nan)


def series_id(specimen, boundary, contact_depth_mm) -> str:
    """Series key: specimen + boundary + contact depth (docs/raw-format.md)."""
    if boundary == "two-sided" or contact_depth_mm is None or not np.isfinite(contact_depth_mm):
        return f"{specimen}-2s"
    return f"{specimen}-1s-cd{int(round(contact_depth_mm))}"


def open_campaign(campaign_dir) -> Campaign:
    """Read and cross-check the three tables of a campaign folder."""
    root = Path(campaign_dir)
    specimens = read_specimens(root)
    setups = read_setups(root)
    return Campaign(root, specimens, setups, read_tests(root, specimens, setups))
