"""Statistics of the per-test ratios by test series (Sects. 3-4).

A series is specimen + boundary + contact depth (Table 2).  Tests within a
series are repetitions of the same set-up and are *not* independent
replicates of the factors that vary between series (h/b, unit material,
contact depth): Fig. 13 shows ratios that are stable within a series and
scattered between series.  Hence

* per-series summaries use the tests (mean, sd, bootstrap 95 % CI);
* "series that stand apart" are outliers among the series means:
  Iglewicz-Hoaglin modified z = 0.6745 (m - median) / MAD over the series
  means of one boundary condition, flagged at |z| > 3.5.  A test of each
  series against the pooled rest (Welch t, Holm-corrected) is reported
  too, but it is not the flag: with ~20 tests per series and a
  within-series sd of ~0.01 it declares nearly every series "different",
  whereas the question (Sect. 3, "only one test series shows much smaller
  values") is which series is atypical of the population of series;
* effects of contact depth and unit material are tested on the series
  means (Kruskal-Wallis; the experimental unit is the series), so that
  repeated tests do not inflate the sample size.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

from rocklab.dissipation import amplitude_law_fit

#: Ratios summarised per series.
RATIO_COLUMNS = ("e_ratio", "theta0_over_alpha", "T_quarter_p", "n_cycles", "duration_p",
                 "e_ratio_complete", "e_ratio_without_first_half_cycle",
                 "e_ratio_first_half_cycle")


def bootstrap_ci(values, n_boot=4000, level=0.95, seed=0):
    """Percentile bootstrap interval of the mean (vectorised, seeded).

    Returns (low, high); NaN for fewer than 2 finite values.
    """
    x = np.asarray(values, float)
    x = x[np.isfinite(x)]
    if x.size < 2:
        return np.nan, np.nan
    rng = np.random.default_rng(seed)
    means = x[rng.integers(0, x.size, size=(n_boot, x.size))].mean(axis=1)
    q = (1 - level) / 2
    lo, hi = np.quantile(means, [q, 1 - q])
    return float(lo), float(hi)


def series_stats(tests_df, columns=RATIO_COLUMNS, by="series", n_boot=4000, seed=0):
    """Mean, sd, bootstrap 95 % CI and count of each ratio by series.

    Returns one row per series with columns ``n``, and for each ratio X
    present in ``tests_df``: X_mean, X_sd, X_ci_low, X_ci_high.
    """
    cols = [c for c in columns if c in tests_df]
    rows = []
    for key, g in tests_df.groupby(by, sort=True):
        row = {by: key, "n": len(g)}
        for c in cols:
            x = g[c].to_numpy(float)
            lo, hi = bootstrap_ci(x, n_boot=n_boot, seed=seed)
            row |= {f"{c}_mean": np.nanmean(x) if np.isfinite(x).any() else np.nan,
                    f"{c}_sd": np.nanstd(x, ddof=1) if np.isfinite(x).sum() > 1 else np.nan,
                    f"{c}_ci_low": lo, f"{c}_ci_high": hi}
        rows.append(row)
    return pd.DataFrame(rows)


def holm(pvalues):
    """Holm step-down adjusted p-values (family-wise error control)."""
    p = np.asarray(pvalues, float)
    order = np.argsort(p)
    m = p.size
    adj = np.minimum(1.0, np.maximum.accumulate((m - np.arange(m)) * p[order]))
    out = np.empty_like(adj)
    out[order] = adj
    return out


def flag_outlying_series(tests_df, value="e_ratio", by="series", within="boundary", z_crit=3.5,
                         p_crit=0.05):
    """Series that stand apart from the others (see module docstring).

    Returns one row per series: within-group, n, mean, modified_z (over the
    series means of the group), welch_p and welch_p_holm (series vs pooled
    rest, Holm within the group), ``flagged`` (|modified_z| > z_crit) and
    ``test`` naming the rule.
    """
    out = []
    for gkey, grp in tests_df.groupby(within, sort=True):
        means = grp.groupby(by)[value].mean()
        med = means.median()
        mad = np.median(np.abs(means - med))
        z = 0.6745 * (means - med) / mad if mad > 0 else means * 0.0
        pv = []
        for s in means.index:
            a = grp.loc[grp[by] == s, value].dropna()
            b = grp.loc[grp[by] != s, value].dropna()
            pv.append(stats.ttest_ind(a, b, equal_var=False).pvalue
                      if len(a) > 1 and len(b) > 1 else np.nan)
        pv = np.asarray(pv, float)
        ph = np.full_like(pv, np.nan)
        ok = np.isfinite(pv)
        ph[ok] = holm(pv[ok])
        for i, s in enumerate(means.index):
            out.append({within: gkey, by: s, "n": int((grp[by] == s).sum()),
                        "mean": means[s], "modified_z": z[s], "welch_p": pv[i],
                        "welch_p_holm": ph[i], "welch_significant": ph[i] < p_crit,
                        "flagged": abs(z[s]) > z_crit,
                        "test": f"modified z of series means > {z_crit} (Iglewicz-Hoaglin)"})
    return pd.DataFrame(out)


def symmetry_test(tests_df, value, by="series", direction="direction"):
    """Push/pull symmetry in the series tested both ways (Sect. 4).

    Per series: mean push, mean pull, relative change (pull - push)/push as
    in the paper (13 % and 3 % for theta0), Welch t and Mann-Whitney p.
    """
    rows = []
    for key, g in tests_df.groupby(by, sort=True):
        a = g.loc[g[direction] == "push", value].dropna()
        b = g.loc[g[direction] == "pull", value].dropna()
        if len(a) < 2 or len(b) < 2:
            continue
        rows.append({by: key, "value": value, "n_push": len(a), "n_pull": len(b),
                     "mean_push": a.mean(), "mean_pull": b.mean(),
                     "relative_change": (b.mean() - a.mean()) / a.mean(),
                     "welch_p": stats.ttest_ind(a, b, equal_var=False).pvalue,
                     "mannwhitney_p": stats.mannwhitneyu(a, b).pvalue})
    return pd.DataFrame(rows)


def factor_effect(tests_df, factor, value="e_ratio", by="series", within="boundary",
                  p_crit=0.05):
    """Systematic effect of a between-series factor (contact depth, unit).

    Kruskal-Wallis on the series means grouped by the factor's levels, per
    boundary condition (the series is the experimental unit).  Returns one
    row per boundary: levels, n_series per level, level means, H, p,
    ``systematic`` (p < p_crit) and the test used.
    """
    rows = []
    d = tests_df.dropna(subset=[factor, value])
    for gkey, grp in d.groupby(within, sort=True):
        sm = grp.groupby(by).agg(level=(factor, "first"), m=(value, "mean"))
        groups = {lvl: s.m.to_numpy() for lvl, s in sm.groupby("level", sort=True)}
        if len(groups) < 2 or sum(len(v) for v in groups.values()) <= len(groups):
            continue
        H, p = stats.kruskal(*groups.values())
        rows.append({within: gkey, "factor": factor, "value": value,
                     "levels": list(groups), "n_series": [len(v) for v in groups.values()],
                     "level_means": [float(np.mean(v)) for v in groups.values()],
                     "statistic": H, "p": p, "systematic": p < p_crit,
                     "test": "Kruskal-Wallis on series means"})
    return pd.DataFrame(rows)


def series_table(tests_df, qc_df, impacts_df=None, by="series", n_boot=4000, seed=0):
    """results/series.csv: counts, e_ratio and theta0/alpha statistics, law.

    Parameters
    ----------
    tests_df : pandas.DataFrame
        results/tests.csv (valid tests).
    qc_df : pandas.DataFrame
        One row per test with ``series``, ``valid`` (bool) and ``reason``
        (rejection reason, ignored when valid).
    impacts_df : pandas.DataFrame, optional
        results/impacts.csv; adds the Eq. 15 fit (law_a, law_b, law_r2).

    Returns
    -------
    pandas.DataFrame
        series, n_valid, n_rejected, rejected_<reason>..., the statistics of
        :func:`series_stats` for e_ratio and theta0_over_alpha, law columns.
    """
    counts = qc_df.assign(valid=qc_df.valid.astype(bool))
    base = counts.groupby(by).valid.agg(n_valid="sum", n_tests="size").reset_index()
    base["n_rejected"] = base.n_tests - base.n_valid
    rej = counts[~counts.valid]
    if len(rej):
        rc = pd.crosstab(rej[by], rej.reason).add_prefix("rejected_").reset_index()
        base = base.merge(rc, on=by, how="left")
    st = series_stats(tests_df, ("e_ratio", "theta0_over_alpha"), by, n_boot, seed)
    out = base.merge(st.drop(columns="n"), on=by, how="left")
    if impacts_df is not None:
        law = amplitude_law_fit(impacts_df, tests_df, by=(by,), law="peak")
        law = law[[by, "a", "b", "r2"]].rename(columns={"a": "law_a", "b": "law_b",
                                                         "r2": "law_r2"})
        out = out.merge(law, on=by, how="left")
    rcols = [c for c in out if c.startswith("rejected_")]
    out[rcols] = out[rcols].fillna(0).astype(int)
    return out.drop(columns="n_tests")


def campaign_tables(datasets, qc_df, n_boot=4000, seed=0):
    """Every table of Sects. 3-4 for the valid tests of a campaign.

    Parameters
    ----------
    datasets : iterable of xarray.Dataset
        Reduced valid tests (``rocklab.reduction``).
    qc_df : pandas.DataFrame
        ``results/qc.csv``.

    Returns
    -------
    dict of pandas.DataFrame, and a list of (test_id, message)
        ``tests``, ``impacts``, ``e_by_n``, ``series``, ``laws`` (Eqs. 15 and
        17 by series and by boundary), ``effects`` (outlying series, contact
        depth, unit material, push/pull); the second item lists the valid
        tests whose motion could not be analysed, with the reason.
    """
    from rocklab.dissipation import analyse_reduced_test

    tests, impacts, e_n, failed = [], [], [], []
    for ds in datasets:
        try:
            s, i, e = analyse_reduced_test(ds)
        except ValueError as exc:
            failed.append((ds.attrs["test_id"], str(exc)))
            continue
        tests.append({**s, "unit": ds.attrs.get("unit", "")})
        impacts.append(i)
        e_n.append(e)
    tests = pd.DataFrame(tests)
    impacts = pd.concat(impacts, ignore_index=True) if impacts else pd.DataFrame()
    e_n = pd.concat(e_n, ignore_index=True) if e_n else pd.DataFrame()
    qc = qc_df.rename(columns={"reject_reason": "reason"})
    series = series_table(tests, qc, impacts, n_boot=n_boot, seed=seed)
    meta = tests.groupby("series").agg(boundary=("boundary", "first"), specimen=("specimen", "first"),
                                       contact_depth_mm=("contact_depth_mm", "first"),
                                       h_over_b=("h_over_b", "first"))
    series = series.merge(meta, left_on="series", right_index=True, how="left")
    outliers = flag_outlying_series(tests)
    if len(outliers):
        series = series.merge(outliers[["series", "modified_z", "flagged"]].rename(columns={"flagged": "stands_apart"}),
                              on="series", how="left")
    laws = pd.concat([
        amplitude_law_fit(impacts, tests, by=(by,), law=law).assign(grouping=by)
        for law in ("peak", "velocity") for by in ("series", "boundary")
    ], ignore_index=True)
    effects = pd.concat([
        factor_effect(tests[tests.boundary == "one-sided"], "contact_depth_mm"),
        factor_effect(tests, "unit"),
        symmetry_test(tests, "theta0_over_alpha").assign(factor="push/pull"),
        symmetry_test(tests, "e_ratio").assign(factor="push/pull"),
    ], ignore_index=True)
    return {"tests": tests, "impacts": impacts, "e_by_n": e_n, "series": series,
            "laws": laws, "effects": effects}, failed
