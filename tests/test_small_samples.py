"""Honest small samples: every interval says what it rests on, none is given from too few.

A campaign of two valid tests used to print a Table 3 cell ``0.949 [nan,
nan]`` and a diagnosis ``alpha_r_over_alpha = 0.9088 [0.9088, 0.9088]``
naming causes from two tests; below
:data:`rocklab.inference.intervals.MIN_BOOTSTRAP` units a table's value
comes without an interval, marked, and a series of two to four tests names a
cause on the t interval of its few degrees of freedom (issue 24), a series of
one test none.
"""

import logging
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from test_diagnosis import SCENARIOS, virtual_series

from rocklab import diagnosis as D
from rocklab.dissipation.statistics import TABLE3_WINDOWS, boundary_summary, series_stats, table3, table3_markdown
from rocklab.inference.intervals import MIN_BOOTSTRAP, bootstrap_ci
from rocklab.lab.campaign import open_campaign


def ratio_table(n_by_series, boundary="two-sided", seed=0):
    """tests.csv-like rows: ``n`` tests of each series, ratios around 0.95; each series a specimen of its
    own (its wall: :func:`own_walls`)."""
    rng = np.random.default_rng(seed)
    rows = [
        {"series": s, "specimen": s, "boundary": boundary, "e_ratio": 0.95 + 0.01 * rng.standard_normal()}
        for s, n in n_by_series.items()
        for _ in range(n)
    ]
    df = pd.DataFrame(rows)
    for c in TABLE3_WINDOWS:
        df[c] = df.e_ratio
    return df


def own_walls(df):
    """Each specimen a wall of its own."""
    return {sp: f"wall {sp}" for sp in df.specimen}


def test_the_minimum_is_where_a_bootstrap_starts():
    x = np.linspace(0.9, 1.0, MIN_BOOTSTRAP)
    assert np.isnan(bootstrap_ci(x[:-1])).all()
    lo, hi = bootstrap_ci(x)
    assert lo < x.mean() < hi


def test_a_two_test_series_has_its_mean_and_no_interval():
    st = series_stats(ratio_table({"tiny": 2, "full": 12}), columns=("e_ratio",)).set_index("series")
    tiny, full = st.loc["tiny"], st.loc["full"]
    assert tiny.e_ratio_n == 2 and np.isfinite(tiny.e_ratio_mean)
    assert np.isnan(tiny.e_ratio_ci_low) and np.isnan(tiny.e_ratio_ci_high)
    assert tiny.ci_note == "too few tests for an interval (2 < 5)"
    assert full.e_ratio_n == 12 and full.e_ratio_ci_low < full.e_ratio_mean < full.e_ratio_ci_high
    assert full.ci_note == ""


def test_a_quantity_short_of_tests_is_named_in_the_note():
    df = ratio_table({"s": 6}).assign(T_quarter_p=[7.0, 7.1, np.nan, np.nan, np.nan, 7.2])
    row = series_stats(df, columns=("e_ratio", "T_quarter_p")).iloc[0]
    assert row.ci_note == "too few tests for an interval (3 < 5): T_quarter_p"
    assert np.isfinite(row.e_ratio_ci_low) and np.isnan(row.T_quarter_p_ci_low)


def test_table3_of_two_tests_is_marked_not_nan():
    """The issue's campaign: two valid tests, one series of each boundary condition."""
    df = pd.concat([ratio_table({"a-2s": 1}), ratio_table({"b-1s": 1}, "one-sided")], ignore_index=True)
    t3 = table3(df, own_walls(df))
    assert t3.ci_low.isna().all() and t3.ci_high.isna().all()
    assert set(t3.ci_note) == {"1 wall, 0 residual df (2 needed): no interval"}
    assert (t3.n_tests == 1).all() and (t3.n_series == 1).all() and (t3.n_walls == 1).all()
    md = table3_markdown(t3)
    assert "nan" not in md and "[" not in md
    assert md.count("†") == 7  # six values and the note
    assert md.endswith("† 1 wall, 0 residual df (2 needed): no interval")
    assert f"{df.e_ratio[0]:.3f}† (1 test, 1 series, 1 wall)" in md


def test_a_normal_boundary_gives_intervals_with_their_counts():
    df = ratio_table({f"s{i}": 4 + i for i in range(6)})
    b = boundary_summary(df, ["e_ratio"], own_walls(df)).iloc[0]
    assert b.n_tests == sum(4 + i for i in range(6)) and b.n_series == 6 and b.n_walls == 6 and b.ci_note == ""
    md = table3_markdown(table3(df, own_walls(df)))
    cell = f"{b['mean']:.3f} [{b.ci_low:.3f}, {b.ci_high:.3f}] ({b.n_tests} tests, 6 series, 6 walls)"
    assert cell in md and "†" not in md


@pytest.fixture(scope="module")
def series_of():
    """Virtual-lab records of a two-sided series with a lower instability angle and a scaled e."""
    boundary, model, kw, _ = SCENARIOS["instability+scale"]
    return lambda n: virtual_series("small", boundary, model, n=n, seed=3, **kw)


def test_a_two_test_series_names_its_causes_on_one_degree_of_freedom(series_of):
    e = D.diagnose_records(series_of(2), "tiny", n_boot=10, n_history=0)
    assert e.n_tests == 2 and e.too_small is None
    assert e.verdict == ["instability_angle", "restitution_scale"]
    # a drift between tests is a slope over tests: two tests cannot carry it, and the entry says so
    assert list(e.not_identifiable) == ["restitution_drift"]
    assert e.not_identifiable["restitution_drift"].endswith("needs 4 of them, the series has 2")
    assert "Not identifiable in this series, its absence from the verdict says nothing: restitution_drift (a drift" in (
        D.diagnosis_markdown([e])
    )
    truth = {"alpha_r_over_alpha": 0.9, "c": 0.95}
    for f in e.findings:
        for k, (lo, hi) in f.ci95.items():
            assert lo <= f.params[k] <= hi and lo <= truth[k] <= hi and f.n_tests == 2
            # the verdict's two values together: each side at least as far out, by up to Student's Šidák
            # factor on 1 df (1.98) where the side is statistical
            j_lo, j_hi = f.ci95_joint[k]
            assert j_lo <= lo and hi <= j_hi and (j_hi - j_lo) <= 1.98 * (hi - lo)
            assert (j_lo, j_hi) != (lo, hi) or lo == 0.0
    b = D.diagnose_boundary([e], "two-sided")
    assert b.verdict == e.verdict and b.n_series_diagnosed == 1 and b.too_small is None
    # one series is one unit: its parameters pass to the boundary without an interval, and say why
    assert all(not f.ci95 and "1 series, 0 residual df" in f.ci_note for f in b.findings)


def test_a_one_test_series_names_nothing(series_of):
    e = D.diagnose_records(series_of(1), "tiny", n_boot=10, n_history=0)
    assert e.n_tests == 1 and e.verdict == [] and e.findings == []
    assert e.too_small.startswith("one test: nothing varies between tests")
    assert e.extended is None and e.sample_test.startswith("small-")
    b = D.diagnose_boundary([e], "two-sided")
    assert b.verdict == [] and b.n_series == 1 and b.n_series_diagnosed == 0
    assert b.too_small_series == ["tiny"] and b.too_small is not None and b.heldout is None
    assert "explains the data" not in b.what_is_wrong
    md = D.diagnosis_markdown([e, b])
    assert md.count("**Verdict: too small to name a cause**") == 2 and "[" not in md


def test_a_drift_needs_two_residual_degrees_of_freedom_of_tests(series_of):
    from rocklab.diagnosis.causes import restitution_drift
    from rocklab.diagnosis.series import not_identifiable
    from rocklab.lab.hierarchy import MIN_DF

    tests = [D.measured_test(r) for r in series_of(1)]
    assert restitution_drift.MIN_TESTS == MIN_DF + 2
    for n in range(1, 6):
        blind = not_identifiable(tests * n)
        assert ("restitution_drift" in blind) == (n < restitution_drift.MIN_TESTS)
        # every other cause is seen at every impact, a loss in flight (viscous, or its family: dry, drag) on
        # the long flights (of a few tests)
        losses = {"flight_damping", "flight_loss"}
        assert set(blind) <= {"restitution_drift"} | losses and (losses <= set(blind)) == (n == 1)
        assert ("flight_damping" in blind) == ("flight_loss" in blind)
        # a family, named on the form its design cannot show, is never named: its signature does not support
        # it, so the selection turns it down unfitted; a listed cause keeps its own signature
        sig = D.catalogue.signatures(tests * n)
        for c, why in blind.items():
            family = D.catalogue.by_name(c).family
            assert (sig[c] == sig[c] | {"supports": False, "not_identifiable": why}) == bool(family)
    assert not not_identifiable(tests * 2, named=["restitution_drift"])


@pytest.fixture(scope="module")
def diagnosed_six(series_of):
    """The diagnosis of six tests and the log it writes."""
    handler = _Collect()
    logger = logging.getLogger("rocklab.diagnosis")
    logger.addHandler(handler)
    level = logger.level
    logger.setLevel(logging.INFO)
    try:
        e = D.diagnose_records(series_of(6), "six", n_boot=10, n_history=0)
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)
    return e, handler.lines


class _Collect(logging.Handler):
    def __init__(self):
        super().__init__(logging.INFO)
        self.lines = []

    def emit(self, record):
        self.lines.append(record.getMessage())


def test_a_normal_series_names_its_causes_with_their_counts(diagnosed_six):
    e, _ = diagnosed_six
    assert e.too_small is None and set(e.verdict) >= {"instability_angle", "restitution_scale"}
    assert e.not_identifiable is None
    for f in e.findings:
        if f.effect != "stop_threshold":
            assert f.n_tests == 6 and f.ci95
    assert "(6 tests) |" in D.diagnosis_markdown([e])


def test_a_boundary_of_few_series_gives_values_without_intervals(diagnosed_six):
    e, _ = diagnosed_six
    few = [replace(e, key=f"s{i}") for i in range(2)]
    b = D.diagnose_boundary(few, "two-sided")
    f = next(f for f in b.findings if f.effect == "instability_angle")
    assert f.ci95 == {} and f.ci_note == "alpha_r_over_alpha: 2 series, 1 residual df (2 needed): no interval"
    assert f.n_series == 2 and f.n_tests == 12
    md = D.diagnosis_markdown([b])
    assert "none† (12 tests, 2 series)" in md and "† alpha_r_over_alpha: 2 series, 1 residual df" in md
    many = D.diagnose_boundary([*few, replace(e, key="s2")], "two-sided")
    f = next(f for f in many.findings if f.effect == "instability_angle")
    lo, hi = f.ci95["alpha_r_over_alpha"]
    assert lo <= f.params["alpha_r_over_alpha"] <= hi and f.ci_note is None
    assert "(18 tests, 3 series)" in D.diagnosis_markdown([many])


def test_the_log_of_a_diagnosis_names_every_candidate(diagnosed_six):
    e, lines = diagnosed_six
    text = "\n".join(lines)
    for cause in D.CAUSES:
        if "two-sided" in cause.boundaries and cause.stage == "selection":
            # fitted, or turned down before its fit for want of its signature
            assert f"fit {cause.name}" in text or f"{cause.name} rejected: its signature" in text, cause.name
    assert "fit base model" in text and "BIC" in text
    assert any(line.startswith("bootstrap of ") and "10 resamples of 6 tests" in line for line in lines)
    for eff in e.verdict:
        assert eff in text
    assert any("accepted" in line for line in lines) and any("rejected" in line for line in lines)
    assert "stop_threshold" in text and "chosen: " in text
    assert lines[-1].startswith("series six: verdict")
    assert 10 < len(lines) < 80  # a few dozen lines, not one per fit of a fold


SNAKEMAKE = Path(sys.executable).with_name("snakemake")
ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.skipif(not SNAKEMAKE.exists(), reason="snakemake not installed beside this interpreter")
def test_a_three_test_campaign_says_its_sample_is_too_small(tiny_campaign, tmp_path):
    """The issue's campaign: the tables mark their values, the diagnosis names nothing, the logs say why."""
    results = tmp_path / "results"
    targets = [str(results / name) for name in ("table3.md", "series.csv", "diagnosis.md")]
    # a working directory of its own (Snakemake's locks and metadata): other workflow tests run at once
    work = tmp_path / "work"
    work.mkdir()
    cmd = [str(SNAKEMAKE), "--cores", "2", "--quiet", "--snakefile", str(ROOT / "Snakefile"), "--directory", str(work)]
    cmd += ["--config", f"raw_dir={tiny_campaign}", f"results_dir={results}", "--", *targets]
    run = subprocess.run(cmd, capture_output=True, text=True, cwd=work, env={**os.environ, "PYTHONWARNINGS": "ignore"})
    assert run.returncode == 0, run.stderr[-3000:]
    t3 = (results / "table3.md").read_text()
    assert "nan" not in t3 and "[" not in t3 and "0 residual df (2 needed): no interval" in t3
    series = pd.read_csv(results / "series.csv")
    assert series.e_ratio_ci_low.isna().all() and (series.ci_note == "too few tests for an interval (1 < 5)").all()
    md = (results / "diagnosis.md").read_text()
    assert md.count("**Verdict: too small to name a cause**") == len(series) + 2  # and both boundaries
    jobs = open_campaign(tiny_campaign).diagnosis_jobs()
    for s in series.series:
        # one diagnosis job (and log) per few series
        (job,) = [job for job, keys in jobs.items() if s in keys]
        log = (results / "logs" / "diagnosis" / f"{job}.log").read_text()
        assert f"series {s} is too small to name a cause" in log and "base model:" in log
