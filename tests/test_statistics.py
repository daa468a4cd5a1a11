"""rocklab.dissipation.statistics on synthetic campaigns with known structure."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from rocklab.dissipation.statistics import (
    boundary_summary,
    factor_effect,
    flag_outlying_series,
    series_stats,
    series_table,
    symmetry_test,
    table3,
    table3_markdown,
)
from rocklab.inference.intervals import (
    bootstrap_ci,
    clustered_mean,
    expanded,
    mean_over_units,
    percentile_interval,
    small_sample_expansion,
)
from rocklab.inference.multiplicity import holm, simultaneous_factor


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


@pytest.mark.parametrize("n", [40, 200])
def test_a_percentile_interval_holds_its_level_of_the_resampled_distribution(n):
    """Order statistics j < k of n draws hold (k - j) / (n + 1) of the distribution on average (a Beta law):
    the interval of n standard normal draws holds 95 % of N(0, 1) over many repeats, where numpy's default
    position holds (n - 1) 0.95 / (n + 1), 0.904 from 40 draws."""
    x = np.random.default_rng(1).normal(size=(20000, n))
    lo, hi = percentile_interval(x, axis=1)
    content = stats.norm.cdf(hi) - stats.norm.cdf(lo)
    assert content.mean() == pytest.approx(0.95, abs=0.002)
    default = np.diff(stats.norm.cdf(np.percentile(x, [2.5, 97.5], axis=1)), axis=0).mean()
    assert default == pytest.approx((n - 1) * 0.95 / (n + 1), abs=0.004)


def test_a_percentile_interval_of_39_draws_is_their_range():
    x = np.random.default_rng(2).permutation(np.arange(1.0, 40.0))
    assert percentile_interval(x) == pytest.approx((1.0, 39.0))


@pytest.mark.parametrize("n", [5, 10])
def test_the_expanded_percentile_interval_of_a_mean_over_few_units_holds_95_percent(n):
    """The percentile interval of the mean over n normal units holds P(|t_{n-1}| < z sqrt((n-1)/n)) of the
    time (0.85 from 5 units); widened by sqrt(n/(n-1)) t_{n-1}/z about the mean it holds 95 %, as the t
    interval does (Hesterberg 2015)."""
    rng = np.random.default_rng(7)
    x = rng.normal(size=(4000, n))
    means = np.take_along_axis(x[:, None, :], rng.integers(0, n, (4000, 200, n)), axis=2).mean(axis=2)
    lo, hi = percentile_interval(means, axis=1)
    plain = ((lo <= 0) & (hi >= 0)).mean()
    z = stats.norm.ppf(0.975)
    assert plain == pytest.approx(1 - 2 * stats.t.sf(z * np.sqrt((n - 1) / n), n - 1), abs=0.02)
    f = small_sample_expansion(n)
    centre = x.mean(axis=1)
    e_lo, e_hi = centre - f * (centre - lo), centre + f * (hi - centre)
    assert ((e_lo <= 0) & (e_hi >= 0)).mean() == pytest.approx(0.95, abs=0.015)
    assert expanded((lo[0], hi[0]), centre[0], n) == pytest.approx((e_lo[0], e_hi[0]))


def test_the_expansion_vanishes_with_many_units_and_the_bootstrap_ci_takes_it():
    assert small_sample_expansion(5) == pytest.approx(np.sqrt(5 / 4) * stats.t.ppf(0.975, 4) / 1.959964)
    assert small_sample_expansion(100000) == pytest.approx(1.0, abs=1e-4)
    x = np.random.default_rng(4).normal(1.0, 0.1, 6)
    rng = np.random.default_rng(0)
    plain = percentile_interval(x[rng.integers(0, 6, (4000, 6))].mean(axis=1))
    assert bootstrap_ci(x, seed=0) == pytest.approx(expanded(plain, x.mean(), 6))


@pytest.mark.parametrize(("k", "df"), [(2, np.inf), (3, np.inf), (2, 4)])
def test_simultaneous_intervals_hold_all_their_parameters_at_95_percent(k, df):
    """k independent estimates, each with its t interval on df: widened by the Šidák factor, all k are
    inside together 95 % of the time (the plain intervals, 0.95^k)."""
    rng = np.random.default_rng(3)
    t = rng.standard_t(df, size=(40000, k)) if np.isfinite(df) else rng.normal(size=(40000, k))
    q = stats.t.ppf(0.975, df)
    assert (np.abs(t) < q).all(axis=1).mean() == pytest.approx(0.95**k, abs=0.006)
    assert (np.abs(t) < q * simultaneous_factor(k, df)).all(axis=1).mean() == pytest.approx(0.95, abs=0.004)
    assert simultaneous_factor(1, df) == 1.0


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
    # five walls reaches 0.05, so the row is not testable, not a p that reads as no effect
    assert u.loc["two-sided", "n_units"] == [3, 2] and u.loc["two-sided", "unit_level"] == "wall"
    assert np.isnan(u.loc["two-sided", "p"]) and not u.loc["two-sided", "systematic"]
    assert u.loc["two-sided", "test"] == "not testable: 5 walls: the test reaches p = 0.083 at best, not below 0.05"
    # with the level of the test above that floor, the same walls are tested
    loose = factor_effect(planted, "unit", walls=walls, p_crit=0.1).set_index("boundary")
    assert loose.loc["two-sided", "statistic"] == pytest.approx(3.0)
    assert loose.loc["two-sided", "p"] == pytest.approx(stats.chi2.sf(3.0, 1)) and loose.loc["two-sided", "systematic"]
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


#: The walls of the specimens of :func:`campaign` (a specimen is its wall fractured lower: 1a, 1b -> wall 1).
WALLS = {sp: sp[0] for sp in ("1a", "1b", "1c", "2a", "2b", "3a", "3b", "4b", "5a", "5b", "5c")}


def walls_campaign(tests_per_series, series_per_wall=3, seed=0, wall_sd=0.05, series_sd=0.002, test_sd=0.01):
    """One boundary condition: walls around 1.05 with a wall effect (sd ``wall_sd``) that the series of a wall
    share; ``tests_per_series`` one entry per wall."""
    rng = np.random.default_rng(seed)
    rows = []
    for w, n in enumerate(tests_per_series):
        mu_w = 1.05 + wall_sd * rng.standard_normal()
        for j in range(series_per_wall):
            mu_s = mu_w + series_sd * rng.standard_normal()
            sp = f"{w}{'abc'[j % 3]}"
            rows += [(f"{sp}-1s-{j}", sp, "one-sided", mu_s + test_sd * rng.standard_normal()) for _ in range(n)]
    df = pd.DataFrame(rows, columns=["series", "specimen", "boundary", "e_ratio"])
    for c in ("e_ratio_complete", "e_ratio_without_first_half_cycle", "e_ratio_first_half_cycle"):
        df[c] = df.e_ratio
    return df, {sp: sp[:-1] for sp in df.specimen}


def test_many_series_on_two_walls_give_no_interval_and_say_why():
    """Twelve series are the evidence of two walls: a t interval on one df is not given (issue 24)."""
    df, walls = walls_campaign([5, 5], series_per_wall=6)
    b = boundary_summary(df, ["e_ratio"], walls).iloc[0]
    assert (b.n_tests, b.n_series, b.n_walls) == (60, 12, 2)
    assert b["mean"] == pytest.approx(df.e_ratio.mean())
    assert np.isnan(b.ci_low) and np.isnan(b.ci_high) and np.isnan(b.df)
    assert b.ci_note == "2 walls, 1 residual df (2 needed): no interval"
    md = table3_markdown(table3(df, walls))
    assert "[" not in md and "(60 tests, 12 series, 2 walls)" in md
    assert md.endswith("† 2 walls, 1 residual df (2 needed): no interval")


def test_six_walls_give_the_t_interval_of_their_means_on_five_df():
    """Equal tests per wall: the interval is the closed-form t interval of the six wall means, however many
    series each wall has, and far wider than one that took the 18 series as units."""
    df, walls = walls_campaign([8] * 6)
    b = boundary_summary(df, ["e_ratio"], walls).iloc[0]
    means = df.groupby(df.specimen.map(walls)).e_ratio.mean()
    lo, hi = stats.t.interval(0.95, 5, means.mean(), stats.sem(means))
    assert (b.n_walls, b.n_series, b.ci_note) == (6, 18, "") and b.df == pytest.approx(5)
    assert b["mean"] == pytest.approx(means.mean())
    assert (b.ci_low, b.ci_high) == pytest.approx((lo, hi), rel=1e-12)
    series = df.groupby("series").e_ratio.mean()
    s_lo, s_hi = stats.t.interval(0.95, len(series) - 1, series.mean(), stats.sem(series))
    assert b.ci_high - b.ci_low > 1.5 * (s_hi - s_lo)


def cr2_by_matrices(y, clusters):
    """The CR2 standard error of the intercept-only least squares and its Imbens-Kolesar df, from the
    N x N definitions: A_g = (I - H_gg)^(-1/2), V = (X'X)^-1 sum_g X_g' A_g u_g u_g' A_g X_g (X'X)^-1,
    G_g = (I - H)_(., g) A_g X_g (X'X)^-1, df = tr(G'G)^2 / tr((G'G)^2)."""
    y = np.asarray(y, float)
    X = np.ones((y.size, 1))
    bread = np.linalg.inv(X.T @ X)
    H = X @ bread @ X.T
    u = y - H @ y
    meat, cols = 0.0, []
    for g in pd.unique(clusters):
        idx = np.flatnonzero(np.asarray(clusters) == g)
        vals, vecs = np.linalg.eigh(np.eye(idx.size) - H[np.ix_(idx, idx)])
        A = vecs @ np.diag(vals**-0.5) @ vecs.T
        score = X[idx].T @ A @ u[idx]
        meat = meat + np.outer(score, score)
        cols.append((np.eye(y.size) - H)[:, idx] @ A @ X[idx] @ bread)
    Gm = np.hstack(cols)
    GG = Gm.T @ Gm
    return float(np.sqrt(bread @ meat @ bread)[0, 0]), float(np.trace(GG) ** 2 / np.trace(GG @ GG))


def test_unequal_walls_take_the_cr2_interval_of_the_mean_over_tests():
    """The paper's mean over tests with the walls as clusters, checked against CR2 and its degrees of
    freedom written from their matrix definitions; fewer df than walls - 1 for walls of unequal tests."""
    df, walls = walls_campaign([3, 20, 7, 12], series_per_wall=2, seed=4)
    b = boundary_summary(df, ["e_ratio"], walls).iloc[0]
    wall = df.specimen.map(walls)
    se, dof = cr2_by_matrices(df.e_ratio, wall)
    assert 1 < dof < 3
    q = stats.t.ppf(0.975, dof)
    m = df.e_ratio.mean()
    assert b["mean"] == pytest.approx(m)
    assert (b.ci_low, b.ci_high, b.df) == pytest.approx((m - q * se, m + q * se, dof), rel=1e-10)
    *numbers, k, reason = clustered_mean(df.e_ratio, wall, "wall")
    assert numbers == pytest.approx([m, se, dof], rel=1e-10) and (k, reason) == (4, "")
    # equal tests per wall: the t interval of the wall means, on walls - 1 df (mean_over_units)
    eq, eq_walls = walls_campaign([5] * 4, seed=4)
    m_u, se_u, k_u, _ = mean_over_units(eq.e_ratio, eq.specimen.map(eq_walls), "wall")
    *numbers, k, _ = clustered_mean(eq.e_ratio, eq.specimen.map(eq_walls), "wall")
    assert numbers == pytest.approx([m_u, se_u, 3]) and k == k_u == 4


def test_the_interval_on_unequal_walls_covers_its_mean():
    """Coverage of the 95 % interval of a mean over tests on four walls, one of them holding 60 of the 75
    tests, walls scattering five times more than their tests: near or above 95 % (CR1 on walls - 1 df
    covers about 62 % here)."""
    rng = np.random.default_rng(7)
    n = np.array([5, 5, 5, 60])
    wall = np.repeat(np.arange(4), n)
    hits = 0
    for _ in range(1000):
        y = 0.05 * rng.standard_normal(4)[wall] + 0.01 * rng.standard_normal(n.sum())
        m, se, dof, _, _ = clustered_mean(y, wall, "wall")
        hits += abs(m) < stats.t.ppf(0.975, dof) * se
    assert 0.93 < hits / 1000 < 0.995


def test_boundary_summary_and_table3():
    df = campaign()
    df["e_ratio_complete"] = df.e_ratio
    df["e_ratio_without_first_half_cycle"] = df.e_ratio + 0.3 * (df.boundary == "one-sided")
    df["e_ratio_first_half_cycle"] = df.e_ratio - 0.3 * (df.boundary == "one-sided")
    b = boundary_summary(df, ["e_ratio", "theta0_over_alpha"], WALLS).set_index(["boundary", "quantity"])
    assert b.loc[("one-sided", "e_ratio"), "mean"] == pytest.approx(df[df.boundary == "one-sided"].e_ratio.mean())
    assert b.loc[("two-sided", "theta0_over_alpha"), "n_series"] == 10
    assert b.loc[("two-sided", "theta0_over_alpha"), "n_walls"] == 5
    assert b.loc[("one-sided", "e_ratio"), "n_walls"] == 3
    assert (b.ci_low < b["mean"]).all() and (b["mean"] < b.ci_high).all()
    t3 = table3(df, WALLS).set_index(["boundary", "column"])
    one = t3.loc["one-sided"]
    assert one.loc["e_ratio_without_first_half_cycle", "mean"] == pytest.approx(
        one.loc["e_ratio_complete", "mean"] + 0.3
    )
    assert list(one.paper) == [1.05, 1.34, 0.72]
    assert t3.loc["two-sided"].paper.isna().all()
    md = table3_markdown(table3(df, WALLS))
    assert "disregarding the first half cycle" in md and "one-sided, paper" in md
    assert md.count("\n") == 4  # header, rule, two boundaries, the paper's row


def test_a_series_whose_tests_were_all_rejected_leaves_the_pooled_laws_whole():
    from rocklab.dissipation.dissipation_summary import _laws

    # series.csv has no boundary for a series without a valid test, and no law of it
    series = pd.DataFrame({"series": ["1a-2s", "2a-2s", "3b-1s-cd260"], "boundary": ["two-sided", "two-sided", None]})
    laws = pd.DataFrame(
        {
            "series": ["1a-2s", "2a-2s", None],
            "law": "peak",
            "a": [1.0, 0.96, 0.98],
            "b": [0.12, 0.03, 0.07],
            "r2": [0.2, 0.4, 0.3],
            "n": [37, 47, 84],
            "grouping": ["series", "series", "boundary"],
            "boundary": [None, None, "two-sided"],
        }
    )
    out = _laws(laws, series)
    assert out["two_sided"]["peak"]["series_median_r2"] == pytest.approx(0.3)
    assert out["two_sided"]["peak"]["a"] == 0.98 and out["one_sided"] == {}


@pytest.mark.parametrize("sizes", [[3, 2], [2, 2], [1, 3], [4, 6, 6], [5, 5, 5], [2, 3, 4], [3, 1, 2, 2]])
def test_the_floor_of_a_rank_test_is_the_p_of_groups_wholly_apart(sizes):
    """smallest_kruskal_p: scipy's Kruskal-Wallis p of groups wholly apart, in the order of ranks that
    gives the largest H; no arrangement of distinct values reaches below it."""
    from itertools import permutations

    from rocklab.inference.power import smallest_kruskal_p

    def wholly_apart(order):
        ends = np.cumsum([0, *order])
        return stats.kruskal(*[np.arange(a, b, dtype=float) for a, b in zip(ends[:-1], ends[1:])]).pvalue

    floor = smallest_kruskal_p(sizes)
    assert floor == pytest.approx(min(wholly_apart(order) for order in permutations(sizes)), rel=1e-12)
    ends = np.cumsum([0, *sizes])
    rng = np.random.default_rng(len(sizes))
    for _ in range(200):
        x = rng.permutation(int(ends[-1])).astype(float)
        assert stats.kruskal(*np.split(x, ends[1:-1])).pvalue >= floor * (1 - 1e-12)
