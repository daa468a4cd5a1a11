"""The campaign level (rocklab.dissipation.covariates): planted effects found with the right
sign and interval, null ones not (at the nominal rate), single levels not testable, the
paper's statements judged without over-claiming, the table against its schema."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from rocklab.diagnosis.result import CampaignDiagnosis
from rocklab.dissipation.claims import PAPER_CLAIMS, Claim, margin_of, read_claims, verdict
from rocklab.dissipation.covariates import (
    COLUMNS,
    campaign_effects,
    fit_level,
    series_fits,
    series_values,
    with_test_order,
    within_series_row,
)
from rocklab.dissipation.regression import ols
from rocklab.inference.verdicts import ClaimVerdict
from rocklab.io import validate_table
from rocklab.lab.campaign import order_in_series
from rocklab.lab.hierarchy import MIN_DF, too_few_units

SCHEMA = "workflow/schemas/campaign_effects.schema.yaml"

#: The campaign's design: (specimen, h/b, unit); every specimen two-sided and one-sided at three contact depths.
SPECIMENS = (
    ("1a", 9.6, "clay brick"),
    ("1b", 7.1, "clay brick"),
    ("2a", 14.4, "clay brick"),
    ("2b", 12.0, "clay brick"),
    ("3a", 13.3, "tuff"),
    ("3b", 10.4, "tuff"),
    ("5a", 14.6, "tuff"),
    ("5c", 6.5, "tuff"),
)


def synthetic_tests(
    seed=0, n_tests=8, slope_hb=0.0, tuff=0.0, per_mm=0.0, drift=0.0, tau=0.02, sigma=0.005, units=None, omega=0.0
):
    """tests.csv of a campaign with known effects on e_ratio (theta0_over_alpha has none).

    e_ratio = mean + slope_hb (h/b - 10) + tuff [unit is tuff] + per_mm (CD - 120)
    + drift (order - 1/2) + a wall effect (sd omega) + a series effect (sd tau)
    + a test's noise (sd sigma).  The wall is the specimen's digit (4 walls, 2 of each unit).
    """
    rng = np.random.default_rng(seed)
    wall_effect = {w: rng.normal(0, omega) for w in "1235"}
    rows, k = [], 0
    for specimen, hb, unit in SPECIMENS:
        unit = units or unit
        for boundary, cd in (("two-sided", np.nan), ("one-sided", 60.0), ("one-sided", 120.0), ("one-sided", 260.0)):
            mean = 0.95 if boundary == "two-sided" else 1.2
            series = f"{specimen}-2s" if boundary == "two-sided" else f"{specimen}-1s-cd{cd:g}"
            level = mean + slope_hb * (hb - 10) + tuff * (unit == "tuff") + wall_effect[specimen[0]]
            level += rng.normal(0, tau)
            level += per_mm * (cd - 120) if boundary == "one-sided" else 0.0
            for i in range(n_tests):
                k += 1
                order = i / (n_tests - 1)
                rows.append(
                    {
                        "test_id": f"T{k:04d}",
                        "series": series,
                        "specimen": specimen,
                        "wall": specimen[0],
                        "boundary": boundary,
                        "contact_depth_mm": cd,
                        "direction": "push",
                        "h_over_b": hb,
                        "unit": unit,
                        "e_ratio": level + drift * (order - 0.5) + rng.normal(0, sigma),
                        "theta0_over_alpha": 0.9 + rng.normal(0, 0.01) + rng.normal(0, 0.001),
                    }
                )
    return pd.DataFrame(rows)


def row(table, boundary, covariate, response="e_ratio"):
    r = table[(table.boundary == boundary) & (table.response == response) & (table.covariate == covariate)]
    assert len(r) == 1, r
    return r.iloc[0]


# --- the pieces against independent checks ----------------------------------------------------


def test_ols_is_the_textbook_simple_regression():
    rng = np.random.default_rng(1)
    x = rng.uniform(5, 15, 12)
    y = 0.9 + 0.01 * x + rng.normal(0, 0.02, 12)
    coef, cov, df = ols(y, np.column_stack([np.ones(12), x]))
    ref = stats.linregress(x, y)
    assert coef[1] == pytest.approx(ref.slope)
    assert np.sqrt(cov[1, 1]) == pytest.approx(ref.stderr)
    assert df == 10


def test_the_paper_claims_are_data_read_and_checked(tmp_path):
    """The paper's statements come from rocklab/data/paper_claims.csv; a file with a kind, a value
    or a key the tests cannot take is refused with its line."""
    assert read_claims() == PAPER_CLAIMS and len(PAPER_CLAIMS) == 15
    assert PAPER_CLAIMS[2] == Claim(
        "ratio_2s_mean",
        "two-sided",
        "e_ratio",
        "mean",
        "near",
        0.93,
        "Sect. 3: if all series are considered, the ratio e_exp/e_an,2s is on average 0.93",
    )
    head = "key,boundary,response,covariate,kind,value,paper\n"
    good = "a,one-sided,e_ratio,order,zero,0,Sect. 3\n"
    for body, message in (
        (good + "b,one-sided,e_ratio,order,above,0,x\n", "line 3: kind 'above'"),
        (good + "b,one-sided,e_ratio,order,near,one,x\n", "line 3: value 'one' is no finite number"),
        (good + "b,one-sided,e_ratio,height,zero,0,x\n", "line 3: covariate 'height'"),
        (good + good, "line 3: key 'a' repeated"),
    ):
        path = tmp_path / "claims.csv"
        path.write_text(head + body)
        with pytest.raises(ValueError, match=message):
            read_claims(path)
    path.write_text("key,boundary\n")
    with pytest.raises(ValueError, match="columns"):
        read_claims(path)
    path.write_text(head + good)
    assert read_claims(path) == (Claim("a", "one-sided", "e_ratio", "order", "zero", 0.0, "Sect. 3"),)


def test_order_in_series_runs_from_zero_to_one_in_the_order_of_the_ids():
    assert order_in_series(["T0003", "T0001", "T0002"]) == {"T0001": 0.0, "T0002": 0.5, "T0003": 1.0}
    assert order_in_series(["T0009"]) == {"T0009": 0.0}


def test_the_place_counts_the_rejected_tests_of_the_series():
    tests = pd.DataFrame({"test_id": ["T1", "T3"], "series": ["s", "s"]})
    qc = pd.DataFrame({"test_id": ["T1", "T2", "T3"], "series": ["s", "s", "s"]})
    assert with_test_order(tests, qc).order.tolist() == [0.0, 1.0]
    assert with_test_order(tests).order.tolist() == [0.0, 1.0]
    tests = pd.DataFrame({"test_id": ["T1", "T2"], "series": ["s", "s"]})
    assert with_test_order(tests, qc).order.tolist() == [0.0, 0.5]


@pytest.mark.parametrize(
    "kind, low, high, p, value, margin, expected",
    [
        ("zero", -0.01, 0.01, 0.5, 0, 0.05, "supported"),
        ("zero", -0.10, 0.10, 0.5, 0, 0.05, "inconclusive"),
        # detected, but within the margin: negligible (issue 41)
        ("zero", 0.01, 0.03, 0.001, 0, 0.05, "supported"),
        ("zero", 0.01, 0.08, 0.001, 0, 0.05, "inconclusive"),
        ("zero", 0.06, 0.08, 0.001, 0, 0.05, "contradicted"),
        ("below", 0.92, 0.97, 0.01, 1.0, 0, "supported"),
        ("below", 0.98, 1.02, 0.5, 1.0, 0, "inconclusive"),
        ("below", 1.01, 1.05, 0.01, 1.0, 0, "contradicted"),
        ("near", 0.93, 0.97, 0.01, 1.0, 0.1, "supported"),
        ("near", 0.85, 0.95, 0.01, 1.0, 0.1, "inconclusive"),
        ("near", 0.70, 0.80, 0.01, 1.0, 0.1, "contradicted"),
    ],
)
def test_verdicts(kind, low, high, p, value, margin, expected):
    assert verdict(kind, low, high, p, value, margin) == expected


# --- planted effects, null effects ------------------------------------------------------------


def test_a_planted_aspect_ratio_effect_is_found_with_its_sign_and_interval():
    slope = -0.02
    table = campaign_effects(synthetic_tests(seed=3, slope_hb=slope, tau=0.005))
    for boundary in ("two-sided", "one-sided"):
        r = row(table, boundary, "h_over_b")
        truth = slope * (r.span_high - r.span_low)
        assert r.estimate < 0 and r.ci_low <= truth <= r.ci_high
        # h/b is compared between the specimens of one wall: 8 specimens, 4 walls, the slope
        assert r.unit_level == "specimen" and r.n_units == 8 and r.df == 8 - 4 - 1
    assert row(table, "two-sided", "h_over_b").statement == "ratio_2s_aspect"
    assert row(table, "two-sided", "h_over_b").verdict == "contradicted"


def test_a_planted_unit_and_contact_depth_effect_is_found():
    table = campaign_effects(synthetic_tests(seed=4, tuff=0.3, per_mm=4e-4, tau=0.005))
    unit = row(table, "one-sided", "unit")
    assert unit.term == "tuff - clay brick" and unit.ci_low <= 0.3 <= unit.ci_high
    # the wall is the unit of its material: 4 walls, 2 coefficients
    assert unit.unit_level == "wall" and unit.n_units == 4 and unit.df == 2 and unit.n_series == 24
    assert unit.verdict == "contradicted"
    cd = row(table, "one-sided", "contact_depth_mm")
    assert cd.slope > 0 and cd.ci_low <= 4e-4 * 200 <= cd.ci_high and cd.ci_low > cd.margin
    assert cd.verdict == "contradicted"
    # a smaller effect, detected, whose interval straddles the margin: whether it matters is open
    small = row(
        campaign_effects(synthetic_tests(seed=4, tuff=0.3, per_mm=3e-4, tau=0.005)), "one-sided", "contact_depth_mm"
    )
    assert small.p < 1e-6 and small.ci_low < small.margin < small.ci_high and small.verdict == "inconclusive"
    # compared between the series of one specimen: 24 series, 8 specimen means and a slope
    assert cd.unit_level == "series" and cd.df == 24 - 8 - 1
    # two-sided walls have no contact depth: no row
    assert table[(table.boundary == "two-sided") & (table.covariate == "contact_depth_mm")].empty


def test_a_drift_over_the_tests_of_a_series_is_found():
    r = row(campaign_effects(synthetic_tests(seed=5, drift=-0.02)), "one-sided", "order")
    # found, and within the margin of e: a drift too small to change the outcome is negligible
    assert r.ci_low <= -0.02 <= r.ci_high < 0 and r.p < 0.01
    assert -r.margin <= r.ci_low and r.verdict == "supported"
    large = row(campaign_effects(synthetic_tests(seed=5, drift=-0.1)), "one-sided", "order")
    assert large.ci_low <= -0.1 <= large.ci_high < -large.margin and large.verdict == "contradicted"
    # each series' slope, then the mean over walls
    assert r.n_series == 24 and r.n_units == 4 and r.df == 3


def test_no_planted_effect_gives_no_contradiction_and_no_support_beyond_the_data():
    # series scatter twice the one-sided walls' margin
    table = campaign_effects(synthetic_tests(seed=6, tau=2 * margin_of("e_ratio", "one-sided")))
    # the one effect planted: the two boundary conditions have different means
    assert row(table, "both", "boundary").verdict == "contradicted"
    effects = ~table.covariate.isin(["boundary", "mean"])
    tested = table[(table.verdict != ClaimVerdict.NOT_TESTABLE) & effects]
    assert not (tested.verdict == "contradicted").any(), tested[tested.verdict == "contradicted"]
    # with it a property of the wall or specimen cannot be shown negligible
    for covariate in ("h_over_b", "unit", "contact_depth_mm"):
        assert row(table, "one-sided", covariate).verdict == "inconclusive"
    # on walls as alike as their tests, it can
    calm = campaign_effects(synthetic_tests(seed=6, tau=0.0002, sigma=0.0005))
    for covariate in ("h_over_b", "contact_depth_mm", "order"):
        assert row(calm, "one-sided", covariate).verdict == "supported"


def test_a_wall_property_tested_on_series_would_be_pseudo_replicated_on_walls_it_is_nominal():
    """Walls that differ (sd 0.03) and no effect of their material: with the wall as the unit the
    material's test rejects at the nominal rate and its interval covers zero at 95 %."""
    rng = np.random.default_rng(7)
    walls = np.repeat(np.arange(6), 4)
    unit = np.where(walls < 3, "clay brick", "tuff")
    rejected = covered = 0
    n = 300
    for _ in range(n):
        value = 1.0 + rng.normal(0, 0.03, 6)[walls] + rng.normal(0, 0.003, walls.size)
        frame = pd.DataFrame(
            {"series": np.arange(walls.size), "wall": walls, "unit": unit, "n_tests": 5, "value": value}
        )
        fit, reason, units = fit_level(frame, "unit")
        assert not reason and len(units) == 6 and fit.df == 4
        j = fit.columns["tuff - clay brick"]
        t = fit.coef[j] / np.sqrt(fit.cov[j, j])
        rejected += 2 * stats.t.sf(abs(t), fit.df) < 0.05
        covered += abs(fit.coef[j]) <= stats.t.ppf(0.975, fit.df) * np.sqrt(fit.cov[j, j])
    # 300 draws: the binomial sd of a 5 % rate is 1.3 %; series as units would reject about half of them
    assert 0.015 <= rejected / n <= 0.09
    assert 0.91 <= covered / n <= 0.985


def test_a_within_wall_slope_is_unbiased_by_the_walls_own_levels():
    """h/b compared between the specimens of one wall: a wall effect correlated with h/b is no slope."""
    rng = np.random.default_rng(8)
    hb = np.array([6.0, 8.0, 10.0, 12.0, 14.0, 16.0])
    wall = np.array([0, 0, 1, 1, 2, 2])
    frame = pd.DataFrame(
        {
            "series": np.arange(6),
            "specimen": np.arange(6),
            "wall": wall,
            "unit": "tuff",
            "h_over_b": hb,
            "n_tests": 5,
            # the walls' own levels rise with their h/b; the true slope within a wall is 0.01
            "value": 0.1 * wall + 0.01 * hb + rng.normal(0, 1e-4, 6),
        }
    )
    fit, reason, _ = fit_level(frame, "h_over_b")
    assert not reason and fit.level == "specimen" and fit.df == MIN_DF
    assert fit.coef[fit.columns["per unit"]] == pytest.approx(0.01, abs=1e-3)


# --- what cannot be tested --------------------------------------------------------------------


def test_a_single_level_covariate_is_not_testable_never_judged():
    table = campaign_effects(synthetic_tests(seed=8, units="clay brick"))
    for boundary in ("two-sided", "one-sided"):
        r = row(table, boundary, "unit")
        assert (r.verdict, r.why_not_testable) == (
            ClaimVerdict.NOT_TESTABLE,
            "only one level (clay brick) among 4 walls",
        )
        assert np.isnan(r.estimate) and np.isnan(r.p)
    # every test pushed: the direction has one level
    assert row(table, "two-sided", "direction").why_not_testable == "only one level (push)"


def test_a_material_on_three_walls_one_of_them_tuff_is_not_testable_with_the_walls_counted():
    """The embedded campaign's one-sided walls: two of clay brick, one of tuff, sixteen series."""
    tests = synthetic_tests(seed=9)
    tests = tests[tests.specimen.isin(["1a", "1b", "2a", "2b", "3a", "3b"])]
    r = row(campaign_effects(tests), "one-sided", "unit")
    assert r.why_not_testable == "2 walls of clay brick, 1 wall of tuff (2 walls a level needed)"
    assert r.n_units == 3 and r.n_series == 18


def test_the_units_a_verdict_needs():
    assert too_few_units("wall", 4, 2, {"clay brick": 2, "tuff": 2}) == ""
    assert too_few_units("wall", 3, 1, {"clay brick": 2, "tuff": 1}).startswith("2 walls of clay")
    assert too_few_units("series", 2, 1) == "2 series, 1 residual df (2 needed)"


def test_direction_tested_in_one_series_only_is_not_testable():
    tests = with_test_order(synthetic_tests(seed=10))
    tests.loc[tests.series.eq("1a-2s") & (tests.order > 0.5), "direction"] = "pull"
    r = within_series_row(tests[tests.boundary == "two-sided"], "two-sided", "e_ratio", "direction")
    assert (r["verdict"], r["why_not_testable"]) == ("not testable", "varies within 1 series (2 needed)")


# --- margins ------------------------------------------------------------------------------------


def test_close_to_one_and_on_average_093_cannot_both_be_supported():
    """Issue 24: on the same numbers the two statements of Sect. 3 contradict each other."""
    rng = np.random.default_rng(11)
    for level in np.linspace(0.90, 1.02, 13):
        tests = synthetic_tests(seed=int(rng.integers(1000)), tau=0.0005, sigma=0.0005)
        tests["e_ratio"] += level - 0.95
        table = campaign_effects(tests).set_index("statement")
        both = table.loc[["ratio_2s_close_to_one", "ratio_2s_mean"], "verdict"]
        assert not (both == "supported").all(), (level, both)


# --- the table ---------------------------------------------------------------------------------


def test_the_paper_statements_come_first_each_once_and_the_table_meets_its_schema():
    table = campaign_effects(synthetic_tests(seed=11))
    validate_table(table, SCHEMA)
    keys = [c.key for c in PAPER_CLAIMS]
    assert table.statement.iloc[: len(keys)].tolist() == keys
    assert (table.statement.iloc[len(keys) :] == "").all()
    # the paper's statements are a family of their own: Holm within it, simultaneous intervals at 1 - 0.05/m
    judged = table.iloc[: len(keys)].dropna(subset=["p"])
    assert (judged.p_holm >= judged.p).all() and (judged.verdict_level == 1 - 0.05 / len(judged)).all()
    bad = table.copy()
    bad.loc[0, "boundary"] = "three-sided"
    with pytest.raises(Exception, match="row 1, boundary"):
        validate_table(bad, SCHEMA)


def test_diagnosis_parameters_are_modelled_per_series():
    tests = synthetic_tests(seed=12)
    names = sorted(tests.series.unique())
    finding = "instability_angle"
    entries = CampaignDiagnosis.from_dict(
        [
            {"scope": "series", "key": s, "findings": [{"effect": finding, "params": {"alpha_r_over_alpha": a}}]}
            for s, a in zip(names, np.linspace(0.7, 0.9, len(names)))
        ]
    )
    values = series_values(tests, entries)
    assert set(values.response) == {"e_ratio", "theta0_over_alpha", "instability_angle.alpha_r_over_alpha"}
    table = campaign_effects(tests, entries)
    r = row(table, "both", "boundary", "instability_angle.alpha_r_over_alpha")
    assert r.source == "diagnosis" and r.n_series == 32 and r.unit_level == "series"
    fits = series_fits(tests, entries)
    part = fits[("one-sided", "e_ratio")]["contact_depth_mm"].partial()
    assert np.all(part["low"] <= part["line"]) and np.all(part["line"] <= part["high"])


def test_the_docs_numbers_and_tables_of_the_campaign_level(tmp_path):
    from rocklab.dissipation.dissipation_summary import campaign_level_summary
    from rocklab.io import write_table
    from rocklab.report import tables
    from rocklab.summaries import rounded

    table = campaign_effects(synthetic_tests(seed=13, slope_hb=-0.02, tau=0.005))
    write_table(table, tmp_path / "diagnosis" / "campaign_effects.csv", SCHEMA)
    c = campaign_level_summary(tmp_path / "diagnosis" / "campaign_effects.csv")
    assert c["order"] == [k.key for k in PAPER_CLAIMS]
    for b in ("two-sided", "one-sided"):
        assert c["margins"][b]["e_ratio"] == margin_of("e_ratio", b)
    assert c["margin_rule"]["tolerance"] == 0.05
    assert c["statements"]["ratio_2s_aspect"]["verdict"] == "contradicted"
    assert c["statements"]["ratio_2s_aspect"]["unit_level"] == "specimen"
    assert c["n_statements"] == len(PAPER_CLAIMS)
    assert c["n_effects"] == c["n_judged"] + c["n_not_testable"]
    numbers = {"campaign_level": rounded(c)}
    text = tables.campaign_statements(numbers)
    assert text.count("\n") == len(PAPER_CLAIMS) + 1 and "**contradicted**" in text
    assert tables.campaign_found({"campaign_level": {"found": []}}) == "None."
    assert tables.campaign_statements({"campaign_level": None}) == "not measured."


def test_the_figure_draws_every_fitted_parameter_and_a_campaign_too_small_for_any():
    from rocklab.plots.covariates import covariate_figure

    tests = synthetic_tests(seed=14)
    fig = covariate_figure(series_fits(tests), campaign_effects(tests))
    assert len(fig.axes) == 2 * 3
    few = tests[tests.series.isin(["1a-2s", "1b-1s-cd60"])]
    assert not any(series_fits(few).values())
    fig = covariate_figure(series_fits(few), campaign_effects(few))
    assert "no parameter" in fig.axes[0].texts[0].get_text()


def test_a_campaign_without_a_valid_test_has_an_empty_table():
    empty = synthetic_tests().iloc[:0]
    assert campaign_effects(empty).columns.tolist() == list(COLUMNS) and campaign_effects(empty).empty
    assert series_fits(empty) == {}
