"""rocklab.dissipation.statistics on synthetic campaigns with known structure."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from rocklab.dissipation.statistics import (
    bootstrap_ci,
    boundary_summary,
    cluster_bootstrap_ci,
    factor_effect,
    flag_outlying_series,
    holm,
    series_stats,
    series_table,
    symmetry_test,
    table3,
    table3_markdown,
)


def campaign(seed=0, odd_series="5a-2s", shift=-0.08):
    """Two-sided series around 0.95 (sd 0.01 within, 0.01 between) and
    one-sided series around 1.05 with three contact depths, no CD effect."""
    rng = np.random.default_rng(seed)
    rows = []
    for _i, sp in enumerate(["1a", "1b", "2a", "2b", "3a", "3b", "4b", "5a", "5b", "5c"]):
        unit = "tuff" if sp[0] in "35" else "clay brick"
        s = f"{sp}-2s"
        mu = 0.95 + 0.01 * rng.standard_normal() + (shift if s == odd_series else 0)
        for _ in range(15):
            rows.append(
                (
                    s,
                    sp,
                    "two-sided",
                    np.nan,
                    unit,
                    "push",
                    mu + 0.01 * rng.standard_normal(),
                    0.91 + 0.02 * rng.standard_normal(),
                )
            )
    for sp in ["1b", "1c", "2a", "2b", "3a", "3b"]:
        unit = "tuff" if sp[0] == "3" else "clay brick"
        for cd in (60, 120, 260):
            s = f"{sp}-1s-cd{cd}"
            mu = 1.05 + 0.05 * rng.standard_normal()
            for _ in range(12):
                rows.append(
                    (
                        s,
                        sp,
                        "one-sided",
                        cd,
                        unit,
                        "push",
                        mu + 0.1 * rng.standard_normal(),
                        0.73 + 0.03 * rng.standard_normal(),
                    )
                )
    return pd.DataFrame(
        rows,
        columns=[
            "series",
            "specimen",
            "boundary",
            "contact_depth_mm",
            "unit",
            "direction",
            "e_ratio",
            "theta0_over_alpha",
        ],
    )


def test_bootstrap_ci_is_seeded_and_covers_the_t_interval():
    x = np.random.default_rng(1).normal(1.0, 0.1, 40)
    lo, hi = bootstrap_ci(x, seed=3)
    assert (lo, hi) == bootstrap_ci(x, seed=3)
    t_lo, t_hi = stats.t.interval(0.95, 39, x.mean(), stats.sem(x))
    assert lo == pytest.approx(t_lo, abs=0.01) and hi == pytest.approx(t_hi, abs=0.01)
    assert np.isnan(bootstrap_ci([1.0])[0])


def test_holm_against_hand_computation():
    assert np.allclose(holm([0.01, 0.04, 0.03]), [0.03, 0.06, 0.06])


def test_series_stats_columns_and_values():
    df = campaign()
    s = series_stats(df, ("e_ratio",))
    g = df[df.series == "1a-2s"].e_ratio
    row = s.set_index("series").loc["1a-2s"]
    assert row.n == 15 and row.e_ratio_mean == pytest.approx(g.mean())
    assert row.e_ratio_sd == pytest.approx(g.std(ddof=1))
    assert row.e_ratio_ci_low < g.mean() < row.e_ratio_ci_high


def test_only_the_planted_series_is_flagged():
    f = flag_outlying_series(campaign())
    assert list(f[f.flagged].series) == ["5a-2s"]
    assert f.set_index("series").loc["5a-2s", "welch_p_holm"] < 1e-6
    assert not flag_outlying_series(campaign(shift=0.0)).flagged.any()


def test_no_contact_depth_or_material_effect_unless_planted():
    df = campaign(seed=2)
    cd = factor_effect(df, "contact_depth_mm")
    assert list(cd.boundary) == ["one-sided"] and not cd.systematic.iloc[0]
    assert "Kruskal" in cd.test.iloc[0]
    assert cd.unit_level.iloc[0] == "series" and cd.n_units.iloc[0] == [6, 6, 6]
    planted = campaign(seed=2, shift=0.0)
    planted.loc[planted.unit == "tuff", "e_ratio"] += 0.05
    walls = {sp: sp[0] for sp in planted.specimen.unique()}
    u = factor_effect(planted, "unit", walls=walls).set_index("boundary")
    # the wall is the unit of its material: 3 walls of clay brick, 2 of tuff, however many series; the
    # tuff walls ranked lowest give H = 3 and p = 0.083, the least five walls allow: no rank test on
    # five walls reaches 0.05
    assert u.loc["two-sided", "n_units"] == [3, 2] and u.loc["two-sided", "unit_level"] == "wall"
    assert u.loc["two-sided", "statistic"] == pytest.approx(3.0)
    assert u.loc["two-sided", "p"] == pytest.approx(stats.chi2.sf(3.0, 1)) and not u.loc["two-sided", "systematic"]
    # one-sided: two walls of clay brick and one of tuff, 18 series: no test
    assert np.isnan(u.loc["one-sided", "p"]) and u.loc["one-sided", "test"].startswith("not testable: 2 walls")


def test_push_pull_symmetry():
    df = campaign()
    m = df.series == "1a-2s"
    df.loc[m & (df.index % 2 == 1), "direction"] = "pull"
    df.loc[m & (df.direction == "pull"), "theta0_over_alpha"] *= 1.13
    s = symmetry_test(df, "theta0_over_alpha")
    assert list(s.series) == ["1a-2s"]
    assert s.relative_change.iloc[0] == pytest.approx(0.13, abs=0.03)
    assert s.welch_p.iloc[0] < 0.01


def test_series_table_counts_and_law():
    df = campaign()
    df["test_id"] = [f"T{i:04d}" for i in range(len(df))]
    qc = pd.concat(
        [
            df[["series"]].assign(valid=True, reason=""),
            pd.DataFrame({"series": ["1a-2s"] * 3, "valid": False, "reason": ["residual_tilt", "channel", "channel"]}),
        ]
    )
    df["e_an"] = np.where(df.boundary == "one-sided", -0.45, 0.98)
    rng = np.random.default_rng(0)
    imp = df[["test_id"]].loc[df.index.repeat(3)].reset_index(drop=True)
    imp["peak_before_over_alpha"] = rng.uniform(0.05, 0.8, len(imp))
    imp["v_over_vr"] = np.sqrt(imp.peak_before_over_alpha)
    e_an = imp.merge(df[["test_id", "e_an"]]).e_an.abs().to_numpy()
    imp["e_exp_k"] = e_an * (1.17 - 0.453 * imp.peak_before_over_alpha)
    t = series_table(df, qc, imp).set_index("series")
    assert t.loc["1a-2s", "n_valid"] == 15 and t.loc["1a-2s", "n_rejected"] == 3
    assert t.loc["1a-2s", "rejected_channel"] == 2 and t.loc["2a-2s", "rejected_channel"] == 0
    assert np.allclose(t.law_a, 1.17) and np.allclose(t.law_b, 0.453)
    for c in ("e_ratio_mean", "e_ratio_sd", "e_ratio_ci_low", "theta0_over_alpha_ci_high"):
        assert t[c].notna().all()
    # a reason no test of the campaign was rejected for is a column of zeros
    assert (t["rejected_instrument_malfunction"] == 0).all()
    clean = series_table(df, df[["series"]].assign(valid=True, reason=""), imp).set_index("series")
    assert {f"rejected_{v}" for v in ("instrument_malfunction", "residual_out_of_plumb")} <= set(clean.columns)
    assert (clean.n_rejected == 0).all() and (clean.filter(like="rejected_") == 0).all().all()


def test_cluster_bootstrap_sees_the_scatter_between_series():
    """Two-sided series: sd 0.01 within, 0.01 between: the series bootstrap is
    ~sqrt(15) wider than the test bootstrap, and covers the population mean."""
    df = campaign(shift=0.0)
    two = df[df.boundary == "two-sided"]
    lo, hi = cluster_bootstrap_ci(two.e_ratio, two.series, seed=1)
    t_lo, t_hi = bootstrap_ci(two.e_ratio, seed=1)
    assert lo < two.e_ratio.mean() < hi
    assert 2.5 < (hi - lo) / (t_hi - t_lo) < 6.0
    means = two.groupby("series").e_ratio.mean()
    s_lo, s_hi = stats.t.interval(0.95, len(means) - 1, means.mean(), stats.sem(means))
    assert hi - lo == pytest.approx(s_hi - s_lo, rel=0.35)
    assert (lo, hi) == cluster_bootstrap_ci(two.e_ratio, two.series, seed=1)
    assert np.isnan(cluster_bootstrap_ci([1.0, 2.0], ["a", "a"])[0])


def test_boundary_summary_and_table3():
    df = campaign()
    df["e_ratio_complete"] = df.e_ratio
    df["e_ratio_without_first_half_cycle"] = df.e_ratio + 0.3 * (df.boundary == "one-sided")
    df["e_ratio_first_half_cycle"] = df.e_ratio - 0.3 * (df.boundary == "one-sided")
    b = boundary_summary(df, ["e_ratio", "theta0_over_alpha"]).set_index(["boundary", "quantity"])
    assert b.loc[("one-sided", "e_ratio"), "mean"] == pytest.approx(df[df.boundary == "one-sided"].e_ratio.mean())
    assert b.loc[("two-sided", "theta0_over_alpha"), "n_series"] == 10
    assert (b.ci_low < b["mean"]).all() and (b["mean"] < b.ci_high).all()
    t3 = table3(df).set_index(["boundary", "column"])
    one = t3.loc["one-sided"]
    assert one.loc["e_ratio_without_first_half_cycle", "mean"] == pytest.approx(
        one.loc["e_ratio_complete", "mean"] + 0.3
    )
    assert list(one.paper) == [1.05, 1.34, 0.72]
    assert t3.loc["two-sided"].paper.isna().all()
    md = table3_markdown(table3(df))
    assert "disregarding the first half cycle" in md and "one-sided, paper" in md
    assert md.count("\n") == 4  # header, rule, two boundaries, the paper's row
