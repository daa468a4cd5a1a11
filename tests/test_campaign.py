"""The raw-format reader: every bad input names the file, the row and the problem."""

import gzip
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rocklab.lab.campaign import UNREADABLE, open_campaign, series_id
from rocklab.lab.raw_format import CONTROL, RawFormatError, holds_any
from rocklab.lab.records import PLAIN_NUMBERS, read_record


def _rewrite(path, edit):
    text = gzip.decompress(path.read_bytes()).decode()
    path.write_bytes(gzip.compress(edit(text).encode()))


def test_reads_embedded_records(tiny_campaign):
    c = open_campaign(tiny_campaign)
    assert list(c.tests.test_id) == ["T0001", "T0027", "T0100"]
    r = read_record(c.record_path("T0001"), "T0001")
    assert r.fs == 400 and r.channels == [0, 1, 2, 3, 4]
    assert r.readings.shape == (r.time.size, 5)
    # first data row of the file: 0.0000,35.620,86.874,36.892,88.154,12.570
    np.testing.assert_allclose(r.readings[0], [35.620, 86.874, 36.892, 88.154, 12.570])
    assert read_record(c.record_path("T0027")).fs == 100
    assert len(r.sha256) == 64


def test_non_numeric_value_names_row(tiny_campaign):
    f = tiny_campaign / "tests" / "T0001.csv.gz"
    _rewrite(f, lambda s: s.replace("0.0050,35.621", "0.0050,3x.621", 1))
    with pytest.raises(RawFormatError) as err:
        read_record(f)
    assert err.value.row == 7 and "T0001.csv.gz:7" in str(err.value) and "'3x.621' is not a number" in str(err.value)


def test_truncated_gzip(tiny_campaign):
    f = tiny_campaign / "tests" / "T0001.csv.gz"
    f.write_bytes(f.read_bytes()[:5000])
    with pytest.raises(RawFormatError, match="truncated or corrupt gzip"):
        read_record(f)


def test_truncated_last_row(tiny_campaign):
    f = tiny_campaign / "tests" / "T0001.csv.gz"
    _rewrite(f, lambda s: s.rstrip("\n").rsplit(",", 2)[0] + "\n")
    with pytest.raises(RawFormatError, match="truncated row"):
        read_record(f)


def test_rate_disagrees_with_time(tiny_campaign):
    f = tiny_campaign / "tests" / "T0001.csv.gz"
    _rewrite(f, lambda s: s.replace("sampling_rate_hz: 400", "sampling_rate_hz: 100"))
    with pytest.raises(RawFormatError, match="disagrees with sampling_rate_hz 100"):
        read_record(f)


def test_missing_column_in_table(tiny_campaign):
    s = pd.read_csv(tiny_campaign / "specimens.csv").drop(columns="thickness_mm")
    s.to_csv(tiny_campaign / "specimens.csv", index=False)
    c = open_campaign(tiny_campaign)
    # every test refused, naming the table's fault: the campaign goes on to its QC table
    assert set(c.log.errors) == set(c.test_ids) == {"T0001", "T0027", "T0100"}
    assert all("specimens.csv:1: missing column(s) thickness_mm" in str(e) for e in c.log.errors.values())


def test_bad_rows_of_the_log_are_set_apart(tiny_campaign):
    t = pd.read_csv(tiny_campaign / "tests.csv", dtype=str, keep_default_na=False)
    extra = t.iloc[[0, 1, 2]].copy()
    extra.loc[:, "test_id"] = ["T0001", "T9001", "T9002"]
    extra.iloc[1, extra.columns.get_loc("specimen")] = "9z"
    extra.iloc[2, extra.columns.get_loc("setup")] = "S-nowhere"
    pd.concat([t, extra]).to_csv(tiny_campaign / "tests.csv", index=False)
    c = open_campaign(tiny_campaign)
    msgs = {k: str(v) for k, v in c.log.errors.items()}
    assert "duplicated test_id T0001: the row at line 2 is the one reduced" in msgs["T0001@5"]
    assert "tests.csv:5" in msgs["T0001@5"]
    assert "unknown specimen '9z'" in msgs["T9001"]
    assert "unknown setup 'S-nowhere'" in msgs["T9002"]
    assert "T0027" not in msgs


def test_header_test_id_must_match(tiny_campaign):
    f = tiny_campaign / "tests" / "T0001.csv.gz"
    with pytest.raises(RawFormatError, match="header test_id 'T0001' but tests.csv says 'T0002'"):
        read_record(f, expected_test_id="T0002")


def test_series_id():
    assert series_id("2a", "two-sided", np.nan) == "2a-2s"
    assert series_id("2a", "one-sided", 60.0) == "2a-1s-cd60"


#: Fields of a record's data rows: numbers as the lab writes them, blanks, a
#: number too large for a float, and what is no number (malformed, or a word
#: pandas would read as one).
FIELDS = ["1", "1.5", " 2", " 3 ", "\t4", "", " ", "+.5", "5.", "1E3", "-0", "0.1234567890123456789", "1e-400"]
INFINITE = ["1e400", "-1e400"]
FIELDS_BAD = ["1e", "1.2.3", "--1", "+", "-", ".", "e5", "1e+", "1 2", "1-", "1e5.5", "0x10", "1_000", "nan", "inf"]


def _python_float(field):
    """The independent parse of a field: Python's correctly rounded float(), NaN for a blank."""
    return float(field) if field.strip() else np.nan


@pytest.mark.parametrize("seed", range(5))
def test_fields_read_as_python_reads_them(tmp_path, seed):
    """Whichever of the two parsers of records._numbers reads a record (the
    fast one for plain decimals, field by field otherwise), a number is
    Python's float of its text, a blank is NaN and anything else is an
    error naming the row and the field (the first that is no number, else
    the first infinite one)."""
    from rocklab.lab.records import _numbers

    rng = np.random.default_rng(seed)
    for _ in range(200):
        rows = [[str(rng.choice(FIELDS + INFINITE + FIELDS_BAD[: seed * 3])) for _ in range(3)] for _ in range(4)]
        body = "\n".join(",".join(r) for r in rows)
        bad = [(i, j, "") for i, r in enumerate(rows) for j, f in enumerate(r) if f in FIELDS_BAD]
        bad += [(i, j, "finite ") for i, r in enumerate(rows) for j, f in enumerate(r) if f in INFINITE]
        if bad:
            i, j, finite = bad[0]
            with pytest.raises(RawFormatError, match=rf"f\.csv:{10 + i}: c{j}: .* is not a {finite}number"):
                _numbers(body, ["c0", "c1", "c2"], "f.csv", 10)
        else:
            got = _numbers(body, ["c0", "c1", "c2"], "f.csv", 10)
            expected = np.array([[_python_float(f) for f in r] for r in rows])
            np.testing.assert_array_equal(got, expected)


def test_embedded_records_read_as_python_reads_them():
    """Records of the embedded campaign, some with lost samples (blank fields): every
    value is Python's float of its text (bit for bit: the fast path is exact)."""
    campaign = open_campaign(Path(__file__).resolve().parents[1] / "raw" / "campaign")
    for k, test_id in enumerate(campaign.test_ids):
        path = campaign.record_path(test_id)
        rows = [ln.split(",") for ln in gzip.decompress(path.read_bytes()).decode().splitlines()[4:]]
        if k % 61 and all(all(r) for r in rows):
            continue
        expected = np.array([[_python_float(f) for f in r] for r in rows])
        r = read_record(path)
        np.testing.assert_array_equal(np.column_stack([r.time, r.readings]), expected)


@pytest.mark.parametrize("max_tests", [1, 40, 150, 10_000])
def test_reduction_jobs_pack_whole_specimens(max_tests):
    """Every test in exactly one job, in the order of tests.csv; a job holds whole
    consecutive specimens up to ``max_tests`` tests, or a part of one larger specimen."""
    campaign = open_campaign(Path(__file__).resolve().parents[1] / "raw" / "campaign")
    jobs = campaign.reduction_jobs(max_tests)
    flat = [t for ids in jobs.values() for t in ids]
    assert flat == campaign.test_ids
    specimen = {t: campaign.test_row(t).specimen for t in flat}
    sizes = pd.Series(specimen).value_counts()
    for name, ids in jobs.items():
        held = list(dict.fromkeys(specimen[t] for t in ids))
        if "-part" in name:
            assert len(held) == 1 and sizes[held[0]] > max_tests and len(ids) <= max_tests
            continue
        # whole specimens, never more than max_tests of them together
        assert all(sum(specimen[t] == s for t in ids) == sizes[s] for s in held)
        assert len(ids) <= max_tests or len(held) == 1
        assert name == (f"specimen-{held[0]}" if len(held) == 1 else f"specimens-{held[0]}+{held[-1]}")
    if max_tests >= len(flat):
        assert len(jobs) == 1


@pytest.mark.parametrize("max_tests", [1, 40, 150, 10_000])
def test_diagnosis_jobs_pack_whole_series(max_tests):
    """Every series in exactly one job, in the order of tests.csv; a job holds whole
    consecutive series up to ``max_tests`` tests, or one larger series alone."""
    campaign = open_campaign(Path(__file__).resolve().parents[1] / "raw" / "campaign")
    groups = {s: ids for s, ids in campaign.reduction_groups().items() if s != UNREADABLE}
    jobs = campaign.diagnosis_jobs(max_tests)
    assert [s for series in jobs.values() for s in series] == list(groups)
    for name, series in jobs.items():
        n = sum(len(groups[s]) for s in series)
        assert n <= max_tests or len(series) == 1
        assert name == (f"series-{series[0]}" if len(series) == 1 else f"series-{series[0]}+{series[-1]}")
    # a pack closes only where the next series would take it past max_tests
    packs = list(jobs.values())
    for first, second in zip(packs, packs[1:]):
        assert sum(len(groups[s]) for s in [*first, second[0]]) > max_tests
    if max_tests >= sum(map(len, groups.values())):
        assert len(jobs) == 1


@pytest.mark.parametrize("characters", [CONTROL, PLAIN_NUMBERS], ids=["control", "not a number"])
def test_holds_any_answers_as_the_search(characters):
    """The reader's fast check of a record's characters says what the regular expression says, for
    every ASCII character and for text beyond ASCII (Unicode blanks, which the ``\\s`` of a str pattern takes)."""
    base = "0.125,-1.5e-3, 7\n"
    texts = [base, "", *(base + chr(c) + base for c in range(128))]
    texts += [base + c for c in ("\u00a0", "\u2003", "\u2028", "\u00e9", "\u0661", "\x85")]
    for text in texts:
        assert holds_any(characters, text) == (characters.search(text) is not None), repr(text)


def test_a_setup_is_filtered_once_and_as_the_table_says(tiny_campaign):
    camp = open_campaign(tiny_campaign)
    for name in camp.setups.setup.unique():
        rows = camp.setup(name)
        expected = camp.setups[camp.setups.setup == name].sort_values("channel").reset_index(drop=True)
        pd.testing.assert_frame_equal(rows, expected)
        assert camp.setup(name) is rows  # kept for the job's next test
    assert camp.setup("no such setup").empty
