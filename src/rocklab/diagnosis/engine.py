"""Estimation engine: fits, held-out deviance, bootstrap intervals, selection.

Independent of what is fitted: a :class:`Problem` hands the engine its
tests, its residual groups (log ratios, model over measured), the noise
covariate of each residual and its candidate causes (objects with ``name``,
``params`` (:class:`rocklab.diagnosis.parameters.Param`) and ``replaces``).  The engine fits a
combination of causes by maximum likelihood with a noise model per group
(:func:`fit`), scores it on tests left out (:func:`heldout`), resamples
tests for parameter intervals (:func:`parameter_intervals`), selects causes
greedily (:func:`select_effects`) and tests what the chosen model leaves
(:func:`structure`).  The method is described in docs/diagnosis-method.md.

Progress goes to the module's logger: each candidate with its BIC, held-out
gain and the reason it is taken or turned down, each full fit (passes,
convergence), each bootstrap (resamples, time); the fits of the folds and
resamples only at DEBUG level.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass

import numba
import numpy as np

from rocklab._imports import lazy_module

optimize = lazy_module("scipy.optimize")
stats = lazy_module("scipy.stats")

log = logging.getLogger(__name__)

#: Floor of the variance of a residual group [log units^2] (noise-free data).
VAR_FLOOR = 1e-10

#: Residual structure smaller than this [log units over the range] is not reported.
STRUCTURE_MIN = 0.01

#: Significance of residual structure (cluster-robust t-test over tests).
STRUCTURE_P = 1e-3


def finite_mean(x):
    """Mean of the finite values of x, None if there are none."""
    x = np.asarray(x, float)
    return float(np.nanmean(x)) if np.isfinite(x).any() else None


class Problem:
    """A set of tests and the residual groups of models over them.

    Subclasses set ``causes`` (the candidates, in the order they are
    reported when tied, each with ``name``, ``params`` and ``replaces``) and
    define :meth:`residuals` (group -> (tests, k) arrays for a subset made by
    :meth:`subset`), :meth:`noise`, :meth:`starts` (data-driven starting
    values) and, optionally, :meth:`heldout_measures` and :meth:`covariates`.
    """

    n_tests: int
    causes: tuple = ()

    def subset(self, idx):
        raise NotImplementedError

    def residuals(self, sub, ext, values):
        raise NotImplementedError

    def candidates(self, families=False):
        """Names of the candidate causes (the listed ones; with ``families``, the generalised families too)."""
        return [c.name for c in self.causes if families or not getattr(c, "family", None)]

    def starts(self, ext):
        return {}

    def heldout_measures(self, sub, ext, values):
        return {}

    def covariates(self, sub):
        """Group -> {label: array like its residuals} for the structure tests."""
        return {}

    def noise(self, sub):
        """Noise covariate (threshold over amplitude) of every residual of :meth:`residuals`."""
        raise NotImplementedError

    def extra_structure(self, sub, ext, values):
        """Structure outside the residual groups (list of statements)."""
        return []

    def form_structure(self, ext):
        """Fit-free evidence that a cause of ``ext`` has the wrong form (list of statements)."""
        return []

    def resolution(self, x):
        """Typical resolution [log units] of a group from its noise covariates ``x``."""
        return float(np.median(x))

    def params(self, ext):
        """The :class:`~rocklab.diagnosis.parameters.Param` of the causes ``ext`` this problem can see, in order."""
        return [q for c in self.causes if c.name in ext for q in c.params]

    def combine(self, current, eff):
        """The causes ``current`` plus ``eff`` in catalogue order, less those ``eff``
        replaces; None where a cause of ``current`` replaces ``eff``."""
        by_name = {c.name: c for c in self.causes}
        if any(eff in by_name[c].replaces for c in current):
            return None
        new = (set(current) | {eff}) - set(by_name[eff].replaces)
        return tuple(c.name for c in self.causes if c.name in new)


@numba.njit(cache=True)
def _profile(t, r2, x2):
    """-2 log L (constants dropped) of :func:`noise_variance`'s model at log rho = t, s0^2 profiled out."""
    n = r2.size
    mean, logs = 0.0, 0.0
    for i in range(n):
        d = 1.0 + math.exp(t) * x2[i]
        mean += r2[i] / d
        logs += math.log(d)
    return n * math.log(mean / n) + logs


@numba.njit(cache=True)
def _profile_minimum(r2, x2, lo, hi, xatol):
    """Minimum (t, value) of :func:`_profile` over lo <= t <= hi: Brent's bounded search.

    The algorithm of :func:`scipy.optimize.minimize_scalar` (``method="bounded"``,
    500 evaluations at most) step for step, compiled: the noise model is
    fitted at every reweighting pass of every fit, where scipy's calls of a
    numpy profile cost a fifth of the diagnosis.
    """
    sqrt_eps = math.sqrt(2.2e-16)
    golden_mean = 0.5 * (3.0 - math.sqrt(5.0))
    a, b = lo, hi
    fulc = a + golden_mean * (b - a)
    nfc, xf = fulc, fulc
    rat = e = 0.0
    fx = _profile(xf, r2, x2)
    num = 1
    ffulc = fnfc = fx
    xm = 0.5 * (a + b)
    tol1 = sqrt_eps * abs(xf) + xatol / 3.0
    tol2 = 2.0 * tol1
    while abs(xf - xm) > tol2 - 0.5 * (b - a):
        golden = True
        # a parabola through the three best points, where acceptable
        if abs(e) > tol1:
            golden = False
            r = (xf - nfc) * (fx - ffulc)
            q = (xf - fulc) * (fx - fnfc)
            p = (xf - fulc) * q - (xf - nfc) * r
            q = 2.0 * (q - r)
            if q > 0.0:
                p = -p
            q = abs(q)
            r = e
            e = rat
            if abs(p) < abs(0.5 * q * r) and p > q * (a - xf) and p < q * (b - xf):
                rat = (p + 0.0) / q
                x = xf + rat
                if (x - a) < tol2 or (b - x) < tol2:
                    rat = tol1 * (np.sign(xm - xf) + ((xm - xf) == 0))
            else:
                golden = True
        if golden:
            e = a - xf if xf >= xm else b - xf
            rat = golden_mean * e
        x = xf + (np.sign(rat) + (rat == 0)) * max(abs(rat), tol1)
        fu = _profile(x, r2, x2)
        num += 1
        if fu <= fx:
            if x >= xf:
                a = xf
            else:
                b = xf
            fulc, ffulc = nfc, fnfc
            nfc, fnfc = xf, fx
            xf, fx = x, fu
        else:
            if x < xf:
                a = x
            else:
                b = x
            if fu <= fnfc or nfc == xf:
                fulc, ffulc = nfc, fnfc
                nfc, fnfc = x, fu
            elif fu <= ffulc or fulc == xf or fulc == nfc:
                fulc, ffulc = x, fu
        xm = 0.5 * (a + b)
        tol1 = sqrt_eps * abs(xf) + xatol / 3.0
        tol2 = 2.0 * tol1
        if num >= 500:
            break
    return xf, fx


def noise_variance(r, x):
    """Maximum-likelihood noise model v = s0^2 + s1^2 x^2 of residuals r [log units^2].

    ``x`` is the observation's noise threshold over its amplitude: records
    are precise to a fixed rotation, so the log residuals of small flights
    are noisier in proportion.  For a ratio rho = s1^2 / s0^2 the best s0^2
    is mean(r^2 / (1 + rho x^2)); the profile likelihood is then minimised
    over log rho (Brent's bounded search to 1e-3, :func:`_profile_minimum`),
    the ends rho = 0 and s0 = 0 included.
    Returns (s0^2, s1^2).
    """
    r2, x2 = r**2 + VAR_FLOOR, x**2
    n = r.size
    hom = (float(np.mean(r2)), 0.0)
    if n < 4 or np.ptp(x2) <= 1e-12 * max(float(np.max(x2)), 1e-300):
        return hom
    x2 = np.maximum(x2, 1e-300)
    lo, hi = -math.log(float(np.max(x2))) - 12.0, -math.log(float(np.min(x2))) + 12.0
    t, fun = _profile_minimum(np.ascontiguousarray(r2, float), np.ascontiguousarray(x2, float), lo, hi, 1e-3)
    ends = {"hom": n * math.log(hom[0]), "prop": n * math.log(float(np.mean(r2 / x2))) + float(np.sum(np.log(x2)))}
    best = min(ends, key=ends.get)
    if fun <= ends[best]:
        rho = math.exp(t)
        s0 = float(np.mean(r2 / (1.0 + rho * x2)))
        return (s0, rho * s0)
    return hom if best == "hom" else (1e-300, float(np.mean(r2 / x2)))


def _obs(R, X):
    """Finite residuals and their noise covariates, per group."""
    out = {}
    for g, r in R.items():
        ok = np.isfinite(r) & np.isfinite(X[g])
        out[g] = (r[ok], X[g][ok])
    return out


def _variances(R, X):
    return {g: noise_variance(r, x) for g, (r, x) in _obs(R, X).items() if r.size >= 2}


def _deviance(R, X, var):
    """-2 log L (constants dropped) of residuals R under the group noise models ``var``."""
    out = 0.0
    for g, (r, x) in _obs(R, X).items():
        if g in var and r.size:
            v = var[g][0] + var[g][1] * x**2 + VAR_FLOOR
            out += float(np.sum(r**2 / v + np.log(v)))
    return out


@dataclass
class Fit:
    """A fitted model: parameter values, group noise models, -2 log L, observations,
    and the reweighting passes of its best start and whether they converged."""

    ext: tuple
    values: dict
    var: dict
    m2ll: float
    n_obs: int
    passes: int = 0
    converged: bool = True

    @property
    def bic(self):
        return self.m2ll + len(self.values) * math.log(max(self.n_obs, 2))


def fit(problem: Problem, idx, ext, x0=None, n_irls=None) -> Fit:
    """Maximum-likelihood fit of ``ext`` on the tests ``idx``, noise model per group.

    Iteratively reweighted least squares: with the weights of the noise
    model (:func:`noise_variance`) of the previous pass, a bounded
    least-squares fit, then the noise model again; its fixed point is the
    maximum of the likelihood.  The first pass searches; the weights of the
    next ones move the optimum by little, and each is one Gauss-Newton step
    with the derivatives at the first pass's optimum, reweighted.  Non-convex parameters start both at their
    null and at the value the data suggest (:meth:`Problem.starts`); the
    better end wins.  ``x0`` (a previous fit) gives a single warm start, and
    two passes (``n_irls``, default 5 cold, 2 warm) then suffice.
    """
    sub = problem.subset(idx)
    X = problem.noise(sub)
    plist = problem.params(ext)
    if not plist:
        R = problem.residuals(sub, ext, {})
        var = _variances(R, X)
        return Fit(tuple(ext), {}, var, _deviance(R, X, var), sum(r.size for r, _ in _obs(R, X).values()))
    names = [q.name for q in plist]
    lo = np.array([q.lower for q in plist], float)
    hi = np.array([q.upper for q in plist], float)
    nulls = np.array([q.null for q in plist], float)
    inside = lambda x: np.clip(x, lo + 1e-6 * (hi - lo), hi - 1e-6 * (hi - lo))  # noqa: E731
    n_irls = n_irls or (2 if x0 is not None else 5)
    if x0 is not None:
        starts = [inside(np.array([x0[n] for n in names], float))]
    else:
        guess = problem.starts(ext)
        starts = [inside(nulls)]
        if any(n in guess for n in names):
            starts.append(inside(np.array([guess.get(n, nu) for n, nu in zip(names, nulls)], float)))
    R0 = problem.residuals(sub, ext, dict(zip(names, starts[0])))
    masks = {g: np.isfinite(r) & np.isfinite(X[g]) for g, r in R0.items()}
    masks = {g: m for g, m in masks.items() if m.sum() >= 2}
    xm = {g: X[g][m] for g, m in masks.items()}
    best = None
    for x in starts:
        R = problem.residuals(sub, ext, dict(zip(names, x)))
        var = _variances({g: R[g] for g in masks}, X)
        passes, converged, jac, m2 = 0, False, None, np.inf
        for _ in range(n_irls):
            passes += 1
            w = {g: 1.0 / np.sqrt(var[g][0] + var[g][1] * xm[g] ** 2 + VAR_FLOOR) for g in masks}

            def stacked(R, w=w):
                return np.concatenate(
                    [np.nan_to_num(R[g][m], nan=1.0, posinf=1.0, neginf=-1.0) * w[g] for g, m in masks.items()]
                )

            def res(xx):
                return stacked(problem.residuals(sub, ext, dict(zip(names, xx))))

            wv = np.concatenate([w[g] for g in masks])
            if jac is None:
                sol = optimize.least_squares(
                    res, x, bounds=(lo, hi), x_scale="jac", diff_step=1e-5, xtol=1e-9, ftol=1e-9
                )
                step, jac = sol.x - x, sol.jac / wv[:, None]
            else:
                # the weights moved the optimum by little: one Gauss-Newton step from the last pass's
                # optimum, with its derivatives (at that point) reweighted, instead of a new search
                step = optimize.lsq_linear(jac * wv[:, None], -stacked(R), bounds=(lo - x, hi - x)).x
            moved = np.max(np.abs(step) / (hi - lo))
            x_new = np.clip(x + step, lo, hi)
            R_new = problem.residuals(sub, ext, dict(zip(names, x_new)))
            var_new = _variances({g: np.where(m, R_new[g], np.nan) for g, m in masks.items()}, X)
            m2_new = _deviance({g: np.where(m, R_new[g], np.nan) for g, m in masks.items()}, X, var_new)
            if m2_new > m2 + 1e-6 * abs(m2):
                # a step along a direction the data barely fix (causes nearly confounded, as the members
                # of a family) can overshoot: the likelihood, not the step, has the last word
                converged = True
                break
            x, R, var, m2 = x_new, R_new, var_new, m2_new
            if moved < 1e-6:
                converged = True
                break
        R = {g: np.where(m, R[g], np.nan) for g, m in masks.items()}
        m2ll = _deviance(R, X, var)
        if best is None or m2ll < best.m2ll:
            n_obs = int(sum(m.sum() for m in masks.values()))
            best = Fit(tuple(ext), dict(zip(names, map(float, x))), var, m2ll, n_obs, passes, converged)
    log.debug("fit %s on %d tests: %s, %d passes", ext, len(idx), best.values, best.passes)
    return best


def _folds(n, k_max=5):
    k = n if n <= 6 else k_max
    idx = np.arange(n)
    return [idx[idx % k == j] for j in range(k)] if n > 1 else [idx]


def heldout(problem: Problem, ext, fitted: Fit | None = None):
    """Per-test held-out deviance of ``ext`` fitted on the other tests (K-fold), and measures.

    The fit of each fold's training tests is one Gauss-Newton step from the
    fit of all tests (``fitted``; made here when None), over the training
    tests' weighted residuals and derivatives at it (:func:`_linearised`,
    the linearisation of the bootstrap, :func:`parameter_intervals`); its
    noise model (:func:`noise_variance`) is then that of the training
    tests' residuals at the step's parameters.  A fold leaves out a fifth
    of the tests (one, up to six): its fit differs from the full one by
    about its standard errors, where the residuals are linear in the
    parameters, so the step lands on the refit of the fold's tests (the
    engine's former held-out fits, at ten times the cost:
    tests/test_diagnosis_engine.py).

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
        names, x0, lo, hi, A, y = _linearised(problem, every, fitted)
    dev = np.full(n, np.nan)
    meas = {}
    for held in _folds(n):
        train = np.setdiff1d(np.arange(n), held) if n > 1 else held
        values = {}
        if problem.params(ext):
            step = optimize.lsq_linear(
                np.concatenate([A[i] for i in train]), np.concatenate([y[i] for i in train]), bounds=(lo, hi)
            )
            values = dict(zip(names, map(float, x0 + step.x)))
        R = problem.residuals(every, ext, values)
        var = _variances({g: r[train] for g, r in R.items()}, {g: x[train] for g, x in X.items()})
        for i in held:
            Ri = {g: r[i : i + 1] for g, r in R.items() if g in var}
            Xi = {g: X[g][i : i + 1] for g in Ri}
            nobs = sum(r.size for r, _ in _obs(Ri, Xi).values())
            dev[i] = _deviance(Ri, Xi, var) / nobs if nobs else np.nan
        for name, x in problem.heldout_measures(problem.subset(held), ext, values).items():
            meas.setdefault(name, np.full(n, np.nan))[held] = x
    return {"deviance": dev, **meas}


def _jacobian(problem: Problem, sub, ext, values):
    """Residuals at ``values`` and their derivatives by each parameter (forward differences).

    Returns (R, J): group -> residual array, group -> list of derivative
    arrays (one per parameter of ``ext``, like the residuals).
    """
    R = problem.residuals(sub, ext, values)
    J = {g: [] for g in R}
    for q in problem.params(ext):
        # the step least_squares takes (diff_step 1e-5, relative), away from the nearer bound
        h = 1e-5 * max(abs(values[q.name]), 1.0)
        h = -h if values[q.name] + h > q.upper else h
        Rq = problem.residuals(sub, ext, {**values, q.name: values[q.name] + h})
        for g in R:
            J[g].append((Rq[g] - R[g]) / h)
    return R, J


def _linearised(problem: Problem, sub, fitted: Fit):
    """The least-squares problem of ``fitted`` linearised at its parameters, test by test.

    Returns
    -------
    names : list of str
    x0, lo, hi : ndarray
        The fitted parameters, and their bounds less x0.
    A, y : list of ndarray
        Per test of ``sub``: the derivatives of its finite residuals (every
        group), weighted by the fit's noise model, and minus those residuals
        weighted alike: the step of a set of tests is the least-squares
        solution of their stacked A dx = y.
    """
    names = list(fitted.values)
    X = problem.noise(sub)
    R, J = _jacobian(problem, sub, fitted.ext, fitted.values)
    x0 = np.array([fitted.values[k] for k in names], float)
    plist = problem.params(fitted.ext)
    lo = np.array([q.lower for q in plist], float) - x0
    hi = np.array([q.upper for q in plist], float) - x0
    tests = range(len(next(iter(R.values()))))
    A, y = [[] for _ in tests], [[] for _ in tests]
    for g, r in R.items():
        if g not in fitted.var:
            continue
        d = np.stack(J[g], axis=-1)
        ok = np.isfinite(r) & np.isfinite(X[g]) & np.all(np.isfinite(d), axis=-1)
        w = 1.0 / np.sqrt(fitted.var[g][0] + fitted.var[g][1] * np.where(ok, X[g], 0.0) ** 2 + VAR_FLOOR)
        for i in tests:
            A[i].append(d[i][ok[i]] * w[i][ok[i], None])
            y[i].append(-r[i][ok[i]] * w[i][ok[i]])
    return names, x0, lo, hi, [np.concatenate(a) for a in A], [np.concatenate(b) for b in y]


def parameter_intervals(problem: Problem, fitted: Fit, n_boot=40, seed=0):
    """Percentile 95 % intervals of the parameters, whole tests resampled (bootstrap over tests).

    Each resample is fitted by one Gauss-Newton step from the full fit
    (the estimating-function bootstrap of Hu & Kalbfleisch 2000, within the
    bounds): the residuals of every test and their derivatives are computed
    once, at the full fit, with the weights of its noise model
    (:func:`_linearised`), and a resample weighs each test by the times it
    was drawn.  The resamples differ from the full fit by a few times its
    standard errors, where the residuals are linear in the parameters to
    well below those errors (the refit of every resample with its own noise
    model, the engine's former bootstrap, gives the same intervals to a few
    per cent of their width at twenty times the cost:
    tests/test_diagnosis_engine.py).
    """
    t0 = time.perf_counter()
    rng = np.random.default_rng(seed)
    if not fitted.values:
        return {}
    names, x0, lo, hi, A, y = _linearised(problem, problem.subset(np.arange(problem.n_tests)), fitted)
    draws = []
    for _ in range(n_boot):
        counts = np.bincount(rng.integers(0, problem.n_tests, problem.n_tests), minlength=problem.n_tests)
        drawn = np.flatnonzero(counts)
        root = np.sqrt(counts[drawn])
        Ab = np.concatenate([A[i] * c for i, c in zip(drawn, root)])
        yb = np.concatenate([y[i] * c for i, c in zip(drawn, root)])
        draws.append(x0 + optimize.lsq_linear(Ab, yb, bounds=(lo, hi)).x)
    d = np.array(draws).reshape(len(draws), len(names))
    ci = {k: [float(np.percentile(d[:, i], 2.5)), float(np.percentile(d[:, i], 97.5))] for i, k in enumerate(names)}
    log.info(
        "bootstrap of %s: %d resamples of %d tests in %.1f s: %s",
        "+".join(fitted.ext),
        n_boot,
        problem.n_tests,
        time.perf_counter() - t0,
        ", ".join(f"{k} [{lo:.4g}, {hi:.4g}]" for k, (lo, hi) in ci.items()),
    )
    return ci


def _paired(d):
    d = d[np.isfinite(d)]
    se = float(np.std(d, ddof=1) / math.sqrt(d.size)) if d.size > 1 else np.inf
    return float(np.mean(d)) if d.size else 0.0, se


def paired_gain(before, after):
    """Mean per-test held-out deviance gain of ``after`` over ``before`` and its standard error."""
    return _paired(np.asarray(before, float) - np.asarray(after, float))


def _improves(d):
    """Whether paired per-test improvements ``d`` are beyond the noise.

    The mean exceeds twice its standard error, or every one of at least five
    tests improved (one-sided sign test, p <= 1/32): with few tests that
    differ in how much they gain, the standard error alone is too strict.
    """
    d = d[np.isfinite(d)]
    gain, se = _paired(d)
    return gain > 2 * se or (d.size >= 5 and bool(np.all(d > 0)))


def _null_excluded(problem, effect, ci):
    """Whether some parameter of ``effect`` stays clear of its null by a practical margin."""
    for q in problem.params((effect,)):
        if q.practical is not None and q.name in ci:
            lo, hi = ci[q.name]
            if lo > q.null + q.practical or hi < q.null - q.practical:
                return True
    return False


def structure(problem: Problem, idx, ext, values):
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
    list of str
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
            found.append(f"{g}: bias {means.mean():+.3f} (p = {t.pvalue:.1g})")
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
                found.append(f"{g}: trend with {label} {slope * span:+.3f} over the range (p = {p_val:.1g})")
    return found + problem.form_structure(ext) + problem.extra_structure(sub, ext, values)


def within_slope(r, x, ok):
    """Within-test slope of r on x, its cluster-robust p-value and the 10-90 % span of x.

    The slope of the residuals on the covariate, each demeaned within its
    test (tests with three observations or more), with the cluster-robust
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
    rows = [i for i in range(r.shape[0]) if ok[i].sum() >= 3]
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


def select_effects(
    problem: Problem, *, signature=None, n_boot=40, max_effects=4, seed=0, bic_margin=10.0, families=False, fits=None
):
    """Greedy forward selection of the causes the data carry, with removal tests.

    Parameters
    ----------
    problem : Problem
    signature : dict, optional
        effect -> {"supports": bool, ...}; an effect whose signature does not
        support it is never named.
    n_boot : int
        Bootstrap resamples for the 95 % intervals.
    bic_margin : float
        BIC must drop by more than this (strong evidence, Kass & Raftery 1995).
    families : bool
        Candidates include the generalised families of the problem's causes
        (those with a ``family``): the search beyond the catalogue.
    fits : dict, optional
        Fits by causes, shared with an earlier selection on the same problem.

    Returns
    -------
    dict
        ``effects`` (chosen, in order of entry), ``fit`` (:class:`Fit`),
        ``ci`` (parameter intervals), ``base``/``final`` held-out results,
        ``steps`` (the held-out result after each entry), ``rejected``
        (effect -> reason), ``structure`` (what the chosen model leaves) and
        ``weak`` (candidates turned down that would remove all of it).
    """
    all_idx = np.arange(problem.n_tests)
    signature = signature or {}
    fits = {} if fits is None else fits

    def fit_of(ext):
        # a fit is deterministic: the rounds, the removals and the weak-evidence
        # pass meet the same models again
        if ext not in fits:
            t0 = time.perf_counter()
            f = fits[ext] = fit(problem, all_idx, ext)
            log.info(
                "fit %s: %s; -2 log L %.1f, BIC %.1f on %d observations; %d passes, %s in %.1f s",
                "+".join(ext) or "base model",
                ", ".join(f"{k} = {v:.4g}" for k, v in f.values.items()) or "no parameter",
                f.m2ll,
                f.bic,
                f.n_obs,
                f.passes,
                "converged" if f.converged else "not converged",
                time.perf_counter() - t0,
            )
        return fits[ext]

    candidates = problem.candidates(families)
    log.info("selection over %d tests, candidates %s", problem.n_tests, ", ".join(candidates))
    current = ()
    cur_fit = fit_of(current)
    cur_ho = heldout(problem, current)
    base_ho = cur_ho
    steps, rejected, ci = {}, {}, {}
    for stage in range(1, max_effects + 1):
        # candidates in the order of their information criterion; the held-out test and the
        # bootstrap, the costly steps, only until one passes
        cands = []
        for eff in candidates:
            ext = problem.combine(current, eff) if eff not in current else None
            if ext is None or ext == current or rejected.get(eff, "").startswith("95%"):
                continue
            if not signature.get(eff, {}).get("supports", True):
                # never named without it: its fit, the costliest of all for a loss in flight, is not needed
                rejected[eff] = "its signature in the data is absent"
                log.info("stage %d: %s rejected: %s", stage, eff, rejected[eff])
                continue
            f = fit_of(ext)
            dbic = f.bic - cur_fit.bic
            if dbic > -bic_margin:
                rejected[eff] = f"BIC {dbic:+.1f}"
            else:
                cands.append((dbic, eff, ext, f))
                continue
            log.info("stage %d: %s rejected: %s", stage, eff, rejected[eff])
        cands.sort(key=lambda c: c[0])
        if cands:
            log.info(
                "stage %d: held-out test in the order of BIC until one passes: %s",
                stage,
                ", ".join(f"{eff} ({dbic:+.1f})" for dbic, eff, *_ in cands),
            )
        accepted = False
        for dbic, eff, ext, f in cands:
            ho = heldout(problem, ext, f)
            d = cur_ho["deviance"] - ho["deviance"]
            gain, se = _paired(d)
            if not _improves(d):
                rejected[eff] = f"held-out deviance gain {gain:.3g} within the noise (standard error {se:.2g})"
                log.info("stage %d: %s (BIC %+.1f) rejected: %s", stage, eff, dbic, rejected[eff])
                continue
            c = parameter_intervals(problem, f, n_boot=n_boot, seed=seed)
            if not _null_excluded(problem, eff, c):
                rejected[eff] = "95% interval within the smallest effect worth naming of its null value"
                log.info(
                    "stage %d: %s (BIC %+.1f, held-out gain %.3g) rejected: %s", stage, eff, dbic, gain, rejected[eff]
                )
                continue
            rejected.pop(eff, None)
            current, cur_fit, cur_ho, ci = ext, f, ho, c
            steps[eff] = {"heldout": ho, "gain": gain, "se": se, "dbic": dbic}
            log.info(
                "stage %d: %s accepted: BIC %+.1f, held-out deviance gain %.3g (standard error %.2g)",
                stage,
                eff,
                dbic,
                gain,
                se,
            )
            accepted = True
            break
        if not accepted:
            log.info(
                "stage %d: no candidate accepted; selection stops at %s", stage, "+".join(current) or "the base model"
            )
            break
        # removal: a cause that entered earlier may be carried by the new one
        for old in [e for e in current if e != eff and e in steps]:
            ext = tuple(e for e in current if e != old)
            f = fit_of(ext)
            ho = heldout(problem, ext, f)
            loss, se = _paired(ho["deviance"] - cur_ho["deviance"])
            if not _improves(ho["deviance"] - cur_ho["deviance"]) or f.bic - cur_fit.bic < bic_margin:
                rejected[old] = f"carried by {eff} (removing it costs {loss:.3g} +- {se:.2g} held out)"
                log.info("stage %d: %s removed: %s", stage, old, rejected[old])
                steps.pop(old)
                current, cur_fit, cur_ho = ext, f, ho
                ci = parameter_intervals(problem, f, n_boot=n_boot, seed=seed) if ext else {}
    found = structure(problem, all_idx, current, cur_fit.values)
    # structure that a candidate turned down by the held-out test or the bootstrap would remove
    # is weak evidence for it, not something outside the catalogue
    weak = {}
    if found:
        for eff in candidates:
            ext = problem.combine(current, eff) if eff not in current else None
            if ext is not None and ext != current and signature.get(eff, {}).get("supports", True):
                f = fit_of(ext)
                if not structure(problem, all_idx, ext, f.values):
                    weak[eff] = {"params": f.values, "reason": rejected.get(eff, "")}
    log.info(
        "chosen: %s; structure left: %s; weak evidence for: %s",
        "+".join(current) or "the base model",
        "; ".join(found) or "none",
        ", ".join(weak) or "none",
    )
    return {
        "effects": list(current),
        "fit": cur_fit,
        "ci": ci,
        "base": base_ho,
        "final": cur_ho,
        "steps": steps,
        "rejected": rejected,
        "structure": found,
        "weak": weak,
    }


def beyond_the_catalogue(problem: Problem, sel, *, signature, n_boot=40, seed=0, fits=None):
    """The selection with the generalised families, where the listed causes leave structure (issue 12).

    Where ``sel`` (a selection of the listed causes,
    :func:`select_effects`) leaves structure in the residual groups (not
    only what the stage after selection addresses, :meth:`Problem.extra_structure`)
    that no candidate turned down by the held-out test or the bootstrap would remove (one turned
    down by the information criterion removes it only with a worse fit), the selection is run again with the
    families of the problem's causes among the candidates (the same engine:
    information criterion, signature, held-out deviance, bootstrap).  When
    it names a family, it replaces ``sel``, with ``catalogue`` (the
    selection of the listed causes) kept beside it; otherwise ``sel`` stands,
    with the families that would remove the structure but fall short of the
    evidence to be named added to its weak evidence.
    """
    # weak evidence for a listed cause that the held-out test or the bootstrap turned down stands; one the
    # information criterion turned down removes the structure only with a worse fit: a form it lacks
    if any(not w["reason"].startswith("BIC") for w in sel["weak"].values()):
        return sel
    if problem.candidates(True) == problem.candidates():
        return sel
    # structure of the residual groups: what the stage after selection addresses (a stop) is not the families'
    every = problem.subset(np.arange(problem.n_tests))
    after = problem.extra_structure(every, tuple(sel["effects"]), sel["fit"].values)
    if not [st for st in sel["structure"] if st not in after]:
        return sel
    log.info("structure left by the listed causes: the generalised families are searched")
    wide = select_effects(problem, signature=signature, n_boot=n_boot, seed=seed, families=True, fits=fits)
    families = set(problem.candidates(True)) - set(problem.candidates())
    named = [e for e in wide["effects"] if e in families]
    if not named:
        weak = {k: v for k, v in wide["weak"].items() if k in families}
        log.info(
            "no family named: %s",
            f"weak evidence for {', '.join(weak)}" if weak else "the structure stays unexplained",
        )
        return {**sel, "weak": {**sel["weak"], **weak}}
    log.info("discovered: %s", ", ".join(named))
    return {**wide, "catalogue": sel}


def family_against_listed(problem: Problem, family, sel, *, n_boot=40, seed=0, fits=None):
    """A family fitted whether named or not, against the base model and the best listed cause.

    The fit of ``family`` on all tests, its bootstrap intervals, the closed
    form it reduces to, and its paired held-out deviance gain per
    observation over the base model and over the single listed cause of
    lowest BIC (the best member of the catalogue), for a report of what a
    form outside the catalogue would give (the limestone blocks).
    """
    fits = {} if fits is None else fits
    all_idx = np.arange(problem.n_tests)
    by_name = {c.name: c for c in problem.causes}
    cause = by_name[family]
    for ext in [(family,), *((c,) for c in problem.candidates())]:
        if ext not in fits:
            fits[ext] = fit(problem, all_idx, ext)
    best = min(problem.candidates(), key=lambda c: fits[(c,)].bic)
    f = fits[(family,)]
    ho = heldout(problem, (family,), f)
    ci = parameter_intervals(problem, f, n_boot=n_boot, seed=seed)
    vs_base, se_base = paired_gain(sel["base"]["deviance"], ho["deviance"])
    vs_best, se_best = paired_gain(heldout(problem, (best,), fits[(best,)])["deviance"], ho["deviance"])
    return {
        "effect": family,
        "form": cause.law,
        "params": f.values,
        "ci95": ci,
        "reduces_to": cause.closed_form(f.values, ci),
        "discovered": family in sel["effects"],
        "best_listed": best,
        "best_listed_params": fits[(best,)].values,
        "dbic_vs_base": f.bic - fits[()].bic if () in fits else None,
        "dbic_vs_best_listed": f.bic - fits[(best,)].bic,
        "heldout_gain": {
            "vs_base": vs_base,
            "vs_base_se": se_base,
            "vs_best_listed": vs_best,
            "vs_best_listed_se": se_best,
        },
    }


def discovery(problem: Problem, eff, sel):
    """The fields of a finding that say whether its form was discovered (a family) rather than listed.

    A discovered form carries the closed form of the library it reduces to
    (or "no closed form of the library") and its held-out gain against the
    base model and against the best model of the listed causes.
    """
    cause = next(c for c in problem.causes if c.name == eff)
    if not getattr(cause, "family", None):
        return {"discovered": False}
    ho = sel["final"]["deviance"]
    vs_catalogue, se_catalogue = paired_gain(sel["catalogue"]["final"]["deviance"], ho)
    vs_base, se_base = paired_gain(sel["base"]["deviance"], ho)
    own = [q.name for q in cause.params]
    return {
        "discovered": True,
        "family": f"{cause.law} (holds {cause.family})",
        "reduces_to": cause.closed_form(
            {k: sel["fit"].values[k] for k in own}, {k: sel["ci"][k] for k in own if k in sel["ci"]}
        ),
        "best_listed": sel["catalogue"]["effects"],
        "heldout_gain": {
            "vs_base": vs_base,
            "vs_base_se": se_base,
            "vs_best_listed": vs_catalogue,
            "vs_best_listed_se": se_catalogue,
        },
    }
