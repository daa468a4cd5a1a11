"""Reader of the lab's raw campaign format (``docs/raw-format.md``): its three tables.

A campaign folder holds ``specimens.csv``, ``setups.csv``, ``tests.csv`` and
one gzip-compressed record per test.  Here the tables are read and
cross-checked row by row (:func:`open_campaign`); the records are read by
:mod:`rocklab.lab.records`, and what every raw file shares (the error that
names file and line, the ids and paths a table may give) is in
:mod:`rocklab.lab.raw_format`.  Every problem is reported as a
:class:`~rocklab.lab.raw_format.RawFormatError` naming the file, the row
(1-based line number in the file, header and comment lines included) and
the problem, so that a lab technician can open the file at that line.
Nothing here writes to the campaign folder.
"""

from __future__ import annotations

import codecs
import csv
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rocklab.lab.raw_format import CONTROL, RawFormatError, campaign_file, check_identifier
from rocklab.physics.boundary import Boundary

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
DIRECTIONS = ("push", "pull")

#: Most tests of one reduction job (:meth:`Campaign.reduction_jobs`; the
#: workflow's ``reduction.max_tests_per_job``).
TESTS_PER_JOB = 250
#: The reduction group of the tests refused at the door (:meth:`Campaign.reduction_groups`).
UNREADABLE = "unreadable"


def _decode_lines(path: Path) -> list[tuple[int, str, str | None]]:
    """Lines of a text table as (line number, text, problem).

    UTF-8 with or without a byte-order mark, LF or CRLF line ends; a line
    that is not UTF-8 or holds a control character is kept, shown with
    replacement characters, with its problem.
    """
    blob = path.read_bytes()
    if blob.startswith(codecs.BOM_UTF8):
        blob = blob[len(codecs.BOM_UTF8) :]
    out: list[tuple[int, str, str | None]] = []
    for n, raw in enumerate(blob.splitlines(), start=1):
        problem = None
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            text = raw.decode("utf-8", errors="replace")
            problem = f"not UTF-8 text (byte {exc.start + 1} of the line)"
        if problem is None and CONTROL.search(text):
            problem = "a control character in the line"
        out.append((n, text, problem))
    return out


@dataclass
class Table:
    """A campaign table as read: its rows, converted, and each row's problem.

    Attributes
    ----------
    path : Path
    rows : DataFrame
        Every data row, in file order, the declared columns converted (a value
        that could not be converted is NaN and its row has a problem), plus
        ``line``: the row's 1-based line number in the file.
    problems : dict
        Row index (of ``rows``) to the problem in words.
    """

    path: Path
    rows: pd.DataFrame
    problems: dict[int, str]

    def error(self, i: int, problem: str | None = None) -> RawFormatError:
        """The :class:`RawFormatError` of row ``i`` (its own problem by default)."""
        return RawFormatError(self.path, int(self.rows.line.iloc[i]), problem or self.problems[i])


def _number(text: str, kind: type) -> tuple[float, str | None]:
    if text == "":
        return np.nan, None
    try:
        value = float(text)
    except ValueError:
        return np.nan, f"{text!r} is not a number"
    if not np.isfinite(value):
        return np.nan, f"{text!r} is not a finite number"
    if kind is int and value % 1 != 0:
        return np.nan, f"{text!r} is not an integer"
    return value, None


def read_table(path: Path, columns: dict[str, type], optional: tuple[str, ...] = (), keep_extra: bool = False) -> Table:
    """Read a campaign table and check it row by row.

    Blanks around a field, a byte-order mark, CRLF line ends, blank lines
    and columns beyond ``columns`` (ignored, or kept as text with
    ``keep_extra``: the test log's own columns) are harmless and read.  A row
    with the wrong number of fields, a value that is not a finite number
    where one is expected, a line that is not UTF-8 text, is kept with its
    problem.

    Raises
    ------
    RawFormatError
        The table as a whole is unusable: not found, not a regular file,
        no header, a required column missing or a column named twice.
    """
    if not path.exists():
        raise RawFormatError(path, None, "file not found")
    if not path.is_file():
        raise RawFormatError(path, None, "not a regular file")
    lines = [ln for ln in _decode_lines(path) if ln[1].strip()]
    if not lines:
        raise RawFormatError(path, None, "empty file: no header row")
    head_n, head_text, head_problem = lines[0]
    if head_problem:
        raise RawFormatError(path, head_n, f"header row: {head_problem}")
    header = [c.strip() for c in next(csv.reader([head_text]))]
    missing = [c for c in columns if c not in header and c not in optional]
    if missing:
        raise RawFormatError(path, head_n, f"missing column(s) {', '.join(missing)}")
    twice = sorted({c for c in header if header.count(c) > 1 and c in columns})
    if twice:
        raise RawFormatError(path, head_n, f"column(s) {', '.join(twice)} named twice")
    index = {c: header.index(c) for c in columns if c in header}
    extra = [c for c in header if keep_extra and c and c not in columns and c != "line" and header.count(c) == 1]
    records: list[dict[str, Any]] = []
    problems: dict[int, str] = {}
    for i, (n, text, problem) in enumerate(lines[1:]):
        fields = [f.strip() for f in next(csv.reader([text]), [])]
        if problem is None and len(fields) != len(header):
            what = "truncated row" if len(fields) < len(header) else "too many fields"
            problem = f"{what}: {len(fields)} fields, expected {len(header)} (the header's)"
        rec = {"line": n, **{c: fields[header.index(c)] if header.index(c) < len(fields) else "" for c in extra}}
        for col, kind in columns.items():
            value = fields[index[col]] if col in index and index[col] < len(fields) else ""
            if kind is str:
                rec[col] = value
                continue
            rec[col], bad = _number(value, kind)
            if bad and problem is None:
                problem = f"column {col}: {bad}"
        if problem:
            problems[i] = problem
        records.append(rec)
    rows = pd.DataFrame(records, columns=["line", *columns, *extra])
    for col, kind in columns.items():
        values = rows[col].astype(str if kind is str else float)
        # whole numbers stay integers, as the lab wrote them (the params that decide a rerun show them)
        if kind is not str and len(values) and np.isfinite(values).all() and (values % 1 == 0).all():
            values = values.astype(int)
        rows[col] = values
    return Table(path, rows, problems)


def _table_path(campaign_dir: str | Path, name: str) -> Path:
    path, problem = campaign_file(Path(campaign_dir), name, "table")
    if problem:
        raise RawFormatError(Path(campaign_dir) / name, None, problem)
    assert path is not None  # campaign_file gives a path or a problem
    return path


@dataclass
class Refused:
    """Ids of a table refused at the door, each with its reason, and the table's own fault."""

    ids: dict[str, RawFormatError] = field(default_factory=dict)
    table: RawFormatError | None = None

    def reason(self, key: str) -> RawFormatError | None:
        """Why ``key`` is refused (the table's fault first), or None."""
        return self.table or self.ids.get(key)


def _conflicting(table: Table, key_cols: list[str], good: pd.Series) -> dict[int, tuple[tuple[Any, ...], str]]:
    """Rows whose key repeats an earlier row with other values: row -> (key tuple, problem).

    A row repeated word for word is harmless (the first is read); a key
    given twice with different values is ambiguous and refused as a whole.
    """
    df = table.rows
    values = [c for c in df.columns if c != "line"]
    out: dict[int, tuple[tuple[Any, ...], str]] = {}
    for key, group in df[good].groupby(key_cols, sort=False):
        if len(group) > 1 and len(group.drop_duplicates(values)) > 1:
            lines = ", ".join(str(n) for n in group.line)
            key = key if isinstance(key, tuple) else (key,)
            name = "/".join(str(k) for k in key)
            out[group.index[1]] = (key, f"{'/'.join(key_cols)} {name} given at lines {lines} with other values")
    return out


def read_specimens(campaign_dir: str | Path) -> tuple[pd.DataFrame, Refused]:
    """Specimens, one row per specimen, dimensions in mm, and the ones refused.

    A specimen is refused (its tests become unreadable, naming the row) when
    its row has a problem, its id is not a safe name, a dimension or the
    unit weight is not positive, or it is given twice with different values.
    """
    path = _table_path(campaign_dir, "specimens.csv")
    table = read_table(path, SPECIMEN_COLUMNS)
    df = table.rows
    problems: dict[int, str | None] = dict(table.problems)
    for i, row in enumerate(df.itertuples(index=False)):
        if i in problems:
            continue
        problems[i] = check_identifier(row.specimen, "specimen")
        for col in ("length_mm", "height_mm", "thickness_mm", "unit_weight_kN_m3"):
            value = getattr(row, col)
            if problems[i] is None and not value > 0:
                problems[i] = f"column {col}: empty" if np.isnan(value) else f"column {col}: {value:g} must be positive"
    problems = {i: p for i, p in problems.items() if p}
    refused = Refused({df.specimen.iloc[i]: table.error(i, p) for i, p in problems.items()})
    good = ~df.index.isin(list(problems))
    for i, (key, problem) in _conflicting(table, ["specimen"], pd.Series(good)).items():
        refused.ids[key[0]] = table.error(i, problem)
    keep = good & ~df.specimen.isin(list(refused.ids))
    return df[keep].drop_duplicates("specimen").drop(columns="line").reset_index(drop=True), refused


def read_setups(campaign_dir: str | Path) -> tuple[pd.DataFrame, Refused]:
    """Transducer geometry, one row per (setup, channel), in mm, and the setups refused.

    A setup is refused as a whole (its tests become unreadable, naming the
    row) when one of its rows has a problem, gives a channel that is not a
    non-negative integer, wall and frame points that coincide, or a channel
    twice with different points: a transducer dropped quietly would change
    the kinematics.
    """
    path = _table_path(campaign_dir, "setups.csv")
    table = read_table(path, SETUP_COLUMNS)
    df, problems = table.rows, dict(table.problems)
    wall_xyz = df[["wall_x_mm", "wall_y_mm", "wall_z_mm"]].to_numpy(float)
    frame_xyz = df[["frame_x_mm", "frame_y_mm", "frame_z_mm"]].to_numpy(float)
    length = np.linalg.norm(frame_xyz - wall_xyz, axis=1)
    for i, row in enumerate(df.itertuples(index=False)):
        if i in problems:
            continue
        if not row.setup:
            problems[i] = "empty setup"
        elif not row.channel >= 0:
            problems[i] = "column channel: empty" if np.isnan(row.channel) else f"channel {row.channel:g} is negative"
        elif not length[i] > 0:
            problems[i] = f"channel {int(row.channel)}: wall and frame points coincide"
    refused = Refused()
    for i, p in problems.items():
        refused.ids.setdefault(df.setup.iloc[i], table.error(i, p))
    good = ~df.index.isin(list(problems))
    for i, (key, problem) in _conflicting(table, ["setup", "channel"], pd.Series(good)).items():
        refused.ids.setdefault(key[0], table.error(i, problem))
    keep = good & ~df.setup.isin(list(refused.ids))
    df = df[keep].drop_duplicates(["setup", "channel"]).drop(columns="line").reset_index(drop=True)
    return df.astype({"channel": int}), refused


@dataclass
class TestLog:
    """The test log, with the rows that cannot be reduced set apart.

    ``tests`` holds every row of ``tests.csv`` (duplicates included), with
    ``line``, its line number in the file; ``errors`` maps a test_id to the
    :class:`RawFormatError` that makes it unreadable, so one bad row never
    stops the campaign.  A row that cannot have a results file of its own
    (an unsafe or repeated test_id) is keyed ``<test_id>@<line>``.
    """

    tests: pd.DataFrame
    errors: dict[str, RawFormatError] = field(default_factory=dict)


def read_tests(
    campaign_dir: str | Path,
    specimens: tuple[pd.DataFrame, Refused] | None = None,
    setups: tuple[pd.DataFrame, Refused] | None = None,
) -> TestLog:
    """Test log with every row checked at the door.

    A row whose test_id is not a safe name or repeats an earlier row, whose
    specimen or setup is unknown or refused, whose boundary or direction is
    not an allowed word, whose contact depth is missing or not positive, or
    whose file is empty, leaves the campaign folder or is not a regular
    file, is kept and recorded in :attr:`TestLog.errors`.  An empty setup
    is a test that no transducer recorded: whether its record agrees is the
    reduction's question (:mod:`rocklab.lab.reduction`).

    Parameters
    ----------
    campaign_dir : path-like
    specimens, setups : (DataFrame, Refused), optional
        From :func:`read_specimens` and :func:`read_setups` (read when not given).

    Raises
    ------
    RawFormatError
        ``tests.csv`` as a whole is unusable (:func:`read_table`).
    """
    root = Path(campaign_dir)
    path = _table_path(root, "tests.csv")
    table = read_table(path, TEST_COLUMNS, optional=("note", "contact_depth_mm"), keep_extra=True)
    specimen_rows, bad_spec = _or_empty(read_specimens, root) if specimens is None else specimens
    setup_rows, bad_setup = _or_empty(read_setups, root) if setups is None else setups
    df = table.rows
    known_spec, known_setup = set(specimen_rows.specimen), set(setup_rows.setup)
    # the line of the first row of each test_id: the one reduced
    first: dict[str, int] = {}
    for tid, line in zip(df.test_id, df.line, strict=True):
        first.setdefault(tid, line)
    errors: dict[str, RawFormatError] = {}
    for i, row in enumerate(df.itertuples(index=False)):
        problem = table.problems.get(i) or check_identifier(row.test_id, "test_id")
        if problem is None and first[row.test_id] != row.line:
            problem = (
                f"duplicated test_id {row.test_id}: the row at line {first[row.test_id]} is the one reduced,"
                " this one is refused"
            )
        if problem is None and row.specimen not in known_spec and bad_spec.reason(row.specimen):
            problem = f"specimen {row.specimen!r} refused: {bad_spec.reason(row.specimen)}"
        elif problem is None and row.setup and row.setup not in known_setup and bad_setup.reason(row.setup):
            problem = f"setup {row.setup!r} refused: {bad_setup.reason(row.setup)}"
        elif problem is None:
            problem = _row_problem(root, row, known_spec, known_setup)
        if problem:
            # an id that cannot name a file, or that an earlier row holds, gets no results file
            unsafe = check_identifier(row.test_id, "test_id") or first[row.test_id] != row.line
            errors[f"{row.test_id}@{row.line}" if unsafe else row.test_id] = table.error(i, problem)
    return TestLog(df, errors)


def order_in_series(test_ids: Iterable[str]) -> dict[str, float]:
    """Each test's place in its series, 0 (first) to 1 (last), from the order of the ids.

    Test ids of a campaign grow with the date of the test (``T0001``...),
    so their order is the order in which the tests were performed: what a
    drift between tests (hinge wear, mortar debris) follows.

    Parameters
    ----------
    test_ids : sequence of str
        The tests of one series.

    Returns
    -------
    dict
        test_id -> place in [0, 1]; a lone test is at 0.
    """
    rank = {tid: i for i, tid in enumerate(sorted(test_ids))}
    n = max(len(rank) - 1, 1)
    return {tid: i / n for tid, i in rank.items()}


def _or_empty(reader: Callable[[Path], tuple[pd.DataFrame, Refused]], root: Path) -> tuple[pd.DataFrame, Refused]:
    """A table reader's result, or no rows and the table's fault when it is unusable."""
    try:
        return reader(root)
    except RawFormatError as exc:
        columns = SPECIMEN_COLUMNS if reader is read_specimens else SETUP_COLUMNS
        return pd.DataFrame({c: pd.Series(dtype=object if k is str else float) for c, k in columns.items()}), Refused(
            table=exc
        )


def _row_problem(root: Path, row: Any, known_spec: set[str], known_setup: set[str]) -> str | None:
    """What makes a row of tests.csv unreadable by itself (None when nothing)."""
    if row.specimen not in known_spec:
        return f"unknown specimen {row.specimen!r} (not in specimens.csv)"
    # no setup: a test no transducer recorded (its record says so, rocklab.lab.records)
    if row.setup and row.setup not in known_setup:
        return f"unknown setup {row.setup!r} (not in setups.csv)"
    if row.boundary not in set(Boundary):
        return f"boundary {row.boundary!r} is not one of {', '.join(Boundary)}"
    if row.direction not in DIRECTIONS:
        return f"direction {row.direction!r} is not one of {', '.join(DIRECTIONS)}"
    if row.boundary == Boundary.ONE_SIDED and not row.contact_depth_mm > 0:
        return "one-sided test without a positive contact_depth_mm"
    if not row.file:
        return "empty file"
    return campaign_file(Path(root), row.file)[1]


def consecutive_packs(sizes: dict[str, int], max_tests: int) -> list[list[str]]:
    """Keys of ``sizes`` (key -> its tests) in their order, packed while a pack holds at most
    ``max_tests`` tests; a key of more tests is a pack of its own.  Lists of keys."""
    packs: list[list[str]] = []
    pack: list[str] = []
    n = 0
    for key, size in sizes.items():
        if pack and n + size > max_tests:
            packs.append(pack)
            pack, n = [], 0
        pack.append(key)
        n += size
    if pack:
        packs.append(pack)
    return packs


@dataclass
class Campaign:
    """A campaign folder: its three tables and where its records are."""

    root: Path
    specimens: pd.DataFrame
    setups: pd.DataFrame
    log: TestLog
    _setup_rows: dict[str, pd.DataFrame] = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def tests(self) -> pd.DataFrame:
        return self.log.tests

    @property
    def test_ids(self) -> list[str]:
        """The tests that get a results file, in the order of tests.csv: one
        per safe test_id, its first row (the others are refused rows)."""
        return [t for t in dict.fromkeys(self.tests.test_id) if not check_identifier(t, "test_id")]

    def reduction_groups(self) -> dict[str, list[str]]:
        """The tests of :attr:`test_ids` by series, in the order of tests.csv.

        What :meth:`reduction_jobs` packs by specimen; the tests refused at
        the door, whose specimen may not even be a safe name, go to the group
        ``unreadable`` (no series is called that: a series ends in ``-2s`` or
        ``-1s-cd<n>``).
        """
        groups: dict[str, list[str]] = {}
        for test_id in self.test_ids:
            key = UNREADABLE if test_id in self.log.errors else row_series(self.test_row(test_id))
            groups.setdefault(key, []).append(test_id)
        return groups

    def reduction_jobs(self, max_tests: int = TESTS_PER_JOB) -> dict[str, list[str]]:
        """The tests of each reduction job: whole specimens, in the order of tests.csv.

        A job spends longer starting Python and importing the library (about
        2 s of CPU) than reducing thirty tests, so consecutive specimens
        share a job while it holds at most ``max_tests`` tests; a specimen of
        more than ``max_tests`` tests is cut into that many near-equal parts
        of its own (two cores stay busy on a large campaign, and an edited
        row reduces at most ``max_tests`` tests again).  The tests refused
        at the door are the job :data:`UNREADABLE`.

        Returns
        -------
        dict
            Job name to test ids: ``specimen-<name>`` for one specimen,
            ``specimens-<first>+<last>`` for the specimens from ``first`` to
            ``last`` in the order of tests.csv (``+`` is in no specimen id,
            so no two jobs share a name), ``specimen-<name>-part<k>`` for
            the parts of a cut one; no specimen, being a safe identifier,
            can turn any of these into :data:`UNREADABLE`.
        """
        if max_tests < 1:
            raise ValueError(f"max_tests must be at least 1, got {max_tests}")
        groups = self.reduction_groups()
        refused = groups.pop(UNREADABLE, None)
        by_specimen: dict[str, list[str]] = {}
        for ids in groups.values():
            by_specimen.setdefault(self.test_row(ids[0]).specimen, []).extend(ids)
        jobs: dict[str, list[str]] = {}
        for pack in consecutive_packs({s: len(ids) for s, ids in by_specimen.items()}, max_tests):
            ids = by_specimen[pack[0]]
            if len(ids) > max_tests:
                n_parts = -(-len(ids) // max_tests)
                for k, part in enumerate(np.array_split(np.asarray(ids, dtype=object), n_parts), start=1):
                    jobs[f"specimen-{pack[0]}-part{k}"] = list(part)
                continue
            name = f"specimen-{pack[0]}" if len(pack) == 1 else f"specimens-{pack[0]}+{pack[-1]}"
            jobs[name] = [t for specimen in pack for t in by_specimen[specimen]]
        if refused:
            jobs[UNREADABLE] = refused
        return jobs

    def diagnosis_jobs(self, max_tests: int = TESTS_PER_JOB) -> dict[str, list[str]]:
        """The series of each diagnosis job: whole series, in the order of tests.csv.

        A job spends about 2 s starting Python and importing the library, as
        long as diagnosing a small series, so consecutive series share a job
        while it holds at most ``max_tests`` tests; a larger series is a job
        of its own (a series is diagnosed as one), so that the large series
        of a large campaign run side by side on the cores.  The tests
        refused at the door are in no series: they have no diagnosis.

        Returns
        -------
        dict
            Job name to series: ``series-<key>`` for one series,
            ``series-<first>+<last>`` for the series from ``first`` to
            ``last`` in the order of tests.csv (``+`` is in no series key).
        """
        if max_tests < 1:
            raise ValueError(f"max_tests must be at least 1, got {max_tests}")
        groups = self.reduction_groups()
        groups.pop(UNREADABLE, None)
        packs = consecutive_packs({s: len(ids) for s, ids in groups.items()}, max_tests)
        return {f"series-{p[0]}" if len(p) == 1 else f"series-{p[0]}+{p[-1]}": p for p in packs}

    @cached_property
    def _first_row(self) -> dict[str, int]:
        """Position in :attr:`tests` of the first row of each test_id (a
        lookup per test would otherwise scan the log: quadratic in its size)."""
        first: dict[str, int] = {}
        for i, test_id in enumerate(self.tests.test_id):
            first.setdefault(test_id, i)
        return first

    def test_row(self, test_id: str) -> pd.Series:
        """The row of tests.csv that is reduced for ``test_id`` (its first)."""
        return self.tests.iloc[self._first_row[test_id]]

    def record_path(self, test_id: str) -> Path:
        return self.root / self.test_row(test_id).file

    def specimen(self, name: str) -> pd.Series:
        return self._specimens_by_name.loc[name]

    @cached_property
    def _specimens_by_name(self) -> pd.DataFrame:
        # indexed once: a reduction looks a specimen up for every test
        return self.specimens.set_index("specimen")

    def setup(self, name: str) -> pd.DataFrame:
        """The rows of setups.csv of setup ``name``, by channel: one frame per setup, shared by
        every test of that setup (a reduction's job filtered the table once a test), not to be modified."""
        if name not in self._setup_rows:
            rows = self.setups[self.setups.setup == name]
            self._setup_rows[name] = rows.sort_values("channel").reset_index(drop=True)
        return self._setup_rows[name]


def row_series(row: pd.Series) -> str:
    """Series of a row of tests.csv (:func:`series_id`)."""
    return series_id(row.specimen, row.boundary, row.contact_depth_mm if row.boundary == Boundary.ONE_SIDED else np.nan)


def series_id(specimen: str, boundary: str, contact_depth_mm: float | None) -> str:
    """Series key: specimen + boundary + contact depth (docs/raw-format.md)."""
    if boundary == Boundary.TWO_SIDED or contact_depth_mm is None or not np.isfinite(contact_depth_mm):
        return f"{specimen}-2s"
    return f"{specimen}-1s-cd{int(round(contact_depth_mm))}"


def open_campaign(campaign_dir: str | Path) -> Campaign:
    """Read and cross-check the three tables of a campaign folder."""
    root = Path(campaign_dir)
    specimens = _or_empty(read_specimens, root)
    setups = _or_empty(read_setups, root)
    return Campaign(root, specimens[0], setups[0], read_tests(root, specimens, setups))
