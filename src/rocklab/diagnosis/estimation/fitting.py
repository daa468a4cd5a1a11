"""Maximum-likelihood fit of a combination of causes, and its linearisation.

The fit (:func:`fit`) is iteratively reweighted least squares with the
noise model of each residual group (:mod:`rocklab.diagnosis.estimation.noise`);
its linearisation at the optimum, test by test (:func:`linearised`), is what
the held-out folds and the bootstrap resamples step from
(:mod:`rocklab.diagnosis.estimation.resampling`).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Collection, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any, TypeAlias, TypeVar

import numpy as np

from rocklab._imports import lazy_module
from rocklab.diagnosis.estimation.noise import VAR_FLOOR, deviance, finite_residuals, group_variances
from rocklab.diagnosis.estimation.problem import Problem

optimize = lazy_module("scipy.optimize")

log = logging.getLogger(__name__)

Sub = TypeVar("Sub")

#: :func:`linearised`: names, x0, lo, hi, A, y.
Linearisation: TypeAlias = tuple[list[str], np.ndarray, np.ndarray, np.ndarray, list[np.ndarray], list[np.ndarray]]


@dataclass
class Fit:
    """A fitted model: parameter values, group noise models, -2 log L, observations,
    and the reweighting passes of its best start and whether they converged; ``heldout``: its
    held-out result (:func:`rocklab.diagnosis.estimation.selection.heldout_of`), made once."""

    ext: tuple[str, ...]
    values: dict[str, float]
    var: dict[str, tuple[float, float]]
    m2ll: float
    n_obs: int
    passes: int = 0
    converged: bool = True
    heldout: dict[str, np.ndarray] | None = field(default=None, repr=False, compare=False)

    @property
    def bic(self) -> float:
        return self.m2ll + len(self.values) * math.log(max(self.n_obs, 2))


#: Fits by their causes, shared by the selections on one problem.
Fits: TypeAlias = dict[tuple[str, ...], Fit]


def fit(
    problem: Problem[Any],
    idx: np.ndarray,
    ext: Collection[str],
    x0: Mapping[str, float] | None = None,
    n_irls: int | None = None,
) -> Fit:
    """Maximum-likelihood fit of ``ext`` on the tests ``idx``, noise model per group.

    Iteratively reweighted least squares: with the weights of the noise
    model (:func:`~rocklab.diagnosis.estimation.noise.noise_variance`) of
    the previous pass, a bounded least-squares fit, then the noise model
    again; its fixed point is the maximum of the likelihood.  The first
    pass searches; the weights of the next ones move the optimum by little,
    and each is one Gauss-Newton step with the derivatives at the first
    pass's optimum, reweighted.  Non-convex parameters start both at their
    null and at the value the data suggest (:meth:`Problem.starts`); the
    better end wins.  ``x0`` (a previous fit) gives a single warm start, and
    two passes (``n_irls``, default 5 cold, 2 warm) then suffice.
    """
    sub = problem.subset(idx)
    X = problem.noise(sub)
    plist = problem.params(ext)
    if not plist:
        R = problem.residuals(sub, ext, {})
        var = group_variances(R, X)
        return Fit(tuple(ext), {}, var, deviance(R, X, var), sum(r.size for r, _ in finite_residuals(R, X).values()))
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
    # the residuals of the latest points evaluated, by the points' bits: a start is the point the masks are
    # read at, and a pass's optimum the point least_squares accepted last (where the two are equal bit for bit)
    latest: dict[bytes, dict[str, np.ndarray]] = {}

    def residuals_of(xx: np.ndarray) -> dict[str, np.ndarray]:
        key = np.asarray(xx, float).tobytes()
        if key not in latest:
            if len(latest) >= 3:
                del latest[next(iter(latest))]
            latest[key] = problem.residuals(sub, ext, dict(zip(names, xx)))
        return latest[key]

    R0 = residuals_of(starts[0])
    masks = {g: np.isfinite(r) & np.isfinite(X[g]) for g, r in R0.items()}
    masks = {g: m for g, m in masks.items() if m.sum() >= 2}
    xm = {g: X[g][m] for g, m in masks.items()}
    best = None
    for x in starts:
        R = residuals_of(x)
        var = group_variances({g: R[g] for g in masks}, X)
        passes, converged, jac, m2 = 0, False, None, np.inf
        for _ in range(n_irls):
            passes += 1
            wv = np.concatenate([1.0 / np.sqrt(var[g][0] + var[g][1] * xm[g] ** 2 + VAR_FLOOR) for g in masks])

            def stacked(R: Mapping[str, np.ndarray], wv: np.ndarray = wv) -> np.ndarray:
                r = np.concatenate([R[g][m] for g, m in masks.items()])
                # a residual the start had and a point of the search lacks: a bounded stand-in (nan_to_num,
                # a tenth of the evaluation's cost, only where one is missing)
                return (r if np.isfinite(r).all() else np.nan_to_num(r, nan=1.0, posinf=1.0, neginf=-1.0)) * wv

            def res(xx: np.ndarray) -> np.ndarray:
                return stacked(residuals_of(xx))

            def together(_: object, points: Iterable[np.ndarray], stacked: Callable[..., np.ndarray] = stacked) -> list:
                # the points of least_squares' finite differences (its own steps and bounds), evaluated at once
                at = [dict(zip(names, xx)) for xx in points]
                return [stacked(R) for R in problem.residuals_at(sub, ext, at)]

            if jac is None:
                sol = optimize.least_squares(
                    res, x, bounds=(lo, hi), x_scale="jac", diff_step=1e-5, xtol=1e-9, ftol=1e-9, workers=together
                )
                step, jac = sol.x - x, sol.jac / wv[:, None]
            else:
                # the weights moved the optimum by little: one Gauss-Newton step from the last pass's
                # optimum, with its derivatives (at that point) reweighted, instead of a new search
                step = optimize.lsq_linear(jac * wv[:, None], -stacked(R), bounds=(lo - x, hi - x)).x
            moved = np.max(np.abs(step) / (hi - lo))
            x_new = np.clip(x + step, lo, hi)
            R_new = residuals_of(x_new)
            var_new = group_variances({g: np.where(m, R_new[g], np.nan) for g, m in masks.items()}, X)
            m2_new = deviance({g: np.where(m, R_new[g], np.nan) for g, m in masks.items()}, X, var_new)
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
        m2ll = deviance(R, X, var)
        if best is None or m2ll < best.m2ll:
            n_obs = int(sum(m.sum() for m in masks.values()))
            best = Fit(tuple(ext), dict(zip(names, map(float, x))), var, m2ll, n_obs, passes, converged)
    # the first pass always gives a fit: best is None before it only
    assert best is not None
    log.debug("fit %s on %d tests: %s, %d passes", ext, len(idx), best.values, best.passes)
    return best


def _jacobian(
    problem: Problem[Sub], sub: Sub, ext: Collection[str], values: Mapping[str, float]
) -> tuple[dict[str, np.ndarray], dict[str, list[np.ndarray]]]:
    """Residuals at ``values`` and their derivatives by each parameter (forward differences).

    Returns (R, J): group -> residual array, group -> list of derivative
    arrays (one per parameter of ``ext``, like the residuals).
    """
    steps = []
    for q in problem.params(ext):
        # the step least_squares takes (diff_step 1e-5, relative), away from the nearer bound
        h = 1e-5 * max(abs(values[q.name]), 1.0)
        steps.append((q.name, -h if values[q.name] + h > q.upper else h))
    R, *moved = problem.residuals_at(sub, ext, [values, *({**values, k: values[k] + h} for k, h in steps)])
    J: dict[str, list[np.ndarray]] = {g: [(Rq[g] - R[g]) / h for Rq, (_, h) in zip(moved, steps)] for g in R}
    return R, J


def linearised(problem: Problem[Sub], sub: Sub, fitted: Fit) -> Linearisation:
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
    A: list[list[np.ndarray]] = [[] for _ in tests]
    y: list[list[np.ndarray]] = [[] for _ in tests]
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
