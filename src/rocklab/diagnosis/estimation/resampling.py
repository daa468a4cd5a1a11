"""Tests left out and tests resampled: held-out deviance and parameter intervals.

Both refit by one Gauss-Newton step from the fit of all tests, over the
linearisation of :func:`rocklab.diagnosis.estimation.fitting.linearised`: the
K folds of :func:`heldout` and the resamples of whole tests of
:func:`parameter_intervals`, which falls back on the cluster-robust t
interval of the same linearisation (:func:`sandwich_intervals`) where the
tests are too few to resample or the resamples collapse on a bound, and
adds the systematic part that no resample of tests sees
(:mod:`rocklab.diagnosis.estimation.systematic`).  The
paired per-test comparison of two models' held-out deviances is
:func:`paired_gain`, and a per-test measure is summed up over the tests by
:func:`finite_mean`.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Collection, Iterable, Mapping, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from rocklab._imports import lazy_module
from rocklab.diagnosis.estimation.fitting import Fit, fit, linearised
from rocklab.diagnosis.estimation.noise import deviance, finite_residuals, group_variances, predictive_dof
from rocklab.diagnosis.estimation.problem import Problem
from rocklab.diagnosis.estimation.systematic import by_group, systematic_uncertainty, widened
from rocklab.inference.intervals import MIN_BOOTSTRAP, expanded, percentile_interval

optimize = lazy_module("scipy.optimize")
stats = lazy_module("scipy.stats")

#: A bootstrap interval narrower than this share of the sandwich interval (:func:`sandwich_intervals`) has
#: resamples collapsed on a bound or on a kink of the fit, not a precision the tests carry: the sandwich
#: interval stands instead.  Over tests that vary freely the two, both on Student's t of the tests less
#: one, differ by the noise of 40 resamples' extreme percentiles, some 20 %.
COLLAPSED_BOOTSTRAP = 0.5

log = logging.getLogger(__name__)


class Intervals(dict[str, list[float]]):
    """Parameter -> its 95 % interval, with ``u_sys``: parameter -> the systematic standard uncertainty
    the interval holds [its unit] (:mod:`rocklab.diagnosis.estimation.systematic`), ``dof_sys`` its
    degrees of freedom, ``statistical`` the statistical interval it widens, on ``df`` degrees of freedom
    (the tests less one).

    The systematic part is what every test of a series shares, and what the series of one lab measured
    with one chain and one model share too: a mean over series averages their statistical parts away
    but not this one (:func:`rocklab.diagnosis.pooling.pooled_parameter`).
    """

    def __init__(
        self,
        ci: Mapping[str, list[float]] | Iterable[tuple[str, list[float]]] = (),
        u_sys: Mapping[str, float] | None = None,
        dof_sys: Mapping[str, float] | None = None,
        statistical: Mapping[str, list[float]] | None = None,
        df: float = np.inf,
    ) -> None:
        super().__init__(ci)
        self.u_sys: dict[str, float] = dict(u_sys or {})
        self.dof_sys: dict[str, float] = dict(dof_sys or {})
        self.statistical: dict[str, list[float]] = dict(statistical or {})
        self.df = df


def finite_mean(x: npt.ArrayLike) -> float | None:
    """Mean of the finite values of x, None if there are none."""
    x = np.asarray(x, float)
    return float(np.nanmean(x)) if np.isfinite(x).any() else None


def heldout_means(ho: Mapping[str, np.ndarray]) -> dict[str, float | None]:
    """The held-out errors of :func:`heldout` as a finding or an entry quotes them: the mean held-out
    deviance per observation (``deviance_per_obs``), then the mean of each engineering measure."""
    return {
        "deviance_per_obs": finite_mean(ho["deviance"]),
        **{k: finite_mean(v) for k, v in ho.items() if k != "deviance"},
    }


def heldout_gain(
    before: Mapping[str, np.ndarray], after: Mapping[str, np.ndarray], paired: float
) -> dict[str, float | None]:
    """What a model gains on another, held out: the mean error of each engineering measure before
    (:func:`heldout` of the other model) minus after, and ``deviance_per_obs``, the ``paired`` gain
    of the held-out deviance per observation (:func:`paired_gain`)."""
    out: dict[str, float | None] = {}
    for k in before:
        b, a = finite_mean(before[k]), finite_mean(after[k])
        if k != "deviance":
            out[k] = None if b is None or a is None else b - a
    return out | {"deviance_per_obs": paired}


def _folds(n: int, k_max: int = 5) -> list[np.ndarray]:
    k = n if n <= 6 else k_max
    idx = np.arange(n)
    return [idx[idx % k == j] for j in range(k)] if n > 1 else [idx]


def heldout(problem: Problem[Any], ext: Collection[str], fitted: Fit | None = None) -> dict[str, np.ndarray]:
    """Per-test held-out deviance of ``ext`` fitted on the other tests (K-fold), and measures.

    The fit of each fold's training tests is one Gauss-Newton step from the
    fit of all tests (``fitted``; made here when None), over the training
    tests' weighted residuals and derivatives at it
    (:func:`~rocklab.diagnosis.estimation.fitting.linearised`, the
    linearisation of the bootstrap, :func:`parameter_intervals`); its noise
    model (:func:`~rocklab.diagnosis.estimation.noise.noise_variance`) is
    then that of the training tests' residuals at the step's parameters, and
    the held-out residuals are scored by the Student-t it predicts on their
    number (:func:`~rocklab.diagnosis.estimation.noise.predictive_dof`): the
    few residuals of a short series' training tests fix their variance
    loosely, and the normal law would take that variance as known.
    A fold leaves out a fifth of the tests (one, up to six): its fit
    differs from the full one by about its standard errors, where the
    residuals are linear in the parameters, so the step lands on the refit
    of the fold's tests (the engine's former held-out fits, at ten times the
    cost: tests/test_diagnosis_engine.py).

    Returns
    -------
    dict
        ``deviance`` (per test, -2 log L per observation of the held-out test
        under the training fit) and the per-test arrays of
        :meth:`Problem.heldout_measures`.
    """
    n = problem.n_tests
    every = problem.subset(np.arange(n))
    X = problem.noise(every)
    if problem.params(ext):
        fitted = fitted or fit(problem, np.arange(n), ext)
        names, x0, lo, hi, A, y = linearised(problem, every, fitted)
    dev = np.full(n, np.nan)
    meas: dict[str, np.ndarray] = {}
    for held in _folds(n):
        train = np.setdiff1d(np.arange(n), held) if n > 1 else held
        values = {}
        if problem.params(ext):
            step = optimize.lsq_linear(
                np.concatenate([A[i] for i in train]), np.concatenate([y[i] for i in train]), bounds=(lo, hi)
            )
            values = dict(zip(names, map(float, x0 + step.x)))
        R = problem.residuals(every, ext, values)
        Rt, Xt = {g: r[train] for g, r in R.items()}, {g: x[train] for g, x in X.items()}
        var = group_variances(Rt, Xt)
        dof = predictive_dof(Rt, Xt, var)
        for i in held:
            Ri = {g: r[i : i + 1] for g, r in R.items() if g in var}
            Xi = {g: X[g][i : i + 1] for g in Ri}
            nobs = sum(r.size for r, _ in finite_residuals(Ri, Xi).values())
            dev[i] = deviance(Ri, Xi, var, dof) / nobs if nobs else np.nan
        for name, x in problem.heldout_measures(problem.subset(held), ext, values).items():
            meas.setdefault(name, np.full(n, np.nan))[held] = x
    return {"deviance": dev, **meas}


def sandwich_errors(A: Sequence[np.ndarray], y: Sequence[np.ndarray]) -> np.ndarray:
    """Cluster-robust (by test) standard errors of the parameters of a linearised fit
    (:func:`sandwich_intervals`); inf for a direction the tests do not fix."""
    G = len(A)
    full = np.concatenate(A)
    N, K = full.shape
    B = full.T @ full
    dx = np.linalg.lstsq(full, np.concatenate(y), rcond=None)[0]
    scores = np.array([a.T @ (b - a @ dx) for a, b in zip(A, y)])
    Binv = np.linalg.pinv(B)
    cov = G / max(G - 1, 1) * (N - 1) / max(N - K, 1) * Binv @ (scores.T @ scores) @ Binv
    se = np.sqrt(np.maximum(np.diag(cov), 0.0))
    # a direction B does not see is not fixed by the tests: its whole range
    seen = np.diag(B) > 0
    seen &= np.abs(np.diag(Binv @ B)) > 0.5
    return np.where(seen & np.isfinite(se), se, np.inf)


def sandwich_intervals(
    names: Sequence[str],
    x0: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    A: Sequence[np.ndarray],
    y: Sequence[np.ndarray],
    level: float = 0.95,
) -> dict[str, list[float]]:
    """Cluster-robust (by test) t intervals of the parameters from the linearisation of a fit.

    The least-squares problem of the fit, linearised test by test (``A``,
    ``y`` of :func:`~rocklab.diagnosis.estimation.fitting.linearised`), is
    solved without its bounds; its covariance is the sandwich
    B^-1 M B^-1 with B = sum A_i^T A_i and M the sum over tests of the
    outer products of their scores A_i^T u_i at that solution, with the
    small-sample correction CR1, G / (G - 1) (N - 1) / (N - K), of G tests,
    N observations and K parameters (statsmodels' cluster covariance with
    ``use_correction=True``).  The interval is x0 +- t se with Student's t on
    G - 1 degrees of freedom (the tests are the units that vary: 4.30 for
    three tests), cut at the parameter's bounds: at a bound it is one-sided,
    from the bound, and always holds the estimate x0.  A direction the tests
    do not fix (B singular) gives the parameter its whole range.

    Returns
    -------
    dict
        name -> [low, high].
    """
    t = float(stats.t.ppf(0.5 + level / 2, max(len(A) - 1, 1)))
    half = t * sandwich_errors(A, y)
    return {
        k: [float(max(x0[i] + lo[i], x0[i] - half[i])), float(min(x0[i] + hi[i], x0[i] + half[i]))]
        for i, k in enumerate(names)
    }


def parameter_intervals(problem: Problem[Any], fitted: Fit, n_boot: int = 40, seed: int = 0) -> Intervals:
    """95 % intervals of the parameters: whole tests resampled (bootstrap over tests), or the sandwich.

    Each resample is fitted by one Gauss-Newton step from the full fit
    (the estimating-function bootstrap of Hu & Kalbfleisch 2000, within the
    bounds): the residuals of every test and their derivatives are computed
    once, at the full fit, with the weights of its noise model
    (:func:`~rocklab.diagnosis.estimation.fitting.linearised`), and a
    resample weighs each test by the times it was drawn; the interval is the
    2.5-97.5 % percentiles of the resamples at the position that gives them
    their nominal content
    (:func:`~rocklab.inference.intervals.percentile_interval`: numpy's
    default holds 90 % of 40 resamples), each side's distance from the
    estimate expanded for the few tests resampled
    (:func:`~rocklab.inference.intervals.expanded`: Student's t on the
    tests less one, not the normal quantiles of the plain percentiles).  The resamples
    differ from the full fit by a few times its standard errors, where the
    residuals are linear in the parameters to well below those errors (the refit of every resample with its own noise
    model, the engine's former bootstrap, gives the same intervals to a few
    per cent of their width at twenty times the cost:
    tests/test_diagnosis_engine.py).

    The cluster-robust t interval of the same linearisation
    (:func:`sandwich_intervals`) stands instead where the percentiles say
    nothing: with fewer than :data:`~rocklab.inference.intervals.MIN_BOOTSTRAP`
    tests (three tests give ten distinct resamples), for a parameter fitted
    on a bound (the bootstrap is inconsistent there, Andrews 2000: the
    resamples pile on the bound, and from a few tests their percentiles
    reach less far than the spread of the tests carries), and for a
    parameter whose percentile interval misses its estimate or is narrower
    than :data:`COLLAPSED_BOOTSTRAP` times the sandwich's, the resamples
    collapsed on a bound (a loss in flight fitted at zero: every resample
    steps onto the bound the full fit stopped short of).

    Either is then widened by the systematic standard uncertainty of the
    parameter, the pulls of the residual groups on it in quadrature,
    rescaled for their few groups and on their effective degrees of freedom
    (:func:`~rocklab.diagnosis.estimation.systematic.systematic_uncertainty`):
    each side's half-width h, on the tests less one, becomes
    t(nu_eff) sqrt((h / t)^2 + u_sys^2) on the Welch-Satterthwaite degrees of
    freedom, within the bounds, and the interval always holds its estimate
    (:func:`~rocklab.diagnosis.estimation.systematic.widened`).

    Returns
    -------
    Intervals
        Parameter -> [lower, upper], with the systematic standard uncertainties in ``u_sys``.
    """
    t0 = time.perf_counter()
    rng = np.random.default_rng(seed)
    if not fitted.values:
        return Intervals()
    names, x0, lo, hi, A, y, groups = by_group(problem, fitted)
    sandwich = sandwich_intervals(names, x0, lo, hi, A, y)
    if problem.n_tests < MIN_BOOTSTRAP:
        log.info(
            "sandwich intervals of %s on %d tests (t on %d degrees of freedom): %s",
            "+".join(fitted.ext),
            problem.n_tests,
            problem.n_tests - 1,
            ", ".join(f"{k} [{a:.4g}, {b:.4g}]" for k, (a, b) in sandwich.items()),
        )
        return _with_systematic(problem, fitted, sandwich, groups)
    draws = []
    for _ in range(n_boot):
        counts = np.bincount(rng.integers(0, problem.n_tests, problem.n_tests), minlength=problem.n_tests)
        drawn = np.flatnonzero(counts)
        root = np.sqrt(counts[drawn])
        Ab = np.concatenate([A[i] * c for i, c in zip(drawn, root)])
        yb = np.concatenate([y[i] * c for i, c in zip(drawn, root)])
        draws.append(x0 + optimize.lsq_linear(Ab, yb, bounds=(lo, hi)).x)
    d = np.array(draws).reshape(len(draws), len(names))
    ci = {}
    for i, k in enumerate(names):
        p_lo, p_hi = expanded(percentile_interval(d[:, i]), x0[i], problem.n_tests)
        b = [max(x0[i] + lo[i], p_lo), min(x0[i] + hi[i], p_hi)]
        s = sandwich[k]
        # a margin of rounding: a fit at its bound and percentiles a step of lsq_linear's tolerance inside it
        tol = 1e-9 * (hi[i] - lo[i])
        outside = x0[i] < b[0] - tol or x0[i] > b[1] + tol
        # the bootstrap of an estimate on a bound is inconsistent (Andrews 2000): resamples pile on the bound
        at_bound = lo[i] >= -tol or hi[i] <= tol
        narrow = b[1] - b[0] < COLLAPSED_BOOTSTRAP * (s[1] - s[0])
        why = "its estimate outside" if outside else "fitted on a bound" if at_bound else "narrow" if narrow else ""
        if why:
            log.info("bootstrap of %s [%.4g, %.4g] of %.4g, %s: the sandwich interval", k, *b, x0[i], why)
        ci[k] = s if why else b
    log.info(
        "bootstrap of %s: %d resamples of %d tests in %.1f s: %s",
        "+".join(fitted.ext),
        n_boot,
        problem.n_tests,
        time.perf_counter() - t0,
        ", ".join(f"{k} [{lo:.4g}, {hi:.4g}]" for k, (lo, hi) in ci.items()),
    )
    return _with_systematic(problem, fitted, ci, groups)


def _with_systematic(
    problem: Problem[Any],
    fitted: Fit,
    ci: Mapping[str, list[float]],
    groups: Mapping[str, tuple[np.ndarray, np.ndarray]],
) -> Intervals:
    """The statistical intervals ``ci``, on the tests less one degrees of freedom, widened by the
    systematic uncertainty of each parameter on its own, within its bounds
    (:func:`~rocklab.diagnosis.estimation.systematic.widened`), as :class:`Intervals`."""
    u_all, nu_all = systematic_uncertainty(groups)
    u, nu = dict(zip(fitted.values, map(float, u_all))), dict(zip(fitted.values, map(float, nu_all)))
    df = max(problem.n_tests - 1, 1)
    out = Intervals(
        {
            q.name: widened(ci[q.name], fitted.values[q.name], q.lower, q.upper, u[q.name], df=df, df_sys=nu[q.name])
            for q in problem.params(fitted.ext)
            if q.name in ci
        },
        {k: v for k, v in u.items() if k in ci},
        {k: v for k, v in nu.items() if k in ci},
        {k: list(v) for k, v in ci.items()},
        df,
    )
    log.info(
        "intervals of %s, statistical and systematic: %s",
        "+".join(fitted.ext),
        ", ".join(f"{k} [{a:.4g}, {b:.4g}] u_sys {u[k]:.2g} on {nu[k]:.3g}" for k, (a, b) in ci.items()),
        extra={"effects": tuple(fitted.ext), "statistical": dict(ci), "systematic": u},
    )
    return out


def paired_difference(d: np.ndarray) -> tuple[float, float]:
    """Mean of the finite paired per-test differences ``d`` and its standard error."""
    d = d[np.isfinite(d)]
    se = float(np.std(d, ddof=1) / math.sqrt(d.size)) if d.size > 1 else np.inf
    return float(np.mean(d)) if d.size else 0.0, se


def paired_gain(before: npt.ArrayLike, after: npt.ArrayLike) -> tuple[float, float]:
    """Mean per-test held-out deviance gain of ``after`` over ``before`` and its standard error."""
    return paired_difference(np.asarray(before, float) - np.asarray(after, float))
