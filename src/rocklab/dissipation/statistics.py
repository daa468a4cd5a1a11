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
* effects of contact depth and unit material are tested on the means of
  the units they are properties of (Kruskal-Wallis; the series for contact
  depth, the wall for the unit material, :mod:`rocklab.lab.hierarchy`), so
  that repeated tests and series do not inflate the sample size;
* for the same reason, a value quoted for a whole boundary condition (the
  paper's "0.95" and "1.05", Table 3, summary.csv) is the mean over its
  tests, the paper's estimate, with a 95 % interval taken with the **wall**
  as the unit (:func:`boundary_summary`): the tests of a series repeat one
  set-up, and the series of a wall share its masonry and its hinge, so the
  units that vary independently are the walls (:mod:`rocklab.lab.hierarchy`).
  Its standard error is the cluster-robust one of the mean over tests with
  the walls as clusters, with Student's t on the walls' degrees of freedom
  (:func:`rocklab.inference.intervals.clustered_mean`: walls - 1 for walls of equal tests, fewer for
  unequal ones); a series bootstrap treated the 16 one-sided series of 3
  walls as 16 independent set-ups;
* every interval says what it rests on (tests, series, walls); below
  :data:`rocklab.inference.intervals.MIN_BOOTSTRAP` tests a series' value is given without one, and
  below the walls a t interval needs
  (:func:`rocklab.lab.hierarchy.too_few_units`) so is a boundary
  condition's, each with the reason
  (:func:`rocklab.inference.intervals.interval_note`,
  :func:`rocklab.inference.intervals.no_interval_note`).

The interval rules themselves (t, cluster-robust, bootstrap, their notes)
are :mod:`rocklab.inference`'s, shared with the diagnosis; this module holds
the tables of Sects. 3-4 that apply them.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from rocklab._imports import lazy_module
from rocklab.dissipation.analysis import AnalysedTests, amplitude_law_fit
from rocklab.inference.intervals import (
    MIN_BOOTSTRAP,
    bootstrap_ci,
    clustered_mean,
    interval_note,
    no_interval_note,
    t_interval,
)
from rocklab.inference.multiplicity import holm
from rocklab.inference.notes import counted, note_lines, note_mark
from rocklab.inference.power import smallest_kruskal_p
from rocklab.inference.verdicts import ClaimVerdict
from rocklab.lab.hierarchy import COVARIATE_LEVEL, UNIT_COLUMN, plural, too_few_units
from rocklab.lab.validity import Verdict
from rocklab.physics.boundary import Boundary
from rocklab.physics.restitution import CALIBRATED_RATIO_ONE_SIDED

if TYPE_CHECKING:
    import xarray as xr

stats = lazy_module("scipy.stats")

log = logging.getLogger(__name__)

#: Per-series quantities of results/series.csv (Figs. 13, 16-20).
SERIES_COLUMNS = (
    "e_ratio",
    "theta0_over_alpha",
    "T_quarter_p",
    "T_quarter_p_housner",
    "T_quarter_p_linear",
    "n_cycles",
    "duration_p",
    "centre_amplification",
)
#: The windows of Table 3 (tests.csv column -> the paper's heading).
TABLE3_WINDOWS = {
    "e_ratio_complete": "complete",
    "e_ratio_without_first_half_cycle": "disregarding the first half cycle",
    "e_ratio_first_half_cycle": "considering only the first half cycle",
}
#: Ratios summarised per series.
RATIO_COLUMNS = (*SERIES_COLUMNS, *TABLE3_WINDOWS)
#: Table 3 of the paper (one-sided rocking only), e_exp / e_an,1s.
PAPER_TABLE3 = {
    (Boundary.ONE_SIDED, "e_ratio_complete"): CALIBRATED_RATIO_ONE_SIDED,
    (Boundary.ONE_SIDED, "e_ratio_without_first_half_cycle"): 1.34,
    (Boundary.ONE_SIDED, "e_ratio_first_half_cycle"): 0.72,
}


def boundary_summary(
    tests_df: pd.DataFrame,
    columns: Sequence[str],
    walls: Mapping[str, str],
    by: str = "series",
    within: str = "boundary",
) -> pd.DataFrame:
    """Mean of per-test quantities by boundary condition, with its 95 % interval on walls.

    The estimate is the mean over the tests (the paper's); its interval is
    Student's t with the cluster-robust standard error of that mean, the
    walls as clusters, on the walls' degrees of freedom
    (:func:`clustered_mean`; walls - 1 for walls of equal tests, for
    which it is the t interval of the wall means): the series of a wall
    share its masonry and hinge, so the walls, not the series, are the
    independent units.  Where the walls are too few for a t interval
    (:func:`rocklab.lab.hierarchy.too_few_units`: fewer than MIN_DF + 1) the
    value has none and ``ci_note`` says why.

    Parameters
    ----------
    tests_df : pandas.DataFrame
        tests.csv, with ``specimen``.
    columns : list of str
        The quantities.
    walls : mapping
        Specimen -> wall (:func:`rocklab.lab.hierarchy.walls_of_specimens`).

    Returns
    -------
    pandas.DataFrame
        One row per (boundary, quantity) with data: n_tests, n_series,
        n_walls, mean (over tests), sd (between tests), series_sd (between
        series means), ci_low, ci_high, df (the t's degrees of freedom) and
        ci_note (:func:`no_interval_note`; "" where there is an interval).
    """
    wall = tests_df.specimen.map(walls)
    if wall.isna().any():
        raise ValueError(f"specimens without a wall: {sorted(set(tests_df.specimen[wall.isna()]))}")
    rows = []
    for key, g in tests_df.assign(wall=wall).groupby(within, sort=True):
        for c in columns:
            d = g[[by, "wall", c]].dropna() if c in g else g.iloc[:0]
            if d.empty:
                continue
            m, se, df, k, reason = clustered_mean(d[c], d.wall, "wall")
            lo, hi = (np.nan, np.nan) if reason else t_interval(m, se, df)[:2]
            rows.append(
                {
                    within: key,
                    "quantity": c,
                    "n_tests": len(d),
                    "n_series": d[by].nunique(),
                    "n_walls": k,
                    "mean": m,
                    "sd": d[c].std(ddof=1),
                    "series_sd": d.groupby(by)[c].mean().std(ddof=1),
                    "ci_low": lo,
                    "ci_high": hi,
                    "df": np.nan if reason else df,
                    "ci_note": no_interval_note(reason),
                }
            )
    return pd.DataFrame(rows)


def table3(tests_df: pd.DataFrame, walls: Mapping[str, str]) -> pd.DataFrame:
    """Table 3: e_exp / |e_an| over the paper's three windows, by boundary.

    The paper gives the one-sided row only (1.05, 1.34, 0.72); the
    two-sided row is computed the same way (Eq. 11 over the windows of
    :func:`rocklab.dissipation.analysis.table3_windows`).

    Parameters
    ----------
    tests_df : pandas.DataFrame
        tests.csv.
    walls : mapping
        Specimen -> wall, the unit of the intervals (:func:`boundary_summary`).

    Returns
    -------
    pandas.DataFrame
        boundary, window (the paper's heading), column (of tests.csv), the
        statistics of :func:`boundary_summary` and ``paper``.
    """
    out = boundary_summary(tests_df, list(TABLE3_WINDOWS), walls)
    out = out.rename(columns={"quantity": "column"})
    out.insert(1, "window", out.column.map(TABLE3_WINDOWS))
    out["paper"] = [PAPER_TABLE3.get(k, np.nan) for k in zip(out.boundary, out.column)]
    return out


def interval_cells(stats: pd.DataFrame, fmt: str = ".3f") -> tuple[list[str], list[str]]:
    """Markdown cells "mean [low, high] (n tests, k series, w walls)" of :func:`boundary_summary` rows, and
    their notes.

    A value without an interval is followed by a mark instead; the notes
    (one per distinct ``ci_note``, e.g. "† 2 walls, 1 residual df (2
    needed): no interval") go under the table.

    Returns
    -------
    cells : list of str
    notes : list of str
    """
    notes: dict[str, str] = {}
    cells: list[str] = []
    for r in stats.itertuples():
        n = f"({counted(r.n_tests, 'test')}, {counted(r.n_series, 'series')}, {counted(r.n_walls, 'wall')})"
        if r.ci_note:
            cells.append(f"{r.mean:{fmt}}{note_mark(notes, r.ci_note)} {n}")
        else:
            cells.append(f"{r.mean:{fmt}} [{r.ci_low:{fmt}}, {r.ci_high:{fmt}}] {n}")
    return cells, note_lines(notes)


def table3_markdown(t3: pd.DataFrame) -> str:
    """Table 3 as markdown: one row per boundary, mean [95 % CI on walls] (tests, series, walls), the paper's row.

    A value resting on too few walls for an interval
    (:func:`boundary_summary`) is marked, and the reason follows the table.
    """
    t3 = t3.assign(ci_note=t3.ci_note.astype(object).fillna(""))
    cells, notes = interval_cells(t3)
    wide = t3.assign(cell=cells).pivot(index="boundary", columns="window", values="cell")
    wide = wide[[w for w in TABLE3_WINDOWS.values() if w in wide]]
    for b, g in t3.dropna(subset=["paper"]).groupby("boundary"):
        wide.loc[f"{b}, paper"] = [f"{v:.2f}" for v in g.set_index("window").paper.reindex(wide.columns)]
    table = wide.rename_axis("boundary").reset_index().to_markdown(index=False)
    return "\n\n".join([table, *notes]) if notes else table


def series_stats(
    tests_df: pd.DataFrame,
    columns: Sequence[str] = RATIO_COLUMNS,
    by: str = "series",
    n_boot: int = 4000,
    seed: int = 0,
) -> pd.DataFrame:
    """Mean, sd, bootstrap 95 % CI and count of each ratio by series.

    Returns
    -------
    pandas.DataFrame
        One row per series with columns ``n``, for each ratio X present in
        ``tests_df``: X_n (tests with a value, on which the interval rests),
        X_mean, X_sd, X_ci_low, X_ci_high (NaN below :data:`MIN_BOOTSTRAP`
        tests), and ``ci_note``: why intervals of values are missing (""
        where none is).
    """
    cols = [c for c in columns if c in tests_df]
    rows = []
    for key, g in tests_df.groupby(by, sort=True):
        row = {by: key, "n": len(g)}
        short: dict[int, list[str]] = {}
        for c in cols:
            x = g[c].to_numpy(float)
            n = int(np.isfinite(x).sum())
            lo, hi = bootstrap_ci(x, n_boot=n_boot, seed=seed)
            row |= {
                f"{c}_n": n,
                f"{c}_mean": np.nanmean(x) if n else np.nan,
                f"{c}_sd": np.nanstd(x, ddof=1) if n > 1 else np.nan,
                f"{c}_ci_low": lo,
                f"{c}_ci_high": hi,
            }
            if 0 < n < MIN_BOOTSTRAP:
                short.setdefault(n, []).append(c)
        # one note per row; a quantity short of the tests the others have is named
        present = [c for c in cols if row[f"{c}_n"]]
        row["ci_note"] = "; ".join(
            interval_note(n) if names == present else f"{interval_note(n)}: {', '.join(names)}"
            for n, names in sorted(short.items())
        )
        rows.append(row)
    return pd.DataFrame(rows)


def flag_outlying_series(
    tests_df: pd.DataFrame,
    value: str = "e_ratio",
    by: str = "series",
    within: str = "boundary",
    z_crit: float = 3.5,
    p_crit: float = 0.05,
) -> pd.DataFrame:
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
        welch = []
        for s in means.index:
            a = grp.loc[grp[by] == s, value].dropna()
            b = grp.loc[grp[by] != s, value].dropna()
            welch.append(stats.ttest_ind(a, b, equal_var=False).pvalue if len(a) > 1 and len(b) > 1 else np.nan)
        pv = np.asarray(welch, float)
        ph = np.full_like(pv, np.nan)
        ok = np.isfinite(pv)
        ph[ok] = holm(pv[ok])
        for i, s in enumerate(means.index):
            out.append(
                {
                    within: gkey,
                    by: s,
                    "n": int((grp[by] == s).sum()),
                    "mean": means[s],
                    "modified_z": z[s],
                    "welch_p": pv[i],
                    "welch_p_holm": ph[i],
                    "welch_significant": ph[i] < p_crit,
                    "flagged": abs(z[s]) > z_crit,
                    "test": f"modified z of series means > {z_crit} (Iglewicz-Hoaglin)",
                }
            )
    return pd.DataFrame(out)


def symmetry_test(tests_df: pd.DataFrame, value: str, by: str = "series", direction: str = "direction") -> pd.DataFrame:
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
        rows.append(
            {
                by: key,
                "value": value,
                "n_push": len(a),
                "n_pull": len(b),
                "mean_push": a.mean(),
                "mean_pull": b.mean(),
                "relative_change": (b.mean() - a.mean()) / a.mean(),
                "welch_p": stats.ttest_ind(a, b, equal_var=False).pvalue,
                "mannwhitney_p": stats.mannwhitneyu(a, b).pvalue,
            }
        )
    return pd.DataFrame(rows)


def factor_effect(
    tests_df: pd.DataFrame,
    factor: str,
    value: str = "e_ratio",
    walls: Mapping[str, str] | None = None,
    within: str = "boundary",
    p_crit: float = 0.05,
) -> pd.DataFrame:
    """Systematic effect of a between-series factor (contact depth, unit material).

    Kruskal-Wallis on the means of the units the factor is a property of
    (:data:`rocklab.lab.hierarchy.COVARIATE_LEVEL`: the series for contact
    depth, the wall for the unit material), grouped by the factor's levels,
    per boundary condition: two series of one wall are one wall's evidence
    about its material.  Below the units a test needs
    (:func:`rocklab.lab.hierarchy.too_few_units`), or where even groups wholly
    apart cannot reach ``p_crit`` (:func:`rocklab.inference.power.smallest_kruskal_p`:
    3 walls against 2 reach 0.083 at best), the row gives no statistic and its
    ``test`` says why.

    Parameters
    ----------
    walls : mapping, optional
        Specimen -> wall; needed for a property of the wall.

    Returns
    -------
    pandas.DataFrame
        One row per boundary: levels, n_units per level, level means, H, p,
        ``systematic`` (p < p_crit), ``unit_level`` and the test used.
    """
    level = COVARIATE_LEVEL[factor]
    rows = []
    d = tests_df.dropna(subset=[factor, value])
    if level == "wall":
        d = d.assign(wall=d.specimen.map(walls))
    for gkey, grp in d.groupby(within, sort=True):
        sm = grp.groupby(UNIT_COLUMN[level]).agg(level=(factor, "first"), m=(value, "mean"))
        groups = {lvl: s.m.to_numpy() for lvl, s in sm.groupby("level", sort=True)}
        if len(groups) < 2:
            continue
        per_level = {str(k): len(v) for k, v in groups.items()}
        reason = too_few_units(level, len(sm), len(sm) - len(groups), per_level)
        floor = smallest_kruskal_p(list(per_level.values()))
        if not reason and floor >= p_crit:
            # wholly apart, these units cannot reach the level: a p above it says nothing of an effect
            reason = f"{plural(level, len(sm))}: the test reaches p = {floor:.2g} at best, not below {p_crit}"
        H, p = (np.nan, np.nan) if reason else stats.kruskal(*groups.values())
        rows.append(
            {
                within: gkey,
                "factor": factor,
                "value": value,
                "levels": list(groups),
                "n_units": [len(v) for v in groups.values()],
                "unit_level": level,
                "level_means": [float(np.mean(v)) for v in groups.values()],
                "statistic": H,
                "p": p,
                "systematic": bool(p < p_crit),
                "test": f"{ClaimVerdict.NOT_TESTABLE}: {reason}" if reason else f"Kruskal-Wallis on {level} means",
            }
        )
    return pd.DataFrame(rows)


def series_table(
    tests_df: pd.DataFrame,
    qc_df: pd.DataFrame,
    impacts_df: pd.DataFrame | None = None,
    by: str = "series",
    n_boot: int = 4000,
    seed: int = 0,
) -> pd.DataFrame:
    """results/series.csv: counts, statistics of :data:`SERIES_COLUMNS`, law.

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
        :func:`series_stats` for the :data:`SERIES_COLUMNS` present in
        ``tests_df``, law columns.
    """
    counts = qc_df.assign(valid=qc_df.valid.astype(bool))
    base = counts.groupby(by).valid.agg(n_valid="sum", n_tests="size").reset_index()
    base["n_rejected"] = base.n_tests - base.n_valid
    rej = counts[~counts.valid]
    # every reason a series' test can be rejected for has its column, 0 where none was
    reasons = sorted({v.value for v in Verdict.rejections() if v is not Verdict.UNREADABLE} | set(rej.reason))
    rc = pd.crosstab(rej[by], rej.reason).reindex(columns=reasons, fill_value=0)
    base = base.merge(rc.add_prefix("rejected_").reset_index(), on=by, how="left")
    st = series_stats(tests_df, SERIES_COLUMNS, by, n_boot, seed)
    out = base.merge(st.drop(columns="n"), on=by, how="left")
    if impacts_df is not None:
        law = amplitude_law_fit(impacts_df, tests_df, by=(by,), law="peak")
        law = law[[by, "a", "b", "r2"]].rename(columns={"a": "law_a", "b": "law_b", "r2": "law_r2"})
        out = out.merge(law, on=by, how="left")
    rcols = [c for c in out if c.startswith("rejected_")]
    out[rcols] = out[rcols].fillna(0).astype(int)
    return out.drop(columns="n_tests")


def campaign_tables(
    analysed: AnalysedTests | Iterable[xr.Dataset],
    qc_df: pd.DataFrame,
    walls: Mapping[str, str],
    n_boot: int = 4000,
    seed: int = 0,
) -> tuple[dict[str, pd.DataFrame], list[tuple[str, str]]]:
    """Every table of Sects. 3-4 for the valid tests of a campaign.

    Parameters
    ----------
    analysed : AnalysedTests, or iterable of xarray.Dataset
        The per-test tables of the valid tests
        (:class:`~rocklab.dissipation.analysis.AnalysedTests`), or their
        stored motions (:func:`rocklab.lab.motion.stored_motion`), analysed here.
    qc_df : pandas.DataFrame
        ``results/qc.csv``.
    walls : mapping
        Specimen -> wall (:func:`rocklab.lab.hierarchy.walls_of_specimens`),
        the unit of the unit material's effect and of the intervals of
        ``table3`` and ``summary``.

    Returns
    -------
    dict of pandas.DataFrame, and a list of (test_id, message)
        ``tests``, ``impacts``, ``e_by_n``, ``series``, ``laws`` (Eqs. 15 and
        17 by series and by boundary), ``effects`` (contact depth and unit
        material on e_ratio, contact depth on the channel-5 amplification,
        push/pull), ``table3`` (:func:`table3`) and ``summary``
        (:func:`boundary_summary` of :data:`SERIES_COLUMNS`); the second item
        lists the valid tests whose motion could not be analysed, with the
        reason.
    """
    if not isinstance(analysed, AnalysedTests):
        analysed = AnalysedTests.of(analysed)
    tests, impacts, e_n = pd.DataFrame(analysed.tests), analysed.impacts, analysed.e_by_n
    qc = qc_df.rename(columns={"reject_reason": "reason"})
    series = series_table(tests, qc, impacts, n_boot=n_boot, seed=seed)
    meta = tests.groupby("series").agg(
        boundary=("boundary", "first"),
        specimen=("specimen", "first"),
        contact_depth_mm=("contact_depth_mm", "first"),
        h_over_b=("h_over_b", "first"),
    )
    series = series.merge(meta, left_on="series", right_index=True, how="left")
    outliers = flag_outlying_series(tests)
    if len(outliers):
        series = series.merge(
            outliers[["series", "modified_z", "flagged"]].rename(columns={"flagged": "stands_apart"}),
            on="series",
            how="left",
        )
    laws = pd.concat(
        [
            amplitude_law_fit(impacts, tests, by=(by,), law=law).assign(grouping=by)
            for law in ("peak", "velocity")
            for by in ("series", "boundary")
        ],
        ignore_index=True,
    )
    one = tests[tests.boundary == Boundary.ONE_SIDED]
    effects = pd.concat(
        [
            factor_effect(one, "contact_depth_mm"),
            factor_effect(tests, "unit", walls=walls),
            factor_effect(one, "contact_depth_mm", value="centre_amplification"),
            symmetry_test(tests, "theta0_over_alpha").assign(factor="push/pull"),
            symmetry_test(tests, "e_ratio").assign(factor="push/pull"),
        ],
        ignore_index=True,
    )
    t3 = table3(tests, walls)
    for r in series[series.ci_note.fillna("") != ""].itertuples():
        log.warning("series %s: %s", r.series, r.ci_note)
    for b, note in t3[t3.ci_note != ""].groupby("boundary").ci_note.first().items():
        log.warning("%s, Table 3 and summary.csv: %s", b, note)
    return {
        "tests": tests,
        "impacts": impacts,
        "e_by_n": e_n,
        "series": series,
        "laws": laws,
        "effects": effects,
        "table3": t3,
        "summary": boundary_summary(tests, SERIES_COLUMNS, walls),
    }, analysed.failed
