"""Residual structure that a fitted model leaves: bias and trends, tested across tests."""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping
from typing import Any

import numpy as np

from rocklab._imports import lazy_module
from rocklab.diagnosis.estimation.problem import Problem
from rocklab.diagnosis.result import Structure

stats = lazy_module("scipy.stats")

#: Residual structure smaller than this [log units over the range] is not reported.
STRUCTURE_MIN = 0.01

#: Significance of residual structure (cluster-robust t-test over tests).
STRUCTURE_P = 1e-3


def structure(
    problem: Problem[Any], idx: np.ndarray, ext: Collection[str], values: Mapping[str, float]
) -> list[Structure]:
    """Residual structure left by a model: bias and trends of each group, across tests.

    For each group, the per-test median (bias) and the within-test slopes on
    the covariates of :meth:`Problem.covariates` (impact index, log
    amplitude), each with a cluster-robust (by test) t-test, or for a
    covariate that is a property of the test the regression of the per-test
    means on it; reported when p < :data:`STRUCTURE_P` and the effect
    over the observed range exceeds :data:`STRUCTURE_MIN` and the median
    noise covariate of the group (its resolution, :meth:`Problem.resolution`);
    and what the fit-free evidence says of the form of the causes in
    ``ext`` (:meth:`Problem.form_structure`).

    Returns
    -------
    list of Structure
    """
    sub = problem.subset(idx)
    R = problem.residuals(sub, ext, values)
    X = problem.noise(sub)
    cov = problem.covariates(sub)
    found = []
    for g, r in R.items():
        ok = np.isfinite(r)
        tests_with = np.flatnonzero(ok.sum(axis=1) >= 1)
        if tests_with.size < 3 or ok.sum() < 6:
            continue
        # structure below the group's typical resolution is no structure worth a cause
        size = max(STRUCTURE_MIN, problem.resolution(X[g][ok]))
        # per-test medians: one wild impact must not make a bias
        means = np.array([np.median(r[i][ok[i]]) for i in tests_with])
        t = stats.ttest_1samp(means, 0.0)
        if np.isfinite(t.pvalue) and t.pvalue < STRUCTURE_P and abs(means.mean()) > size:
            found.append(Structure(g, f"{g}: bias {means.mean():+.3f} (p = {t.pvalue:.1g})"))
        for label, x in cov.get(g, {}).items():
            x = np.broadcast_to(x, r.shape)
            xo = np.where(ok, x, np.nan)[tests_with]
            if np.all(np.nanmax(xo, axis=1) == np.nanmin(xo, axis=1)):
                # a property of the test (a slenderness): its per-test medians against it
                xm = np.array([x[i][ok[i]][0] for i in tests_with])
                fit = stats.linregress(xm, means) if np.ptp(xm) > 0 else None
                slope, p_val = (fit.slope, fit.pvalue) if fit is not None else (0.0, np.nan)
                span = float(np.subtract(*np.percentile(xm, [90, 10])))
            else:
                slope, p_val, span = within_slope(r, x, ok)
            if np.isfinite(p_val) and p_val < STRUCTURE_P and abs(slope * span) > size:
                found.append(
                    Structure(g, f"{g}: trend with {label} {slope * span:+.3f} over the range (p = {p_val:.1g})")
                )
    return found + problem.form_structure(ext) + problem.extra_structure(sub, ext, values)


def within_slope(r: np.ndarray, x: np.ndarray, ok: np.ndarray, min_obs: int = 3) -> tuple[float, float, float]:
    """Within-test slope of r on x, its cluster-robust p-value and the 10-90 % span of x.

    The slope of the residuals on the covariate, each demeaned within its
    test (tests with ``min_obs`` observations or more, at least three such tests), with the cluster-robust
    (by test) standard error and its small-sample correction CR1,
    se^2 = G / (G - 1) (N - 1) / (N - K) sum_g (x_g . u_g)^2 / (sum x^2)^2
    with G tests, N observations and K = 1 slope (statsmodels' cluster
    covariance with ``use_correction=True``): without it the errors are
    sqrt((G - 1) / G) too small, 9 % with six tests.  The p-value is
    two-sided, Student's t with G - 1 degrees of freedom.

    Returns
    -------
    slope, p_value, span : float
    """
    ok = ok & np.isfinite(x)
    rows = [i for i in range(r.shape[0]) if ok[i].sum() >= min_obs]
    if len(rows) < 3:
        return 0.0, np.nan, 0.0
    xs = [x[i][ok[i]] - x[i][ok[i]].mean() for i in rows]
    rs = [r[i][ok[i]] - r[i][ok[i]].mean() for i in rows]
    sxx = sum(float(a @ a) for a in xs)
    if sxx <= 0:
        return 0.0, np.nan, 0.0
    beta = sum(float(a @ b) for a, b in zip(xs, rs)) / sxx
    meat = sum(float(a @ (b - beta * a)) ** 2 for a, b in zip(xs, rs))
    n_clusters = len(rows)
    # CR1: (N - 1) / (N - K) is 1 for the one slope
    se = math.sqrt(n_clusters / (n_clusters - 1) * meat) / sxx
    allx = np.concatenate([x[i][ok[i]] for i in rows])
    span = float(np.subtract(*np.percentile(allx, [90, 10])))
    if se == 0:
        return beta, 0.0 if beta else 1.0, span
    return beta, float(2 * stats.t.sf(abs(beta / se), n_clusters - 1)), span
