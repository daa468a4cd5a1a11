"""Hostile and broken campaigns: every bad input is a row of qc.csv, nothing else changes.

Each kind of corruption is applied to a copy of one small virtual-lab
campaign and read by the functions the workflow calls (``open_campaign``,
``reduce_tests``, ``qc_table``).  For each kind: the campaign is reduced to
the end, the bad test is flagged with the right reason and a detail naming
the file, the line or column and the problem, every good test is reduced
exactly as without the bad one, and the campaign folder is byte-identical
afterwards.  One workflow run carries several attacks at once and checks
that nothing is read or written outside its two folders.
"""

import gzip
import hashlib
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rocklab.config import ConfigError, check_names, check_paths
from rocklab.lab.campaign import open_campaign
from rocklab.lab.reduction import qc_table, reduce_tests

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")

pytest.importorskip("rocklab.simulation.rocking_model")
from rocklab.lab import virtual_lab  # noqa: E402

GOOD = ["V0001", "V0002", "V0003"]
BAD = "X0001"


def tree_state(folder):
    """Kind, modification time and content hash of everything under folder, by
    relative path (a folder's time aside: it changes when a sibling is made and removed)."""
    out = {}
    for p in sorted(Path(folder).rglob("*")):
        st = p.lstat()
        if p.is_symlink():
            what = os.readlink(p)
        elif p.is_file():
            what = hashlib.sha256(p.read_bytes()).hexdigest()
        else:
            what = ""
        out[p.relative_to(folder).as_posix()] = (st.st_mode, None if p.is_dir() else st.st_mtime_ns, what)
    return out


def tree_hash(folder):
    """One hash of :func:`tree_state`."""
    return hashlib.sha256(repr(sorted(tree_state(folder).items())).encode()).hexdigest()


def reduce_campaign(folder):
    """What the workflow makes of a campaign: the QC table and the motion of each test."""
    c = open_campaign(folder)
    reduced = dict(reduce_tests(c, c.test_ids))
    qc = qc_table(reduced.values(), c)
    theta = {t: ds.theta.values for t, ds in reduced.items() if "theta" in ds}
    return qc, theta


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    folder = tmp_path_factory.mktemp("hostile") / "base"
    virtual_lab.write_campaign(folder, virtual_lab.default_plan(3, seed=3), seed=3)
    qc, theta = reduce_campaign(folder)
    assert list(qc.test_id) == GOOD
    return folder, qc.set_index("test_id"), theta


# --- the corruptions: each edits a copy of the campaign in place ---------------------------------------------


def _table(folder, name):
    return pd.read_csv(folder / name, dtype=str, keep_default_na=False)


def _record_text(folder, test_id="V0001"):
    return gzip.decompress((folder / "tests" / f"{test_id}.csv.gz").read_bytes()).decode()


def add_test(folder, record=None, source="V0001", **row):
    """Append a copy of the row of test ``source`` to tests.csv, with ``row``
    changed; ``record`` (text -> text, or bytes) gives the new test's file
    from the source's."""
    tests = _table(folder, "tests.csv")
    new = tests[tests.test_id == source].copy()
    new.loc[:, "test_id"] = BAD
    new.loc[:, "file"] = f"tests/{BAD}.csv.gz"
    for k, v in row.items():
        new.loc[:, k] = v
    pd.concat([tests, new]).to_csv(folder / "tests.csv", index=False)
    if record is not None:
        text = _record_text(folder, source).replace(f"# test_id: {source}", f"# test_id: {BAD}")
        blob = record if isinstance(record, bytes) else gzip.compress(record(text).encode(), mtime=0)
        (folder / "tests" / f"{BAD}.csv.gz").write_bytes(blob)


def add_specimen(folder, **row):
    """A new specimen 9z (a copy of 1a with ``row`` changed) and a test of it."""
    spec = _table(folder, "specimens.csv")
    new = spec[spec.specimen == "1a"].copy()
    new.loc[:, "specimen"] = "9z"
    for k, v in row.items():
        new.loc[:, k] = v
    pd.concat([spec, new]).to_csv(folder / "specimens.csv", index=False)
    add_test(folder, record=lambda s: s, specimen=row.get("specimen", "9z"))


def add_setup(folder, edit):
    """A new setup S-bad (V0001's, edited by ``edit``) and a test using it."""
    setups = _table(folder, "setups.csv")
    used = _table(folder, "tests.csv").setup.iloc[0]
    new = setups[setups.setup == used].copy().reset_index(drop=True)
    new.loc[:, "setup"] = "S-bad"
    pd.concat([setups, edit(new)]).to_csv(folder / "setups.csv", index=False)
    add_test(folder, record=lambda s: s, setup="S-bad")


def _lines(text, edit):
    """Apply edit(list of lines) to the record's lines."""
    lines = text.split("\n")
    edit(lines)
    return "\n".join(lines)


def _data_row(k):
    """Line index (0-based) of the k-th data row of a virtual-lab record (4 lines of header)."""
    return 4 + k


def _set(lines, i, value):
    lines[i] = value


def _drop_columns(text, channels):
    rows = [ln.split(",") for ln in text.rstrip("\n").split("\n")[3:]]
    keep = [j for j, name in enumerate(rows[0]) if name not in {f"ch{c}" for c in channels}]
    head = "\n".join(text.split("\n")[:3])
    return head + "\n" + "\n".join(",".join(r[j] for j in keep) for r in rows) + "\n"


def _outside_symlink(folder):
    target = folder.parent / f"{folder.name}-outside.csv.gz"
    target.write_bytes((folder / "tests" / "V0001.csv.gz").read_bytes())
    (folder / "tests" / "link.csv.gz").symlink_to(target)
    add_test(folder, file="tests/link.csv.gz")


def _folder_as_file(folder):
    (folder / "tests" / "adir.csv.gz").mkdir()
    add_test(folder, file="tests/adir.csv.gz")


def _tests_csv_bytes(folder, edit):
    path = folder / "tests.csv"
    path.write_bytes(edit(path.read_bytes()))


def _bad_row_bytes(folder, field_bytes):
    add_test(folder, record=lambda s: s)
    _tests_csv_bytes(folder, lambda b: b.rstrip(b"\n") + field_bytes + b"\n")


def row_kind(problem, where="tests.csv:5", **row):
    """The kind of a new row of tests.csv (V0001's with ``row`` changed, its record a copy of
    V0001's unless a ``file`` is given), refused at ``where`` for ``problem``."""
    record = None if "file" in row else (lambda s: s)
    return lambda f: add_test(f, record=record, **row), {row.get("test_id", BAD): ("unreadable", [where, problem])}


def replaced(old, new, line, problem):
    """The kind of a record of V0001 with ``old`` replaced by ``new``, refused at ``line`` for ``problem``."""
    where = f"{BAD}.csv.gz:{line}" if line else f"{BAD}.csv.gz"
    return lambda f: add_test(f, record=lambda s: s.replace(old, new)), {BAD: ("unreadable", [where, problem])}


#: name -> (corruption, expected {test_id: (reason, [substrings of the detail])}); a test_id that cannot
#: name a file is matched on the qc.csv row that carries it as data.
KINDS = {
    # names and paths
    "test_id climbing out": row_kind("not a safe name", test_id="../../../pwned"),
    "test_id with a slash": row_kind("'a/b' is not a safe name", test_id="a/b"),
    "hidden test_id": row_kind("not a safe name", test_id=".hidden"),
    "empty test_id": row_kind("empty test_id", test_id=""),
    "file climbing out": row_kind("'../../outside.csv.gz' leaves the campaign folder", file="../../outside.csv.gz"),
    "absolute file": row_kind("'/etc/passwd' leaves the campaign folder", file="/etc/passwd"),
    "symbolic link out": (
        _outside_symlink,
        {BAD: ("unreadable", ["tests.csv:5", "leads outside the campaign folder"])},
    ),
    "file is a folder": (_folder_as_file, {BAD: ("unreadable", ["adir.csv.gz", "not a regular file"])}),
    "file not found": row_kind("file not found", where="nowhere.csv.gz", file="tests/nowhere.csv.gz"),
    "empty file column": row_kind("empty file", file=""),
    "unsafe specimen name": (
        lambda f: add_specimen(f, specimen="../x"),
        {BAD: ("unreadable", ["specimens.csv:6", "specimen '../x' is not a safe name"])},
    ),
    # tests.csv
    "duplicated test_id, other file": row_kind(
        "the row at line 3 is the one reduced, this one is refused", test_id="V0002"
    ),
    "unknown specimen": row_kind("unknown specimen 'nowhere'", specimen="nowhere"),
    "unknown setup": row_kind("unknown setup 'S-nowhere'", setup="S-nowhere"),
    "bad boundary": row_kind("boundary 'three-sided'", boundary="three-sided"),
    "bad direction": row_kind("direction 'sideways'", direction="sideways"),
    "one-sided without contact depth": row_kind(
        "without a positive contact_depth_mm", boundary="one-sided", contact_depth_mm=""
    ),
    "contact depth not a number": row_kind(
        "column contact_depth_mm: '12O' is not a number", boundary="one-sided", contact_depth_mm="12O"
    ),
    "negative contact depth": row_kind(
        "without a positive contact_depth_mm", boundary="one-sided", contact_depth_mm="-120"
    ),
    "truncated row of tests.csv": (
        lambda f: (add_test(f, record=lambda s: s), _tests_csv_bytes(f, lambda b: b.rsplit(b",", 5)[0] + b"\n")),
        {BAD: ("unreadable", ["tests.csv:5", "truncated row: 3 fields, expected 8"])},
    ),
    "too many fields in tests.csv": (
        lambda f: _bad_row_bytes(f, b",extra,fields"),
        {BAD: ("unreadable", ["tests.csv:5", "too many fields: 10 fields, expected 8"])},
    ),
    "tests.csv row not UTF-8": (
        lambda f: _bad_row_bytes(f, b"caf\xe9"),
        {BAD: ("unreadable", ["tests.csv:5", "not UTF-8 text"])},
    ),
    "NUL in tests.csv": (
        lambda f: _bad_row_bytes(f, b"\x00"),
        {BAD: ("unreadable", ["tests.csv:5", "control character"])},
    ),
    # specimens.csv and setups.csv
    "zero thickness": (
        lambda f: add_specimen(f, thickness_mm="0"),
        {BAD: ("unreadable", ["specimen '9z' refused", "specimens.csv:6", "thickness_mm: 0 must be positive"])},
    ),
    "negative height": (
        lambda f: add_specimen(f, height_mm="-1090"),
        {BAD: ("unreadable", ["specimens.csv:6", "height_mm: -1090 must be positive"])},
    ),
    "dimension not a number": (
        lambda f: add_specimen(f, length_mm="1,4 m"),
        {BAD: ("unreadable", ["specimens.csv:6"])},
    ),
    "specimen twice, other values": (
        lambda f: (add_specimen(f), _append_line(f / "specimens.csv", "9z,1,clay brick,1420,1090,200,18.1")),
        {BAD: ("unreadable", ["specimens.csv:7", "specimen 9z given at lines 6, 7 with other values"])},
    ),
    "setup points coincide": (
        lambda f: add_setup(
            f, lambda s: s.assign(frame_x_mm=s.wall_x_mm, frame_y_mm=s.wall_y_mm, frame_z_mm=s.wall_z_mm)
        ),
        {BAD: ("unreadable", ["setup 'S-bad' refused", "setups.csv:", "wall and frame points coincide"])},
    ),
    "setup channel not an integer": (
        lambda f: add_setup(f, lambda s: s.assign(channel=s.channel.where(s.index != 2, "2.5"))),
        {BAD: ("unreadable", ["setups.csv:", "column channel: '2.5' is not an integer"])},
    ),
    "setup channel twice, other points": (
        lambda f: add_setup(f, lambda s: pd.concat([s, s.iloc[[1]].assign(wall_z_mm="1")])),
        {BAD: ("unreadable", ["setups.csv:", "setup/channel S-bad/1 given at lines"])},
    ),
    # the record as a file
    "truncated gzip": (
        lambda f: add_test(f, record=gzip.compress(_record_text(f).encode(), mtime=0)[:3000]),
        {BAD: ("unreadable", [f"{BAD}.csv.gz", "truncated or corrupt gzip"])},
    ),
    "not gzip": (
        lambda f: add_test(f, record=_record_text(f).encode()),
        {BAD: ("unreadable", [f"{BAD}.csv.gz", "truncated or corrupt gzip"])},
    ),
    "empty record": (
        lambda f: add_test(f, record=b""),
        {BAD: ("unreadable", [f"{BAD}.csv.gz:1", "no header row and no data"])},
    ),
    "header only": (
        lambda f: add_test(f, record=lambda s: "\n".join(s.split("\n")[:4]) + "\n"),
        {BAD: ("unreadable", [f"{BAD}.csv.gz:5", "no data rows"])},
    ),
    "record not UTF-8": (
        lambda f: add_test(f, record=gzip.compress(b"# test_id: X0001\n# caf\xe9\n", mtime=0)),
        {BAD: ("unreadable", [f"{BAD}.csv.gz", "not UTF-8 text"])},
    ),
    # the record's header
    "rate disagrees with time": replaced(
        "sampling_rate_hz: 400", "sampling_rate_hz: 500", 6, "disagrees with sampling_rate_hz 500"
    ),
    "no sampling rate": replaced("# sampling_rate_hz: 400\n", "", 1, "missing '# sampling_rate_hz:'"),
    "negative sampling rate": replaced("rate_hz: 400", "rate_hz: -400", 1, "sampling_rate_hz must be positive"),
    "bad units": replaced("# units: s, mm", "# units: ms, in", 1, "units 'ms, in'"),
    "header names another test": replaced(
        f"# test_id: {BAD}", "# test_id: V0002", 1, "header test_id 'V0002' but tests.csv says 'X0001'"
    ),
    "bad header row": replaced("time_s,", "t,", 4, "header row must be time_s,ch0,ch1"),
    "channel twice in the header": replaced(",ch4", ",ch3", 4, "a channel appears twice"),
    "channel not in setups.csv": replaced(",ch4", ",ch7", "", "channel(s) [7] not described in setups.csv"),
    # the record's values
    "truncated last row": (
        lambda f: add_test(f, record=lambda s: s.rstrip("\n").rsplit(",", 2)[0] + "\n"),
        {BAD: ("unreadable", [f"{BAD}.csv.gz:", "truncated row: 4 fields, expected 6"])},
    ),
    "too many fields in a row": (
        lambda f: add_test(f, record=lambda s: _lines(s, lambda ln: _set(ln, _data_row(9), ln[_data_row(9)] + ",1"))),
        {BAD: ("unreadable", [f"{BAD}.csv.gz:14", "too many fields: 7 fields, expected 6"])},
    ),
    "value not a number": (
        lambda f: add_test(f, record=lambda s: _lines(s, lambda ln: _set(ln, _data_row(2), ln[_data_row(2)] + "x"))),
        {BAD: ("unreadable", [f"{BAD}.csv.gz:7", "ch4:", "is not a number"])},
    ),
    "infinite value": (
        lambda f: add_test(
            f,
            record=lambda s: _lines(s, lambda ln: _set(ln, _data_row(3), ln[_data_row(3)].rsplit(",", 1)[0] + ",inf")),
        ),
        {BAD: ("unreadable", [f"{BAD}.csv.gz:8", "ch4: 'inf' is not a finite number"])},
    ),
    "repeated time": (
        lambda f: add_test(f, record=lambda s: _lines(s, lambda ln: _set(ln, _data_row(5), ln[_data_row(4)]))),
        {BAD: ("unreadable", [f"{BAD}.csv.gz:10", "repeats the previous row's"])},
    ),
    "time going back": (
        lambda f: add_test(
            f, record=lambda s: _lines(s, lambda ln: _set(ln, _data_row(5), "0.0000" + ln[_data_row(5)][6:]))
        ),
        {BAD: ("unreadable", [f"{BAD}.csv.gz:10", "goes back"])},
    ),
    "empty time": (
        lambda f: add_test(f, record=lambda s: _lines(s, lambda ln: _set(ln, _data_row(5), ln[_data_row(5)][6:]))),
        {BAD: ("unreadable", [f"{BAD}.csv.gz:10", "empty time_s"])},
    ),
    "NUL in the record": (
        lambda f: add_test(f, record=lambda s: _lines(s, lambda ln: _set(ln, _data_row(5), ln[_data_row(5)] + "\x00"))),
        {BAD: ("unreadable", [f"{BAD}.csv.gz:10", "control character"])},
    ),
    # channels missing from the record: what the backup is for
    "two channels missing": (
        lambda f: add_test(f, record=lambda s: _drop_columns(s, [1, 3])),
        {
            BAD: (
                "instrument_malfunction",
                ["2 out-of-plane channel(s) lost (ch1 not in the record, ch3 not in the record)"],
            )
        },
    ),
}


def _append_line(path, line):
    path.write_bytes(path.read_bytes() + line.encode() + b"\n")


def _check_good(qc, theta, base_qc, base_theta, good=GOOD):
    got = qc.drop_duplicates("test_id").set_index("test_id")
    for t in good:
        assert got.loc[t].equals(base_qc.loc[t]), (t, got.loc[t], base_qc.loc[t])
        np.testing.assert_array_equal(theta[t], base_theta[t])


@pytest.mark.parametrize("kind", list(KINDS))
def test_a_bad_input_is_one_row_of_qc(kind, base, tmp_path):
    folder, base_qc, base_theta = base
    work = tmp_path / "campaign"
    shutil.copytree(folder, work, symlinks=True)
    corrupt, expected = KINDS[kind]
    corrupt(work)
    before = tree_hash(work)
    qc, theta = reduce_campaign(work)
    assert tree_hash(work) == before
    _check_good(qc, theta, base_qc, base_theta)
    flagged = qc.iloc[len(GOOD) :] if kind.startswith("duplicated") else qc[~qc.test_id.isin(GOOD)]
    assert len(flagged) == 1, qc
    row = flagged.iloc[0]
    ((test_id, (reason, detail)),) = expected.items()
    assert row.test_id == test_id and not row.valid and row.reject_reason == reason, row
    for part in detail:
        assert part in row.reject_detail, (part, row.reject_detail)
    # an id that cannot name a file has none
    assert set(theta) <= {t for t in qc.test_id if t in GOOD or t == BAD}


def test_harmless_variations_are_read(base, tmp_path):
    """A byte-order mark, CRLF line ends, blanks, blank lines and an extra column change nothing."""
    folder, base_qc, base_theta = base
    work = tmp_path / "campaign"
    shutil.copytree(folder, work)
    for name in ("tests.csv", "specimens.csv", "setups.csv"):
        text = (work / name).read_text()
        lines = text.rstrip("\n").split("\n")
        lines[0] += ",extra"
        lines[1:] = [ln.replace(",", " , ") + ",x" for ln in lines[1:]]
        (work / name).write_bytes(b"\xef\xbb\xbf" + ("\r\n".join(lines) + "\r\n\r\n").encode())
    for t in GOOD:
        path = work / "tests" / f"{t}.csv.gz"
        text = gzip.decompress(path.read_bytes()).decode()
        path.write_bytes(gzip.compress(("\ufeff" + text.replace("\n", "\r\n")).encode(), mtime=0))
    qc, theta = reduce_campaign(work)
    _check_good(qc, theta, base_qc, base_theta)
    assert len(qc) == len(GOOD)


def test_a_missing_channel_3_is_replaced_by_the_backup(base, tmp_path):
    """The verdict agrees with its detail: channel 2 stands in, as for a dead channel 3."""
    folder, base_qc, base_theta = base
    work = tmp_path / "campaign"
    shutil.copytree(folder, work)
    add_test(work, record=lambda s: _drop_columns(s, [3]))
    qc, theta = reduce_campaign(work)
    _check_good(qc, theta, base_qc, base_theta)
    row = qc.set_index("test_id").loc[BAD]
    # V0001 has channel 1 dead: without channel 3 too, two are lost and the test is rejected
    assert row.reject_reason == "instrument_malfunction"
    assert row.reject_detail == "2 out-of-plane channel(s) lost (ch1, ch3 not in the record)"
    # V0002 has all of channels 0-3: without channel 3 the backup stands in and the test is valid
    work = tmp_path / "campaign2"
    shutil.copytree(folder, work)
    add_test(work, record=lambda s: _drop_columns(s, [3]), source="V0002")
    row = reduce_campaign(work)[0].set_index("test_id").loc[BAD]
    assert row.valid and "ch3 not in the record" in row["flags"] and "backup ch2 used" in row["flags"]
    assert row.channels_used == "ch0 ch1 ch2"


def test_results_dir_and_raw_dir_kept_apart(tmp_path):
    raw = tmp_path / "results" / "campaign"
    raw.mkdir(parents=True)
    (raw / "tests.csv").write_text("test_id\n")
    with pytest.raises(ConfigError, match="is inside results_dir"):
        check_paths(raw, tmp_path / "results")
    (tmp_path / "afile").write_text("")
    with pytest.raises(ConfigError, match="is a file"):
        check_paths(raw, tmp_path / "afile")


@pytest.mark.parametrize(
    "section, key, value",
    [
        ("figures", "sample_test", "../../../etc/passwd"),
        ("figures", "fig20_test", "T9999"),
        ("maps", "figure_record", "../../x"),
        ("maps", "records", ["Pac164", "../../../x"]),
    ],
)
def test_names_in_the_config_must_be_inputs(section, key, value):
    """A test or record the config names becomes a file name: one the inputs lack is refused."""
    config = {"figures": {"sample_test": "", "fig20_test": ""}, "maps": {"records": [], "figure_record": "Pac164"}}
    check_names(config, ["V0001"], {"Pac164"})
    config[section][key] = value
    with pytest.raises(ConfigError, match=f"config key {section}.{key}"):
        check_names(config, ["V0001"], {"Pac164"})


@pytest.mark.skipif(not SNAKEMAKE.exists(), reason="snakemake not installed beside this interpreter")
def test_the_workflow_never_reads_or_writes_outside_its_folders(tmp_path, tmp_path_factory):
    """Several attacks at once through the workflow, to the QC table.

    The file outside the campaign is a named pipe: opening it would block
    the run (and the timeout would fail the test), stat-ing it does not.
    Snakemake's working directory (its locks and metadata) is a folder of
    the test's own outside ``tmp_path``, so that the watched tree holds only
    the campaign and the results.
    """
    box = tmp_path / "a" / "b"
    folder, results = box / "campaign", box / "results"
    virtual_lab.write_campaign(folder, virtual_lab.default_plan(3, seed=3), seed=3)
    add_test(folder, record=lambda s: s, test_id="../../../pwned")
    tests = _table(folder, "tests.csv")
    extra = tests.iloc[[0, 0, 0]].copy()
    extra["test_id"] = ["X0002", "V0002", "X0003"]
    extra["file"] = ["../../outside.csv.gz", "tests/X0001.csv.gz", "/etc/hostname"]
    pd.concat([tests, extra]).to_csv(folder / "tests.csv", index=False)
    os.mkfifo(tmp_path / "a" / "outside.csv.gz")
    config = tmp_path / "a" / "config.yaml"
    config.write_text("figures: {fig9_specimen: 1a}\n")
    before = tree_state(tmp_path)
    workdir = tmp_path_factory.mktemp("workdir")
    cmd = [str(SNAKEMAKE), str(results / "qc.csv"), "--cores", "2", "--quiet"]
    cmd += ["--snakefile", str(ROOT / "Snakefile"), "--directory", str(workdir), "--configfile", str(config)]
    cmd += ["--config", f"raw_dir={folder}", f"results_dir={results}"]
    run = subprocess.run(cmd, capture_output=True, text=True, cwd=workdir, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    qc = pd.read_csv(results / "qc.csv", dtype=str, keep_default_na=False)
    assert {p.name for p in (results / "tests").rglob("*.nc")} == {f"{t}.nc" for t in [*GOOD, "X0002", "X0003"]}
    # nothing outside results/ written, nothing named pwned anywhere
    shutil.rmtree(results)
    after = tree_state(tmp_path)
    assert after == before, {
        k: (before.get(k), after.get(k)) for k in set(before) | set(after) if before.get(k) != after.get(k)
    }
    assert not [p for d in (tmp_path, workdir, ROOT) for p in d.rglob("*pwned*")]
    refused = qc.set_index("test_id").reject_detail
    assert "not a safe name" in refused["../../../pwned"]
    assert "leaves the campaign folder" in refused["X0002"] and "leaves the campaign folder" in refused["X0003"]
    assert "the row at line 3 is the one reduced" in qc.reject_detail.iloc[-1]
    assert list(qc.valid.iloc[: len(GOOD)]) == ["True", "True", "False"] and list(qc.test_id.iloc[:3]) == GOOD
