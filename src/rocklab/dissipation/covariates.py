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
repetitions of one set-up, not replicates of the factors that vary between
series (see :mod:`rocklab.dissipation.statistics`), hence two models:

* covariates of the series (:data:`SERIES_COVARIATES`: h/b, unit material,
  contact depth; and the boundary condition across both): one value per
  series (the mean of its tests, or the diagnosis' estimate), regressed by
  ordinary least squares on all the covariates that vary among those series,
  each effect adjusted for the others; Student's t with n_series - k degrees
  of freedom.  The series are weighted equally: the scatter between series
  (sd ~0.01-0.05 of e_exp/e_an) dwarfs the uncertainty of a series' value
  (a bootstrap interval of ~1e-4 wide), so precision weights would be equal
  weights anyway;
* covariates of the test within its series (:data:`WITHIN_COVARIATES`: the
  direction of release, the test's place in the series): the effect within
  each series (the slope on the place, 0 first to 1 last, or the pulled
  minus the pushed mean), then their mean over the series with a t interval
  on n_series - 1 degrees of freedom (a two-stage random-effects estimate:
  each series is one unit, and the between-series spread of the effect is
  its uncertainty).

An effect is reported over the range the campaign spans: the slope times
the range of h/b or contact depth, the change from the first to the last
test of a series, the difference between two levels.  A covariate with
one level among the series that carry the response, or confounded with
the others, is "not testable", never given a verdict.

Verdicts (:func:`verdict`) never over-claim.  A claim of no effect is
"contradicted" when the effect differs from zero (p < 0.05), "supported"
only when its whole 95 % interval lies within +-``margin`` of the
response's mean (an equivalence test: absence of evidence is not evidence
of absence), else "inconclusive"; a claim "below v" is supported when the
interval lies below v, contradicted when it lies at or above; a claim
"close to v" is supported when the interval lies within v +- margin v,
contradicted when it lies outside.  The paper's statements
(:data:`PAPER_CLAIMS`, data: ``rocklab/data/paper_claims.csv``) are
tested each at the 5 % level; every other
effect is an exploratory "no effect" check with Holm-adjusted p-values
over all of them, so that forty looks do not make two false findings.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from rocklab.data import data_path
from rocklab.dissipation.regression import ols
from rocklab.dissipation.statistics import holm
from rocklab.lab.campaign import order_in_series

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
#: Default relative margin of "no effect" and "close to" (:func:`verdict`).
MARGIN = 0.10


@dataclass(frozen=True)
class Claim:
    """A campaign-wide statement to test.

    Attributes
    ----------
    key : str
        Short name (a column of campaign_effects.csv).
    boundary : str
        'two-sided', 'one-sided' or 'both' (the boundary condition as a covariate).
    response : str
        A column of tests.csv or ``<cause>.<parameter>`` of the diagnosis.
    covariate : str
        One of :data:`SERIES_COVARIATES`, :data:`WITHIN_COVARIATES`,
        'boundary', or 'mean' (a claim on the response's value itself).
    kind : {'zero', 'below', 'near'}
        No effect; the mean below ``value``; the mean close to ``value``.
    value : float
    paper : str
        Where the paper says it, and how.
    """

    key: str
    boundary: str
    response: str
    covariate: str
    kind: str = "zero"
    value: float = 0.0
    paper: str = ""


#: The kinds of claim :func:`verdict` judges: no effect, the mean below a value, the mean close to it.
CLAIM_KINDS = ("zero", "below", "near")
#: The boundary conditions a claim can be on ('both': the boundary condition as a covariate).
CLAIM_BOUNDARIES = ("two-sided", "one-sided", "both")


def read_claims(path=None):
    """The campaign-wide statements in a CSV file, checked, as :class:`Claim` objects.

    Parameters
    ----------
    path : str or Path, optional
        A CSV file with the columns of :class:`Claim`, one statement a row;
        default the paper's, ``rocklab/data/paper_claims.csv``.

    Returns
    -------
    tuple of Claim
        In the order of the file (the order of campaign_effects.csv).

    Raises
    ------
    ValueError
        A missing or unknown column, a repeated key, a boundary, covariate
        or kind that the tests do not know, or a value that is no finite number.
    """
    path = data_path("paper_claims.csv") if path is None else Path(path)
    columns = [f.name for f in fields(Claim)]
    covariates = (*SERIES_COVARIATES, *WITHIN_COVARIATES, "boundary", "mean")
    with open(path, newline="", encoding="utf-8") as fh:
        reader = csv.DictReader(fh)
        if reader.fieldnames != columns:
            raise ValueError(f"{path}: columns {reader.fieldnames}, expected {columns}")
        claims = []
        for line, row in enumerate(reader, start=2):
            where = f"{path}, line {line}"
            for column, known in (("boundary", CLAIM_BOUNDARIES), ("covariate", covariates), ("kind", CLAIM_KINDS)):
                if row[column] not in known:
                    raise ValueError(f"{where}: {column} {row[column]!r}, expected one of {', '.join(known)}")
            try:
                value = float(row["value"])
            except ValueError:
                value = math.nan
            if not math.isfinite(value):
                raise ValueError(f"{where}: value {row['value']!r} is no finite number")
            if row["key"] in {c.key for c in claims}:
                raise ValueError(f"{where}: key {row['key']!r} repeated")
            claims.append(Claim(**{**row, "value": value}))
    return tuple(claims)


#: The statements of the paper (Sects. 2-4, Figs. 10 and 13, Tables 2-3) that the campaign can test.
PAPER_CLAIMS = read_claims()


# --- the tables -------------------------------------------------------------------------------


def with_test_order(tests, qc=None):
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
    order = {}
    for _, ids in every.groupby("series").test_id:
        order |= order_in_series(ids.astype(str).tolist())
    return tests.assign(order=tests.test_id.astype(str).map(order))


def series_values(tests, diagnosis=None):
    """One value per series and response: the mean of its tests, or the diagnosis' estimate.

    Parameters
    ----------
    tests : pandas.DataFrame
        results/tests.csv (series, boundary, specimen and the covariates).
    diagnosis : rocklab.diagnosis.result.CampaignDiagnosis, optional
        results/diagnosis.json; its series entries give
        ``<cause>.<parameter>`` for the causes named in each series.

    Returns
    -------
    pandas.DataFrame
        series, boundary, specimen, :data:`SERIES_COVARIATES`, n_tests,
        source ('tests' or 'diagnosis'), response, value.
    """
    meta = tests.groupby("series").agg(
        boundary=("boundary", "first"),
        specimen=("specimen", "first"),
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


def t_interval(est, se, df, level=1 - ALPHA, null=0.0):
    """Two-sided Student's t interval of ``est`` and the p-value of ``est = null``."""
    if se == 0:
        return est, est, 1.0 if est == null else 0.0
    q = stats.t.ppf(0.5 + level / 2, df)
    return est - q * se, est + q * se, float(2 * stats.t.sf(abs(est - null) / se, df))


def _level_text(v):
    return f"{v:g}" if isinstance(v, (int, float, np.integer, np.floating)) else str(v)


def _design(frame, covariates):
    """The design matrix of the covariates that can be tested on these rows.

    Returns
    -------
    X : (n, k) array
        Intercept first.
    terms : list of (covariate, column index or None, term, reason)
        One per effect: its column of X, its label ("per unit", "tuff - clay
        brick"), and for a covariate that cannot be tested the reason, with
        no column.
    """
    cols, terms = [np.ones(len(frame))], []
    for c in covariates:
        if c not in frame or frame[c].isna().any():
            terms.append((c, None, "", "not testable: not known for every series"))
            continue
        levels = sorted(frame[c].unique())
        if len(levels) < 2:
            terms.append((c, None, "", f"not testable: only one level ({_level_text(levels[0])})"))
            continue
        if c in NUMERIC:
            new = {"per unit": frame[c].to_numpy(float)}
        else:
            ref = levels[0]
            new = {f"{_level_text(lv)} - {_level_text(ref)}": (frame[c] == lv).to_numpy(float) for lv in levels[1:]}
        trial = np.column_stack([*cols, *new.values()])
        if np.linalg.matrix_rank(trial) < trial.shape[1]:
            entered = ", ".join(t[0] for t in terms if t[1] is not None) or "the intercept"
            terms.append((c, None, "", f"not testable: confounded with {entered} among these series"))
            continue
        for label, x in new.items():
            terms.append((c, len(cols), label, ""))
            cols.append(x)
    return np.column_stack(cols), terms


@dataclass
class SeriesFit:
    """A between-series model of one response: y_s = X_s beta + error, OLS.

    Attributes
    ----------
    frame : pandas.DataFrame
        The series' rows of :func:`series_values`.
    X : array
    terms : list
        See :func:`_design`.
    coef, cov : array
    df : int
    """

    frame: pd.DataFrame
    X: np.ndarray
    terms: list
    coef: np.ndarray
    cov: np.ndarray
    df: int

    def partial(self, covariate, n=50):
        """The effect of one numeric covariate with the others at their mean (a partial plot).

        Returns
        -------
        dict
            x, y (each series' value with the other covariates' effects
            removed, to the mean of the others), grid, line, low, high (the
            fitted line and its 95 % confidence band on the grid).
        """
        j = next(t[1] for t in self.terms if t[0] == covariate and t[1] is not None)
        xbar = self.X.mean(axis=0)
        others = np.ones(self.X.shape[1], bool)
        others[[0, j]] = False
        y = self.frame.value.to_numpy(float) - (self.X[:, others] - xbar[others]) @ self.coef[others]
        grid = np.linspace(self.X[:, j].min(), self.X[:, j].max(), n)
        G = np.tile(xbar, (n, 1))
        G[:, j] = grid
        line = G @ self.coef
        se = np.sqrt(np.einsum("ij,jk,ik->i", G, self.cov, G))
        q = stats.t.ppf(1 - ALPHA / 2, self.df)
        return {"x": self.X[:, j], "y": y, "grid": grid, "line": line, "low": line - q * se, "high": line + q * se}


def fit_series(frame, covariates):
    """:class:`SeriesFit` of ``frame.value`` on the testable ``covariates`` (None: too few series), and the terms."""
    X, terms = _design(frame, covariates)
    if len(frame) <= X.shape[1]:
        return None, terms
    coef, cov, df = ols(frame.value.to_numpy(float), X)
    return SeriesFit(frame.reset_index(drop=True), X, terms, coef, cov, df), terms


def _row(boundary, response, source, covariate, **kw):
    return {"boundary": boundary, "response": response, "source": source, "covariate": covariate, **kw}


def between_series_rows(frame, boundary, response, source, covariates):
    """Effects of the series covariates on one response (:func:`fit_series`), one row per term."""
    fit, terms = fit_series(frame, covariates)
    common = dict(n_series=len(frame), n_tests=int(frame.n_tests.sum()))
    rows = []
    for c, j, term, reason in terms:
        if reason or fit is None:
            k = 1 + sum(t[1] is not None for t in terms)
            why = reason or f"not testable: {len(frame)} series for {k} coefficients"
            rows.append(_row(boundary, response, source, c, model="", verdict=why, **common))
            continue
        est, se = fit.coef[j], math.sqrt(fit.cov[j, j])
        lo, hi, p = t_interval(est, se, fit.df)
        span = (np.nan, np.nan)
        scale = 1.0
        if c in NUMERIC:
            span = (frame[c].min(), frame[c].max())
            scale = span[1] - span[0]
            term = f"over {c} {span[0]:.3g}-{span[1]:.3g}"
        entered = " + ".join(dict.fromkeys(t[0] for t in terms if t[1] is not None))
        rows.append(
            _row(
                boundary, response, source, c,
                term=term, model=f"series values ~ {entered}, OLS",
                estimate=est * scale, ci_low=lo * scale, ci_high=hi * scale, slope=est if c in NUMERIC else np.nan,
                p=p, df=fit.df, span_low=span[0], span_high=span[1], **common,
            )
        )  # fmt: skip
    return rows


def within_series_effects(tests, response, covariate):
    """The effect of a within-series covariate in each series that varies in it.

    ``order``: the OLS slope of the response on the test's place (0 to 1),
    in series with at least :data:`MIN_WITHIN_TESTS` tests; ``direction``:
    the pulled minus the pushed mean, in series with two tests each way.

    Returns
    -------
    pandas.Series
        Effect by series.
    """
    out = {}
    for s, g in tests.dropna(subset=[response, covariate]).groupby("series"):
        if covariate == "direction":
            push, pull = g[g.direction == "push"][response], g[g.direction == "pull"][response]
            if len(push) >= 2 and len(pull) >= 2:
                out[s] = pull.mean() - push.mean()
        elif len(g) >= MIN_WITHIN_TESTS and np.ptp(g[covariate].to_numpy(float)) > 0:
            out[s] = stats.linregress(g[covariate].to_numpy(float), g[response].to_numpy(float)).slope
    return pd.Series(out, dtype=float)


def within_series_row(tests, boundary, response, covariate):
    """The campaign-wide within-series effect: mean over series with a t interval (df = series - 1)."""
    effects = within_series_effects(tests, response, covariate)
    k = len(effects)
    used = tests[tests.series.isin(effects.index)]
    common = dict(n_series=k, n_tests=len(used))
    term = "pull - push" if covariate == "direction" else "last - first test of a series"
    if k < 2:
        levels = sorted(tests[covariate].dropna().unique())
        if covariate == "direction" and len(levels) < 2:
            why = f"not testable: only one level ({levels[0]})" if levels else "not testable: no values"
        else:
            why = f"not testable: varies within {k} series (2 needed)"
        return _row(boundary, response, "tests", covariate, term=term, model="", verdict=why, **common)
    m, se = effects.mean(), effects.std(ddof=1) / math.sqrt(k)
    lo, hi, p = t_interval(m, se, k - 1)
    return _row(
        boundary, response, "tests", covariate,
        term=term, model="within-series effect per series, mean over series (t)",
        estimate=m, ci_low=lo, ci_high=hi, p=p, df=k - 1, **common,
    )  # fmt: skip


def mean_row(frame, boundary, response, source, value):
    """The mean of the series' values with a t interval (df = series - 1) and the p-value of mean = value."""
    y = frame.value.to_numpy(float)
    common = dict(n_series=len(y), n_tests=int(frame.n_tests.sum()), term="mean over series")
    if len(y) < 2:
        return _row(boundary, response, source, "mean", model="", verdict="not testable: one series", **common)
    m, se = y.mean(), y.std(ddof=1) / math.sqrt(len(y))
    lo, hi, p = t_interval(m, se, len(y) - 1, null=value)
    return _row(boundary, response, source, "mean", model="mean of series values (t)", estimate=m, ci_low=lo,
                ci_high=hi, p=p, df=len(y) - 1, **common)  # fmt: skip


# --- verdicts ---------------------------------------------------------------------------------


def verdict(kind, low, high, p, value=0.0, margin=0.0, alpha=ALPHA):
    """The verdict on a claim from the 95 % interval [low, high] and the p-value.

    Parameters
    ----------
    kind : {'zero', 'below', 'near'}
        No effect; the mean below ``value``; the mean within ``value`` +- ``margin``.
    margin : float
        Absolute margin: the effect (or distance from ``value``) that counts as negligible.

    Returns
    -------
    str
        'supported', 'contradicted' or 'inconclusive'.
    """
    if kind == "zero":
        if p < alpha:
            return "contradicted"
        return "supported" if -margin <= low and high <= margin else "inconclusive"
    if kind == "below":
        return "supported" if high < value else "contradicted" if low >= value else "inconclusive"
    if kind == "near":
        if value - margin <= low and high <= value + margin:
            return "supported"
        return "contradicted" if high < value - margin or low > value + margin else "inconclusive"
    raise ValueError(f"unknown kind of claim {kind!r}")


def claim_text(kind, value, margin):
    """The claim of a row in words: "no effect", "mean below 1", "mean within 10% of 1"."""
    words = {"zero": "no effect", "below": f"mean below {value:g}", "near": f"mean within {margin:.0%} of {value:g}"}
    return words[kind]


def _judge(rows, claims, means, margin):
    """Verdicts of every row: the paper's claims at ALPHA, the other "no effect" checks Holm-adjusted."""
    by_key = {c.key: c for c in claims}
    by_effect = {(c.boundary, c.response, c.covariate): c.key for c in claims if c.covariate != "mean"}
    for r in rows:
        r.setdefault("statement", by_effect.get((r["boundary"], r["response"], r["covariate"]), ""))
    table = pd.DataFrame(rows)
    for c in ("term", "model", "verdict"):
        table[c] = table[c].fillna("") if c in table else ""
    for c in ("estimate", "ci_low", "ci_high", "slope", "p", "df", "span_low", "span_high"):
        table[c] = table[c].astype(float) if c in table else np.nan
    explore = table.index[(table.statement == "") & np.isfinite(table.p)]
    table["p_holm"] = np.nan
    table.loc[explore, "p_holm"] = holm(table.loc[explore, "p"].to_numpy())
    claimed, margins, words, papers, verdicts = [], [], [], [], []
    for r in table.itertuples():
        claim = by_key.get(r.statement)
        kind, value = (claim.kind, claim.value) if claim else ("zero", 0.0)
        # "close to v": a margin of v; "no effect": a margin of the response's mean
        absolute = margin * (abs(value) if kind == "near" else abs(means.get((r.boundary, r.response), np.nan)))
        claimed.append(value if kind != "zero" else np.nan)
        margins.append(absolute)
        papers.append(claim.paper if claim else "")
        words.append(claim_text(kind, value, margin))
        p = r.p if claim else r.p_holm
        verdicts.append(r.verdict or verdict(kind, r.ci_low, r.ci_high, p, value, absolute))
    return table.assign(claimed_value=claimed, margin=margins, claim=words, paper=papers, verdict=verdicts)


#: Columns of campaign_effects.csv, in order (workflow/schemas/campaign_effects.schema.yaml).
COLUMNS = (
    "statement", "boundary", "response", "source", "covariate", "term", "claim", "verdict",
    "estimate", "ci_low", "ci_high", "p", "p_holm", "df", "n_series", "n_tests",
    "slope", "span_low", "span_high", "claimed_value", "margin", "model", "paper",
)  # fmt: skip


def campaign_effects(tests, diagnosis=None, qc=None, margin=MARGIN, claims=PAPER_CLAIMS):
    """Every parameter of the campaign against every covariate, and the paper's statements judged.

    Parameters
    ----------
    tests : pandas.DataFrame
        results/tests.csv.
    diagnosis : rocklab.diagnosis.result.CampaignDiagnosis, optional
        results/diagnosis.json (its series entries).
    qc : pandas.DataFrame, optional
        results/qc.csv, for the test's place among all the tests of its series.
    margin : float
        Relative margin of "no effect" and "close to" (:func:`verdict`).
    claims : sequence of Claim
        The statements to test with the paper's words; every other effect is
        checked against "no effect".

    Returns
    -------
    pandas.DataFrame
        campaign_effects.csv (:data:`COLUMNS`): one row per (boundary,
        response, covariate term) and per claim on a mean; statements first.
    """
    tests = with_test_order(tests, qc)
    values = series_values(tests, diagnosis)
    rows = []
    means = values.groupby(["boundary", "response"]).value.mean().to_dict()
    for (boundary, response), frame in values.groupby(["boundary", "response"], sort=True):
        source = frame.source.iloc[0]
        covariates = [c for c in SERIES_COVARIATES if c != "contact_depth_mm" or boundary == "one-sided"]
        rows += between_series_rows(frame, boundary, response, source, covariates)
        if source == "tests":
            sub = tests[tests.boundary == boundary]
            rows += [within_series_row(sub, boundary, response, c) for c in WITHIN_COVARIATES]
        rows += [
            mean_row(frame, boundary, response, source, c.value) | {"statement": c.key}
            for c in claims
            if c.covariate == "mean" and (c.boundary, c.response) == (boundary, response)
        ]
    # the boundary condition: the responses of both, one value per series, adjusted for h/b and unit
    for response, frame in values.groupby("response", sort=True):
        if frame.boundary.nunique() == 2:
            means[("both", response)] = frame.value.mean()
            covariates = ["boundary", "h_over_b", "unit"]
            fit_rows = between_series_rows(frame, "both", response, frame.source.iloc[0], covariates)
            rows += [r for r in fit_rows if r["covariate"] == "boundary"]
    if not rows:
        # no valid test: the table has its columns and no row
        return pd.DataFrame(columns=list(COLUMNS))
    table = _judge(rows, claims, means, margin)
    # the paper's statements first, in the paper's order, then the rest
    rank = {c.key: i for i, c in enumerate(claims)}
    table["rank"] = table.statement.map(rank).fillna(len(rank))
    table = table.sort_values(["rank", "boundary", "response", "covariate"], kind="stable")
    return table[list(COLUMNS)].reset_index(drop=True)


def series_fits(tests, diagnosis=None, qc=None):
    """The between-series fits of every (boundary, response) for the figures.

    Returns
    -------
    dict
        (boundary, response) -> :class:`SeriesFit` (None where too few series).
    """
    values = series_values(with_test_order(tests, qc), diagnosis)
    out = {}
    for (boundary, response), frame in values.groupby(["boundary", "response"], sort=True):
        covariates = [c for c in SERIES_COVARIATES if c != "contact_depth_mm" or boundary == "one-sided"]
        out[(boundary, response)] = fit_series(frame, covariates)[0]
    return out
