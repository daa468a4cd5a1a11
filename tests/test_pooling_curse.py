"""Pooling without a curse (issue 41, item 4): every series at its own estimate, or left out.

One-sided walls, restitution scale plus viscous damping: one wall's series
names zeta 0.0062, the other's estimates it without naming it; a series
whose design cannot see the cause says nothing of its size. A mean over the
namers alone is the winner's curse, zeros for the others the loser's curse:
the pool takes every series' own estimate with its standard error and
leaves out the series that cannot estimate it, listed with why.
"""

import numpy as np
import pytest
from scipy import stats
from test_diagnosis import SPEC

from rocklab import diagnosis as D
from rocklab.diagnosis.diagnosis_summary import diagnosis_summary
from rocklab.diagnosis.estimation.systematic import widened
from rocklab.diagnosis.pooling import pooled_bias, statistical_error
from rocklab.diagnosis.result import (
    BaseRun,
    CampaignDiagnosis,
    Finding,
    HeldOut,
    LeftOut,
    LeftOutBecause,
    SeriesDiagnosis,
)
from rocklab.inference.intervals import mean_over_units, random_effects_mean
from rocklab.lab import virtual_lab as vl
from rocklab.report.tables import findings


def _same(x):
    return {"measured": x, "model": x}


ERRORS = {
    "n_impacts": _same(10.0),
    "duration_s": _same(5.0),
    "decay_pct": _same(50.0),
    "first_quarter_p": _same(0.3),
    "flight_time_pct": 0.0,
    "lag_cycles": 0.0,
}
CAUSE, NAME = "flight_damping", "zeta"


def named(zeta, half=0.002, u=0.0003, n_tests=8):
    return Finding(
        effect=CAUSE,
        params={NAME: zeta},
        ci95={NAME: [zeta - half, zeta + half]},
        u_systematic={NAME: u},
        n_tests=n_tests,
        error_heldout={"deviance_per_obs": 1.0},
        gain={"deviance_per_obs": 0.2},
    )


def series(key, findings=(), unnamed=None, se=None, blind=None):
    return SeriesDiagnosis(
        scope="series",
        key=key,
        boundary="one-sided",
        n_tests=8,
        n_impacts=40,
        base=BaseRun(model="one-sided", errors=ERRORS),
        what_is_wrong="",
        verdict=[f.effect for f in findings],
        not_identifiable=blind,
        findings=list(findings),
        unnamed_estimates=None if unnamed is None else {CAUSE: {NAME: unnamed}},
        unnamed_se=None if se is None else {CAUSE: {NAME: se}},
        heldout=HeldOut(base={"impact_rms": 0.1}, model={"impact_rms": 0.05}),
        sample_test=f"T-{key}",
    )


def pooled(entries, walls):
    b = D.diagnose_boundary(entries, "one-sided", walls=walls)
    assert b is not None and b.verdict == [CAUSE]
    return b.findings[0]


def test_the_losers_curse_a_series_that_did_not_name_it_counts_at_its_own_estimate():
    """Two walls: one series names zeta 0.006, the other estimates 0.0058 without naming it. Pooled at the
    null value it was 0.003 (the loser's curse); at its own estimate the pool is near 0.006."""
    walls = {"a": "A", "b": "B"}
    f = pooled([series("a", [named(0.006)]), series("b", unnamed=0.0058, se=0.0012)], walls)
    assert f.params[NAME] == pytest.approx(0.0059, abs=2e-4)
    assert abs(f.params[NAME] - 0.003) > 0.0025
    assert not f.left_out
    # two walls: one residual df, too few for an interval, and the entry says so
    assert f.ci95 == {} and "2 walls, 1 residual df" in f.ci_note
    assert "1 that did not" in f.evidence["pooled"]


def test_a_series_that_cannot_see_the_cause_is_left_out_not_put_at_zero():
    walls = {"a": "A", "b": "B", "c": "C"}
    why = "a viscous loss on short flights only"
    entries = [
        series("a", [named(0.0062)]),
        series("b", [named(0.0058)]),
        series("c", blind={CAUSE: why}),
    ]
    f = pooled(entries, walls)
    # the mean of the two that can see it, not (0.0062 + 0.0058 + 0) / 3 = 0.004
    assert f.params[NAME] == pytest.approx(0.006, abs=1e-5)
    assert f.left_out == [LeftOut(series="c", reason=LeftOutBecause.NOT_IDENTIFIABLE, params=[NAME], why=why)]
    assert "left out: series c (" + why + ")" in f.evidence["pooled"]
    # the pages say so: the readable diagnosis and the docs' table of the boundary's causes
    b = D.diagnose_boundary(entries, "one-sided", walls=walls)
    assert f"flight_damping, left out: series c ({why})." in D.diagnosis_markdown([*entries, b])
    summary = diagnosis_summary(CampaignDiagnosis([*entries, b]))
    assert f"series c ({why})" in findings({"diagnosis": summary}, "one_sided")
    # a series with no estimate at all (no sign of the cause in its data) is left out too, with its reason
    entries[2] = series("c")
    assert pooled(entries, walls).left_out[0].reason is LeftOutBecause.NO_ESTIMATE
    # the reason travels through the file, typed
    b = D.diagnose_boundary(entries, "one-sided", walls=walls)
    back = CampaignDiagnosis.from_dict(CampaignDiagnosis([*entries, b]).to_dict()).boundaries[0]
    assert back.findings[0].left_out[0].reason is LeftOutBecause.NO_ESTIMATE


def test_the_winners_curse_the_pool_takes_the_smaller_unnamed_estimates():
    """The namers' estimates are those that cleared the test: large by selection. Where the other series
    have their own, smaller estimates, the pool uses them and falls below the namers' mean."""
    walls = {k: k.upper() for k in "abcd"}
    entries = [
        series("a", [named(0.009)]),
        series("b", [named(0.008)]),
        series("c", unnamed=0.004, se=0.0008),
        series("d", unnamed=0.003, se=0.0008),
    ]
    f = pooled(entries, walls)
    # without their own estimates the two are left out: the namers' mean, 0.0085
    namers_only = pooled([*entries[:2], series("c"), series("d")], walls)
    assert namers_only.params[NAME] == pytest.approx(0.0085, abs=1e-5) and len(namers_only.left_out) == 2
    assert f.params[NAME] < namers_only.params[NAME] - 0.002
    assert f.params[NAME] == pytest.approx(0.006, abs=5e-4)
    assert f.n_series == 2 and not f.left_out and NAME in f.ci95


def test_a_series_estimate_its_statistical_error_is_its_interval_less_the_systematic_part():
    # the interval widened (systematic.widened) from t on the 7 tests less one and u_sys 0.0003 by
    # Welch-Satterthwaite, its systematic part's degrees of freedom not kept: taken as infinite
    t = stats.t.ppf(0.975, 7)
    se = 0.001
    ci = widened([0.006 - t * se, 0.006 + t * se], 0.006, 0.0, 1.0, 0.0003, df=7)
    assert statistical_error(ci, 0.0003, 8) == pytest.approx(se, rel=1e-6)
    assert np.isnan(statistical_error([], 0.0, 8))


def test_the_random_effects_mean_weighs_by_the_errors_and_the_scatter():
    # units that agree within their errors: the inverse-variance mean
    m, se, k, note, tau = random_effects_mean([1.0, 1.1], [0.1, 0.2], ["a", "b"], "wall")
    assert tau == 0.0 and k == 2 and "1 residual df" in note
    assert m == pytest.approx((1.0 / 0.01 + 1.1 / 0.04) / (1 / 0.01 + 1 / 0.04))
    # units that scatter far more than their errors: the plain mean over units
    x = [1.0, 2.0, 3.5, 0.2]
    m, se, k, note, tau = random_effects_mean(x, [1e-3] * 4, list("abcd"), "wall")
    m0, se0, *_ = mean_over_units(x, list("abcd"), "wall")
    assert (m, note) == (pytest.approx(m0, rel=1e-4), "") and se == pytest.approx(se0, rel=1e-3) and tau > 1
    # a missing error: the plain mean
    assert random_effects_mean([1.0, 2.0], [0.1, np.nan], ["a", "b"], "wall")[0] == pytest.approx(1.5)
    # the series of one wall are one wall's evidence: their mean, not two units
    m, _, k, *_ = random_effects_mean([1.0, 3.0, 2.5], [0.1, 0.1, 0.1], ["a", "a", "b"], "wall")
    assert k == 2 and m == pytest.approx(2.25, abs=0.01)


def test_the_pooled_bias_is_in_units_of_the_smallest_effect_worth_naming():
    # zeta (smallest effect 0.0002) and v_stop/v_r (0.01, say) over three campaigns: each campaign's
    # errors are one unit's evidence
    est = [0.0064, 0.11, 0.0058, 0.10, 0.0031, 0.0553]
    truth = [0.006, 0.1, 0.006, 0.1, 0.006, 0.1]
    smallest = [0.0002, 0.01, 0.0002, 0.01, 0.0002, 0.01]
    units = ["c1", "c1", "c2", "c2", "c3", "c3"]
    b = pooled_bias(est, truth, smallest, units)
    per_unit = np.array([(2.0 + 1.0) / 2, (-1.0 + 0.0) / 2, (-14.5 - 4.47) / 2])
    half = stats.t.ppf(0.975, 2) * per_unit.std(ddof=1) / np.sqrt(3)
    assert (b.n_units, b.level, b.note) == (3, "campaign", "")
    assert b.mean == pytest.approx(per_unit.mean()) and b.ci95 == pytest.approx((b.mean - half, b.mean + half))
    # unbiased campaigns: 0 within the interval
    ok = pooled_bias([0.0062, 0.0059, 0.0058, 0.0061], [0.006] * 4, [0.0002] * 4, list("abcd"))
    assert ok.ci95[0] < 0 < ok.ci95[1]
    # one campaign: no interval, and the note says why
    one = pooled_bias([0.0062, 0.11], [0.006, 0.1], [0.0002, 0.01], ["c1", "c1"])
    assert one.ci95 is None and "1 campaign" in one.note and one.mean == pytest.approx(1.0)
    with pytest.raises(ValueError, match="smallest effect"):
        pooled_bias([0.1], [0.1], [0.0], ["c1"])


def test_a_series_unnamed_estimates_carry_their_standard_errors():
    """A one-sided series of three tests names the instability angle; the amplitude-dependent angle, whose
    signature its data carry, it estimates without naming: each estimate with its sandwich error."""
    records = vl.series_records("c", SPEC.loc["5c"], "one-sided", {}, alpha_ratio=0.9, n=3, seed=1)
    e = D.diagnose_series(records, key="c", n_boot=10, n_history=0)
    assert e.unnamed_estimates and set(e.unnamed_se) == set(e.unnamed_estimates)
    for cause, est in e.unnamed_estimates.items():
        assert set(e.unnamed_se[cause]) <= set(est)
        assert all(0 < v < np.inf for v in e.unnamed_se[cause].values())
