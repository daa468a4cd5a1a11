"""The campaign level: every parameter against the specimen and test covariates (issue 12, item 2).

The paper states campaign-wide facts from Fig. 13 and Table 3 by eye: the
ratio e_exp/e_an,2s "is close to one, irrespective of the aspect ratio",
contact depth "has no systematic influence" on one-sided rocking, "the unit
material has no effect", e "remains stable test after test".  Here each is
a test with an effect estimate, a 95 % interval, a p-value and a verdict,
and every other (parameter, covariate) pair of the campaign gets the same
treatment.

The responses are the per-test ratios of ``tests.csv`` (:data:`TEST_RESPONSES`)
and every parameter of the causes the diagnosis named for a series
(``results/diagnosis.json``, ``<cause>.<parameter>``).  Tests of a series are
repetitions of one set-up, series of a specimen share its masonry, and
specimens of a wall are that wall fractured to a lower height: every
effect is estimated at the level the covariate is a property of
(:mod:`rocklab.lab.hierarchy`), with that level's units as the
observations:

* covariates of the wall, specimen or series (:data:`SERIES_COVARIATES`:
  unit material, h/b, contact depth; and the boundary condition across
  both): one value per series (the mean of its tests, or the diagnosis'
  estimate), averaged to one value per unit of the covariate's level, then
  ordinary least squares of the unit values on the covariate with a mean
  per unit of the level above (:class:`LevelFit`): h/b is compared between
  the specimens of one wall, contact depth and the boundary condition
  between the series of one specimen, the unit material between walls;
  Student's t on units minus coefficients degrees of freedom.  This is the
  two-stage (aggregated) form of a mixed model with random effects for wall
  and series, chosen over statsmodels' MixedLM because a campaign has 3 to
  5 walls: a likelihood estimate of a between-wall variance from so few
  walls sits at its bound or fails to converge, and its Wald intervals use
  the normal quantile, narrower than the t on the walls' own degrees of
  freedom that the aggregated model gives exactly (for a balanced design
  the two coincide).  Parent means remove what differs between walls
  (material, workmanship) from a within-wall contrast at the cost of the
  parent's degrees of freedom;
* covariates of the test within its series (:data:`WITHIN_COVARIATES`: the
  direction of release, the test's place in the series): the effect within
  each series (the slope on the place, 0 first to 1 last, or the pulled
  minus the pushed mean), then their mean over walls (each the mean of its
  series') with a t interval on walls - 1 degrees of freedom;
* a claim on a boundary condition's mean: the mean over tests (a series'
  value weighing its tests) with the walls as clusters, the estimate and
  interval of Table 3 (:func:`rocklab.inference.intervals.clustered_mean`:
  CR2, t on Imbens-Kolesar degrees of freedom, walls - 1 for walls of equal
  tests and fewer for unequal ones), so that a statement on the mean is
  judged on the number the tables quote.

Below the units a verdict needs (two units at each level of a material,
two residual degrees of freedom, :func:`rocklab.lab.hierarchy.too_few_units`)
the row reads "not testable" with the units counted, never a verdict.

An effect is reported over the range the campaign spans: the slope times
the range of h/b or contact depth, the change from the first to the last
test of a series, the difference between two levels.  A covariate with
one level among the units that carry the response, or constant within
every unit of the level above, is "not testable", never given a verdict.

Verdicts (:func:`rocklab.dissipation.claims.verdict`) never over-claim.  A claim of no effect is
"supported" only when its whole interval lies within +-margin (an equivalence test: absence of
evidence is not evidence of absence; an effect the test detects inside the margin is negligible),
"contradicted" when the interval lies beyond the margin, or, where no margin is known, when the
effect differs from zero, else "inconclusive"; a claim "below
v" is supported when the interval lies below v, contradicted when it lies
at or above; a claim "close to v" is supported when the interval lies
within v +- margin, contradicted when it lies outside.  The margin follows
one rule (:func:`rocklab.dissipation.claims.margin_of`): the smallest change of the catalogue
parameter the response is that changes the simulated free-rocking duration of the reference wall of
the row's boundary condition by 5 % (:func:`rocklab.dissipation.claims.outcome_margin`); two claims
on one mean further apart than twice it (close to 1, on average 0.93) cannot both be supported.  The paper's statements
(:data:`rocklab.dissipation.claims.PAPER_CLAIMS`, data: ``rocklab/data/paper_claims.csv``) are one
family and every other effect (an exploratory "no effect" check) another;
each family is corrected for its own multiplicity: p-values Holm-adjusted,
and a claim supported or contradicted by its interval only on the
simultaneous (Bonferroni) interval at 1 - 0.05/m (``verdict_level``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
from scipy import stats

from rocklab.dissipation.claims import PAPER_CLAIMS, Claim, claim_text, margin_of, verdict
from rocklab.dissipation.regression import ols
from rocklab.inference.intervals import clustered_mean, mean_over_units, t_interval
from rocklab.inference.multiplicity import holm
from rocklab.inference.verdicts import ClaimVerdict
from rocklab.lab.campaign import order_in_series
from rocklab.lab.hierarchy import COVARIATE_LEVEL, UNIT_COLUMN, parent, plural, too_few_units
from rocklab.physics.boundary import Boundary

if TYPE_CHECKING:
    from rocklab.diagnosis.result import CampaignDiagnosis

#: Per-test quantities of tests.csv modelled against the covariates.
TEST_RESPONSES = ("e_ratio", "theta0_over_alpha")
#: Covariates constant within a series (columns of tests.csv), in the order they enter the model.
SERIES_COVARIATES = ("h_over_b", "unit", "contact_depth_mm")
#: Covariates that vary between the tests of a series: ``order`` is the test's
#: place in its series, 0 (first) to 1 (last) (:func:`rocklab.lab.campaign.order_in_series`).
WITHIN_COVARIATES = ("direction", "order")
#: Covariates taken as numbers (a slope); the others are levels.
NUMERIC = ("h_over_b", "contact_depth_mm", "order")
#: Fewest tests of a series for its own within-series effect (a slope needs three).
MIN_WITHIN_TESTS = 3
#: Significance level of the tests; the intervals are at 1 - ALPHA.
ALPHA = 0.05


# --- the tables -------------------------------------------------------------------------------


def with_test_order(tests: pd.DataFrame, qc: pd.DataFrame | None = None) -> pd.DataFrame:
    """tests.csv with the test's place in its series (``order``, 0 first to 1 last).

    Parameters
    ----------
    tests : pandas.DataFrame
        results/tests.csv.
    qc : pandas.DataFrame, optional
        results/qc.csv: when given, the place counts every test performed in
        the series, the rejected ones too (they wore the hinge as well).

    Returns
    -------
    pandas.DataFrame
        ``tests`` with an ``order`` column.
    """
    every = qc if qc is not None else tests
    order: dict[str, float] = {}
    for _, ids in every.groupby("series").test_id:
        order |= order_in_series(ids.astype(str).tolist())
    return tests.assign(order=tests.test_id.astype(str).map(order))


def with_walls(tests: pd.DataFrame, walls: Mapping[str, str] | None = None) -> pd.DataFrame:
    """tests.csv with the wall of each test's specimen (``wall``).

    Parameters
    ----------
    tests : pandas.DataFrame
    walls : mapping, optional
        Specimen -> wall (the ``wall`` column of the campaign's specimens.csv);
        None: ``tests`` has its ``wall`` column already.

    Raises
    ------
    ValueError
        No wall given for some specimen: without it the unit of a wall's
        property is unknown, and no verdict on it can be given.
    """
    if walls is None:
        if "wall" not in tests:
            raise ValueError("the tests name no wall: give each specimen's wall (specimens.csv)")
        return tests
    missing = sorted(set(tests.specimen) - set(walls))
    if missing:
        raise ValueError(f"no wall for specimen(s) {', '.join(map(str, missing))}")
    return tests.assign(wall=tests.specimen.map(walls).astype(str))


def series_values(tests: pd.DataFrame, diagnosis: CampaignDiagnosis | None = None) -> pd.DataFrame:
    """One value per series and response: the mean of its tests, or the diagnosis' estimate.

    Parameters
    ----------
    tests : pandas.DataFrame
        results/tests.csv (series, boundary, specimen, wall and the covariates).
    diagnosis : rocklab.diagnosis.result.CampaignDiagnosis, optional
        results/diagnosis.json; its series entries give
        ``<cause>.<parameter>`` for the causes named in each series.

    Returns
    -------
    pandas.DataFrame
        series, boundary, specimen, wall, :data:`SERIES_COVARIATES`, n_tests,
        source ('tests' or 'diagnosis'), response, value.
    """
    meta = tests.groupby("series").agg(
        boundary=("boundary", "first"),
        specimen=("specimen", "first"),
        wall=("wall", "first"),
        n_tests=("test_id", "size"),
        **{c: (c, "first") for c in SERIES_COVARIATES if c in tests},
    )
    rows = [
        {"series": s, "source": "tests", "response": r, "value": v}
        for r in TEST_RESPONSES
        if r in tests
        for s, v in tests.groupby("series")[r].mean().items()
    ]
    for e in diagnosis.series if diagnosis is not None else ():
        if e.key not in meta.index:
            continue
        for f in e.findings:
            for name, v in f.params.items():
                rows.append({"series": e.key, "source": "diagnosis", "response": f"{f.effect}.{name}", "value": v})
    values = pd.DataFrame(rows, columns=["series", "source", "response", "value"]).dropna(subset=["value"])
    return meta.reset_index().merge(values, on="series")


# --- the models -------------------------------------------------------------------------------


def _level_text(v: object) -> str:
    return f"{v:g}" if isinstance(v, (int, float, np.integer, np.floating)) else str(v)


def unit_values(frame: pd.DataFrame, covariate: str) -> pd.DataFrame:
    """The series values of ``frame`` as one value per unit of the covariate's level.

    A unit's value is the mean of its series' values; its covariate, its
    parent (the unit of the level above) and its unit material are those of
    its series (constant within it, :mod:`rocklab.lab.hierarchy`).

    Returns
    -------
    pandas.DataFrame
        unit_id, parent, unit (the material), ``covariate``, value, n_series,
        n_tests; one row per unit.

    Raises
    ------
    ValueError
        The covariate takes two values within one unit of its level.
    """
    level = COVARIATE_LEVEL[covariate]
    col, up = UNIT_COLUMN[level], parent(level)
    d = frame.assign(_parent=frame[UNIT_COLUMN[up]] if up in UNIT_COLUMN else "campaign")
    if (d.groupby(col)[covariate].nunique(dropna=False) > 1).any():
        raise ValueError(f"{covariate} varies within a {level}: it is no property of the {level}")
    aggs = {
        "parent": ("_parent", "first"),
        "unit": ("unit", "first"),
        covariate: (covariate, "first"),
        "value": ("value", "mean"),
        "n_series": ("series", "size"),
        "n_tests": ("n_tests", "sum"),
    }
    return d.groupby(col, sort=True).agg(**aggs).rename_axis("unit_id").reset_index()


@dataclass
class LevelFit:
    """The effect of one covariate at its level: unit values ~ covariate + a mean per parent unit, OLS.

    Each unit of the covariate's level (:data:`rocklab.lab.hierarchy.COVARIATE_LEVEL`)
    is one observation (the mean of its series); where that level sits in
    a parent with several units (specimens in walls, series in specimens),
    each parent gets its own mean, so that the effect is the contrast
    within parents (two heights of one wall, three contact depths of one
    specimen) and a parent's own departure is never taken for the effect.
    Units alone in their parent carry no such contrast and are left out.

    Attributes
    ----------
    frame : pandas.DataFrame
        The units' rows of :func:`unit_values`.
    covariate, level : str
    X : array
        Parent means (or the intercept) first, then the covariate's columns.
    columns : dict
        Term label ("per unit", "tuff - clay brick") -> column of X.
    coef, cov : array
    df : int
    """

    frame: pd.DataFrame
    covariate: str
    level: str
    X: np.ndarray
    columns: dict[str, int]
    coef: np.ndarray
    cov: np.ndarray
    df: int

    def partial(self, n: int = 50) -> dict[str, np.ndarray]:
        """The effect of a numeric covariate with the parents' means averaged out (a partial plot).

        Returns
        -------
        dict
            x, y (each unit's value less its parent's departure from the
            mean of the parents), grid, line, low, high (the fitted line
            and its 95 % confidence band on the grid).
        """
        j = self.columns["per unit"]
        xbar = self.X.mean(axis=0)
        others = np.ones(self.X.shape[1], bool)
        others[j] = False
        y = self.frame.value.to_numpy(float) - (self.X[:, others] - xbar[others]) @ self.coef[others]
        grid = np.linspace(self.X[:, j].min(), self.X[:, j].max(), n)
        G = np.tile(xbar, (n, 1))
        G[:, j] = grid
        line = G @ self.coef
        se = np.sqrt(np.einsum("ij,jk,ik->i", G, self.cov, G))
        q = stats.t.ppf(1 - ALPHA / 2, self.df)
        return {"x": self.X[:, j], "y": y, "grid": grid, "line": line, "low": line - q * se, "high": line + q * se}


def fit_level(frame: pd.DataFrame, covariate: str) -> tuple[LevelFit | None, str, pd.DataFrame]:
    """:class:`LevelFit` of one covariate on the series values ``frame``, or why it cannot be tested.

    Returns
    -------
    fit : LevelFit or None
    reason : str
        "" when fitted, else why it is not testable (one level, constant within
        every parent, too few units: :func:`rocklab.lab.hierarchy.too_few_units`).
    units : pandas.DataFrame
        The units the fit rests on (:func:`unit_values`).
    """
    level = COVARIATE_LEVEL[covariate]
    if covariate not in frame or frame[covariate].isna().any():
        return None, "not known for every series", frame.iloc[:0]
    units = unit_values(frame, covariate)
    if parent(level) in UNIT_COLUMN:
        units = units[units.groupby("parent").unit_id.transform("size") > 1].reset_index(drop=True)
        if units.empty:
            return None, f"no {parent(level)} holds two {level}s with a value", units
    levels = sorted(units[covariate].unique())
    if len(levels) < 2:
        only = f" ({_level_text(levels[0])})" if levels else ""
        return None, f"only one level{only} among {plural(level, len(units))}", units
    parents = sorted(units.parent.unique())
    base = np.column_stack([(units.parent == p).to_numpy(float) for p in parents])
    if covariate in NUMERIC:
        new = {"per unit": units[covariate].to_numpy(float)}
        per_level = None
    else:
        ref = levels[0]
        new = {f"{_level_text(v)} - {_level_text(ref)}": (units[covariate] == v).to_numpy(float) for v in levels[1:]}
        per_level = {_level_text(v): int((units[covariate] == v).sum()) for v in levels}
    X = np.column_stack([base, *new.values()])
    if np.linalg.matrix_rank(X) < X.shape[1]:
        return None, f"constant within every {parent(level)} of {plural(level, len(units))}", units
    df = len(units) - X.shape[1]
    reason = too_few_units(level, len(units), df, per_level)
    if reason:
        return None, reason, units
    coef, cov, df = ols(units.value.to_numpy(float), X)
    columns = {label: base.shape[1] + i for i, label in enumerate(new)}
    return LevelFit(units, covariate, level, X, columns, coef, cov, df), "", units


def _not_testable(reason: str) -> dict[str, Any]:
    """The fields of a row that gets no verdict, and why."""
    return {"model": "", "verdict": ClaimVerdict.NOT_TESTABLE, "why_not_testable": reason}


def _row(boundary: str, response: str, source: str, covariate: str, **kw: Any) -> dict[str, Any]:
    return {"boundary": boundary, "response": response, "source": source, "covariate": covariate, **kw}


def covariate_rows(
    frame: pd.DataFrame, boundary: str, response: str, source: str, covariate: str
) -> list[dict[str, Any]]:
    """The effect of one series covariate on one response at its level (:func:`fit_level`), one row per term."""
    fit, reason, units = fit_level(frame, covariate)
    level = COVARIATE_LEVEL[covariate]
    common = dict(
        n_series=int(units.n_series.sum()) if len(units) else len(frame),
        n_tests=int(units.n_tests.sum()) if len(units) else int(frame.n_tests.sum()),
        unit_level=level,
        n_units=len(units),
    )
    if fit is None:
        return [_row(boundary, response, source, covariate, **_not_testable(reason), **common)]
    up = parent(level)
    within = f" + a mean per {up}" if up in UNIT_COLUMN else ""
    model = f"{level} means ~ {covariate}{within}, OLS ({plural(level, len(units))})"
    rows = []
    for term, j in fit.columns.items():
        est, se = fit.coef[j], math.sqrt(fit.cov[j, j])
        lo, hi, p = t_interval(est, se, fit.df)
        span, scale = (np.nan, np.nan), 1.0
        if covariate in NUMERIC:
            span = (units[covariate].min(), units[covariate].max())
            scale = span[1] - span[0]
            term = f"over {covariate} {span[0]:.3g}-{span[1]:.3g}"
        rows.append(
            _row(
                boundary, response, source, covariate,
                term=term, model=model, estimate=est * scale, se=se * scale, ci_low=lo * scale, ci_high=hi * scale,
                slope=est if covariate in NUMERIC else np.nan, p=p, df=fit.df, span_low=span[0], span_high=span[1],
                **common,
            )
        )  # fmt: skip
    return rows


def within_series_effects(tests: pd.DataFrame, response: str, covariate: str) -> pd.Series:
    """The effect of a within-series covariate in each series that varies in it.

    ``order``: the OLS slope of the response on the test's place (0 to 1),
    in series with at least :data:`MIN_WITHIN_TESTS` tests; ``direction``:
    the pulled minus the pushed mean, in series with two tests each way.

    Returns
    -------
    pandas.Series
        Effect by series.
    """
    out: dict[Any, float] = {}
    for s, g in tests.dropna(subset=[response, covariate]).groupby("series"):
        if covariate == "direction":
            push, pull = g[g.direction == "push"][response], g[g.direction == "pull"][response]
            if len(push) >= 2 and len(pull) >= 2:
                out[s] = pull.mean() - push.mean()
        elif len(g) >= MIN_WITHIN_TESTS and np.ptp(g[covariate].to_numpy(float)) > 0:
            out[s] = stats.linregress(g[covariate].to_numpy(float), g[response].to_numpy(float)).slope
    return pd.Series(out, dtype=float)


def wall_mean_row(values: pd.Series, walls: pd.Series, **row: Any) -> dict[str, Any]:
    """The mean over walls of ``values`` (one per series: each wall the mean of its series) with a t
    interval on walls - 1 df, as a row; "not testable" below the units a verdict needs."""
    null = row.pop("null", 0.0)
    m, se, k, reason = mean_over_units(values, walls, "wall")
    row |= dict(unit_level="wall", n_units=k)
    if reason:
        return row | _not_testable(reason)
    lo, hi, p = t_interval(m, se, k - 1, null=null)
    return row | dict(estimate=m, se=se, ci_low=lo, ci_high=hi, p=p, df=k - 1)


def within_series_row(tests: pd.DataFrame, boundary: str, response: str, covariate: str) -> dict[str, Any]:
    """The campaign-wide within-series effect: the mean over walls of the series' effects (t, walls - 1 df)."""
    effects = within_series_effects(tests, response, covariate)
    used = tests[tests.series.isin(effects.index)]
    term = "pull - push" if covariate == "direction" else "last - first test of a series"
    common = dict(term=term, n_series=len(effects), n_tests=len(used))
    if len(effects) < 2:
        levels = sorted(tests[covariate].dropna().unique())
        if covariate == "direction" and len(levels) < 2:
            why = f"only one level ({levels[0]})" if levels else "no values"
        else:
            why = f"varies within {len(effects)} series (2 needed)"
        return _row(boundary, response, "tests", covariate, **_not_testable(why), unit_level="wall",
                    n_units=used.wall.nunique(), **common)  # fmt: skip
    wall = used.groupby("series").wall.first().reindex(effects.index)
    model = "within-series effect per series, mean over walls of their series' (t)"
    return wall_mean_row(effects, wall, **_row(boundary, response, "tests", covariate, model=model, **common))


def mean_row(frame: pd.DataFrame, boundary: str, response: str, source: str, value: float) -> dict[str, Any]:
    """The mean over tests (each series' value weighing its tests) with its cluster-robust t interval, the
    walls as clusters, and the p-value of mean = value: the estimate and interval of Table 3
    (:func:`rocklab.inference.intervals.clustered_mean`, CR2 on Imbens-Kolesar df), one estimate of
    a statement on the mean wherever it is quoted."""
    n = frame.n_tests.to_numpy(int)
    m, se, df, k, reason = clustered_mean(np.repeat(frame.value.to_numpy(float), n), np.repeat(frame.wall, n), "wall")
    row = _row(boundary, response, source, "mean", n_series=len(frame), n_tests=int(n.sum()), term="mean over tests",
               unit_level="wall", n_units=k)  # fmt: skip
    if reason:
        return row | _not_testable(reason)
    lo, hi, p = t_interval(m, se, df, null=value)
    model = "mean over tests, walls as clusters (CR2, Imbens-Kolesar df, t)"
    return row | dict(model=model, estimate=m, se=se, ci_low=lo, ci_high=hi, p=p, df=df)


# --- verdicts ---------------------------------------------------------------------------------


def _judge(rows: list[dict[str, Any]], claims: Sequence[Claim]) -> pd.DataFrame:
    """Verdicts of every row, each family (the paper's statements; the exploratory "no effect" checks)
    corrected for its own multiplicity: p Holm-adjusted, and a claim supported only by its simultaneous
    (Bonferroni) interval at 1 - ALPHA/m, m the family's judged rows."""
    by_key = {c.key: c for c in claims}
    by_effect = {(c.boundary, c.response, c.covariate): c.key for c in claims if c.covariate != "mean"}
    for r in rows:
        r.setdefault("statement", by_effect.get((r["boundary"], r["response"], r["covariate"]), ""))
    table = pd.DataFrame(rows)
    for c in ("term", "model", "verdict", "why_not_testable"):
        table[c] = table[c].fillna("") if c in table else ""
    for c in ("estimate", "se", "ci_low", "ci_high", "slope", "p", "df", "span_low", "span_high"):
        table[c] = table[c].astype(float) if c in table else np.nan
    table["p_holm"] = np.nan
    table["verdict_level"] = np.nan
    for family in (table.statement != "", table.statement == ""):
        judged = table.index[family & np.isfinite(table.p)]
        table.loc[judged, "p_holm"] = holm(table.loc[judged, "p"].to_numpy())
        table.loc[judged, "verdict_level"] = 1 - ALPHA / max(len(judged), 1)
    claimed, margins, words, papers, verdicts = [], [], [], [], []
    for r in table.itertuples():
        claim = by_key.get(r.statement)
        kind, value = (claim.kind, claim.value) if claim else ("zero", 0.0)
        margin = margin_of(r.response, r.boundary)
        claimed.append(value if kind != "zero" else np.nan)
        margins.append(margin)
        papers.append(claim.paper if claim else "")
        words.append(claim_text(kind, value, margin))
        if r.verdict:
            verdicts.append(r.verdict)
            continue
        low, high, _ = t_interval(r.estimate, r.se, r.df, level=r.verdict_level)
        verdicts.append(verdict(kind, low, high, r.p_holm, value, margin))
    return table.assign(claimed_value=claimed, margin=margins, claim=words, paper=papers, verdict=verdicts)


#: Columns of campaign_effects.csv, in order (workflow/schemas/campaign_effects.schema.yaml).
COLUMNS = (
    "statement", "boundary", "response", "source", "covariate", "term", "claim", "verdict", "why_not_testable",
    "estimate", "ci_low", "ci_high", "p", "p_holm", "df", "unit_level", "n_units", "n_series", "n_tests",
    "slope", "span_low", "span_high", "claimed_value", "margin", "verdict_level", "model", "paper",
)  # fmt: skip


def _covariates(boundary: str) -> list[str]:
    return [c for c in SERIES_COVARIATES if c != "contact_depth_mm" or boundary == Boundary.ONE_SIDED]


def campaign_effects(
    tests: pd.DataFrame,
    diagnosis: CampaignDiagnosis | None = None,
    qc: pd.DataFrame | None = None,
    walls: Mapping[str, str] | None = None,
    claims: Sequence[Claim] = PAPER_CLAIMS,
) -> pd.DataFrame:
    """Every parameter of the campaign against every covariate, and the paper's statements judged.

    Parameters
    ----------
    tests : pandas.DataFrame
        results/tests.csv.
    diagnosis : rocklab.diagnosis.result.CampaignDiagnosis, optional
        results/diagnosis.json (its series entries).
    qc : pandas.DataFrame, optional
        results/qc.csv, for the test's place among all the tests of its series.
    walls : mapping, optional
        Specimen -> wall (the campaign's specimens.csv); without it ``tests``
        must have a ``wall`` column (:func:`with_walls`).
    claims : sequence of Claim
        The statements to test with the paper's words; every other effect is
        checked against "no effect".

    Returns
    -------
    pandas.DataFrame
        campaign_effects.csv (:data:`COLUMNS`): one row per (boundary,
        response, covariate term) and per claim on a mean; statements first.
    """
    tests = with_walls(with_test_order(tests, qc), walls)
    values = series_values(tests, diagnosis)
    rows = []
    for (boundary, response), frame in values.groupby(["boundary", "response"], sort=True):
        source = frame.source.iloc[0]
        for c in _covariates(boundary):
            rows += covariate_rows(frame, boundary, response, source, c)
        if source == "tests":
            sub = tests[tests.boundary == boundary]
            rows += [within_series_row(sub, boundary, response, c) for c in WITHIN_COVARIATES]
        rows += [
            mean_row(frame, boundary, response, source, c.value) | {"statement": c.key}
            for c in claims
            if c.covariate == "mean" and (c.boundary, c.response) == (boundary, response)
        ]
    # the boundary condition: both of a specimen's boundary conditions compared within the specimen
    for response, frame in values.groupby("response", sort=True):
        if frame.boundary.nunique() == 2:
            rows += covariate_rows(frame, "both", response, frame.source.iloc[0], "boundary")
    if not rows:
        # no valid test: the table has its columns and no row
        return pd.DataFrame(columns=list(COLUMNS))
    table = _judge(rows, claims)
    # the paper's statements first, in the paper's order, then the rest
    rank = {c.key: i for i, c in enumerate(claims)}
    table["rank"] = table.statement.map(rank).fillna(len(rank))
    table = table.sort_values(["rank", "boundary", "response", "covariate"], kind="stable")
    return table[list(COLUMNS)].reset_index(drop=True)


def series_fits(
    tests: pd.DataFrame,
    diagnosis: CampaignDiagnosis | None = None,
    qc: pd.DataFrame | None = None,
    walls: Mapping[str, str] | None = None,
) -> dict[tuple[str, str], dict[str, LevelFit]]:
    """The fits of the numeric covariates at their level, for the figures.

    Returns
    -------
    dict
        (boundary, response) -> {covariate: :class:`LevelFit`}, the
        covariates that could be fitted only.
    """
    values = series_values(with_walls(with_test_order(tests, qc), walls), diagnosis)
    out: dict[tuple[str, str], dict[str, LevelFit]] = {}
    for (boundary, response), frame in values.groupby(["boundary", "response"], sort=True):
        fits = {c: fit_level(frame, c)[0] for c in _covariates(boundary) if c in NUMERIC}
        out[(boundary, response)] = {c: f for c, f in fits.items() if f is not None}
    return out
