"""Changes of a fitted model's parameters over the tests of a series: a change point, or gradual.

A series is pooled into one value per parameter on the premise that its
tests share one wall state; a rocking edge crushed part-way through, or a
hinge worn test after test, breaks it.  For every parameter of a fit
(:func:`rocklab.diagnosis.series.within_series`: the chosen model's, and a
candidate's that the held-out test turned down), :func:`changes_over_tests` asks whether it changes over the tests'
place in the series, the test being the unit:

- the statistic.  The fit's least-squares problem linearised test by test at
  its optimum (:func:`~rocklab.diagnosis.estimation.fitting.linearised`, the
  one the held-out folds and the bootstrap step from) gains one column: the
  parameter's derivative times an indicator of the tests after a split (a
  change point; every split with at least :data:`MIN_SIDE` tests on each
  side) or times the test's place n - 1/2, n from 0 (first) to 1 (last) (a
  gradual change).  The drop of the weighted residual sum of squares it buys
  is the drop of the deviance under the fit's noise model; the change point's
  is its largest over the splits.
- its significance, a permutation test over the test order: the same
  statistics with the tests' places shuffled (whole tests, their impacts
  together), their maximum over the splits taken again each time.  It
  accounts for the search over splits (the maximum is what is permuted) and
  for residuals correlated within a test (whole tests move), which a
  chi-square reference of the deviance, or a Bonferroni over splits on it,
  would not: a Bonferroni on a statistic too large by the within-test
  correlation stays overconfident.  The two kinds and the parameters are
  tested at ``level`` together (Bonferroni over both).
- the choice between none, gradual and change point: a change where either
  kind clears the permutation test; which kind, the one of lower information
  criterion (BIC, the location of a change point counted as a parameter),
  which must drop by the strong evidence a cause needs to enter the
  selection (:data:`~rocklab.diagnosis.estimation.selection.BIC_MARGIN`);
  and its size must exceed the parameter's smallest effect worth naming.
  The permutation test has few orders to draw on: a step's statistic is the
  same for a partition of the tests and its mirror, so a step after 3 of 10
  tests has a p-value no smaller than 2 / C(10, 3) = 0.017, and one two tests
  from an end of ten no smaller than 2 / 45 = 0.044, above the level: such a
  step is named only where the gradual statistic carries it.  A series whose
  rarest order is above the level names nothing and says so (``note``).
- its size, on the tests.  A change point: the model refitted on the tests
  before and after the split, warm from the series' fit, each side's
  cluster-robust t interval on its tests less one
  (:func:`~rocklab.diagnosis.estimation.resampling.sandwich_intervals`)
  widened by the systematic part every test shares, and
  the jump's on the fewer side's tests less one (with two tests a side, t on
  one degree of freedom: 12.7).  A gradual change: the line of the tests'
  own values of the parameter over their place (the change from the first
  test to the last), its t interval on the tests less two.  The place of a change
  point is given without an interval.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from collections.abc import Mapping, Sequence
from typing import Any, cast

import numpy as np

from rocklab._imports import lazy_module
from rocklab.diagnosis.estimation.fitting import Fit, fit, linearised
from rocklab.diagnosis.estimation.problem import Problem
from rocklab.diagnosis.estimation.resampling import sandwich_errors, sandwich_intervals
from rocklab.diagnosis.estimation.systematic import by_group, systematic_uncertainty, widened
from rocklab.diagnosis.result import ChangeKind, SeriesChange

stats = lazy_module("scipy.stats")

log = logging.getLogger(__name__)

#: Tests on each side of a change point, at least: one test a side has no spread to give an interval by.
MIN_SIDE = 2
#: Permutations of the test order: the smallest p-value they give is 1 / (N + 1), 0.0025, below the
#: Bonferroni level of 0.05 over the two kinds and five parameters (0.005).
N_PERMUTATIONS = 399
#: Family-wise level of the tests of one series (every parameter, both kinds).
LEVEL = 0.05


def _drops(AtA: np.ndarray, Aty: np.ndarray, Z: np.ndarray, j: int) -> np.ndarray:
    """Drops of the weighted residual sum of squares of the linearised fit when the column (derivative by
    parameter ``j``) x z_i joins it, for each row z of ``Z`` (..., tests).

    ``AtA`` (tests, k, k) and ``Aty`` (tests, k) are the per-test normal equations.  The drop of one
    added column is closed (the Schur complement of the shared parameters): with G the summed normal
    matrix, b its right-hand side, g = sum_i z_i (A_i^T A_i)[:, j], d = sum_i z_i^2 (A_i^T A_i)[j, j] and
    c = sum_i z_i (A_i^T y_i)[j], it is (c - g^T G^-1 b)^2 / (d - g^T G^-1 g) (:func:`_closed_drop`).
    """
    g = np.einsum("...i,ik->...k", Z, AtA[:, :, j])
    d = np.einsum("...i,i->...", Z**2, AtA[:, j, j])
    c = np.einsum("...i,i->...", Z, Aty[:, j])
    return _closed_drop(AtA, Aty, g, d, c)


def _step_drops(AtA: np.ndarray, Aty: np.ndarray, ranks: np.ndarray, splits: Sequence[int], j: int) -> np.ndarray:
    """:func:`_drops` of the steps: z_i = 1 for the tests ranked at or after each split, 0 before
    (..., splits), for tests ranked ``ranks`` (..., tests; 0 first).

    A step's sums g, d and c are those of every test less those ranked before the split: prefix sums over
    the tests in rank order, O(tests) per order where the steps' indicators cost O(tests^2) (some 2.7 GB
    for the 400 orders of a series of 900 tests).
    """
    order = np.argsort(ranks, axis=-1)
    before = np.asarray(splits) - 1
    g, d, c = (
        v.sum(axis=0) - np.cumsum(v[order], axis=ranks.ndim - 1)[..., before, :]
        for v in (AtA[:, :, j], AtA[:, j, j, None], Aty[:, j, None])
    )
    return _closed_drop(AtA, Aty, g, d[..., 0], c[..., 0])


def _closed_drop(AtA: np.ndarray, Aty: np.ndarray, g: np.ndarray, d: np.ndarray, c: np.ndarray) -> np.ndarray:
    """(c - g^T G^-1 b)^2 / (d - g^T G^-1 g), the drop of one added column from its sums (:func:`_drops`):
    every split of every permutation at the cost of a few products."""
    Ginv = np.linalg.pinv(AtA.sum(axis=0))
    w = Ginv @ Aty.sum(axis=0)
    schur = d - np.einsum("...k,kl,...l->...", g, Ginv, g)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = (c - g @ w) ** 2 / schur
    # a column the shared parameters already span buys nothing
    return np.where(schur > 1e-12 * np.maximum(d, 1e-300), out, 0.0)


def changes_over_tests(
    problem: Problem[Any],
    tested: Mapping[str, Fit],
    *,
    test_ids: Sequence[str] = (),
    n_permutations: int = N_PERMUTATIONS,
    level: float = LEVEL,
    bic_margin: float | None = None,
    seed: int = 0,
) -> list[SeriesChange]:
    """The parameters of each cause of ``tested`` tested for a change over the tests of ``problem``.

    Parameters
    ----------
    problem : Problem
        Its tests in series order (index 0 first).
    tested : mapping
        Cause -> the fit (on all the tests) whose parameters of that cause are tested: the chosen
        model's for the causes it names.
    test_ids : sequence of str
        The tests' ids, to name where a change point is.
    n_permutations : int
        Shuffles of the test order for the permutation test, at least; more where the level over the
        parameters needs them (4 / the level of each).
    level : float
        Family-wise level over every parameter tested and the two kinds (Bonferroni).
    bic_margin : float, optional
        BIC drop a change needs (default: the selection's
        :data:`~rocklab.diagnosis.estimation.selection.BIC_MARGIN`).

    Returns
    -------
    list of SeriesChange
        One per parameter tested, its ``kind`` :attr:`ChangeKind.NONE` where no change is found, with a
        ``note`` where the tests are too few to test one.
    """
    from rocklab.diagnosis.estimation.selection import BIC_MARGIN

    margin = BIC_MARGIN if bic_margin is None else bic_margin
    t0 = time.perf_counter()
    n = problem.n_tests
    own = {x: [q.name for q in problem.params((x,)) if q.name in f.values] for x, f in tested.items()}
    n_params = sum(len(v) for v in own.values())
    if not n_params:
        return []
    per_test = level / (2 * n_params)
    splits = list(range(MIN_SIDE, n - MIN_SIDE + 1))
    if not splits:
        short = f"a change over tests needs {2 * MIN_SIDE} tests ({MIN_SIDE} each side of a split), the series has {n}"
        return [
            SeriesChange(parameter=k, effect=x, n_tests=n, level=per_test, note=short)
            for x, ks in own.items()
            for k in ks
        ]
    # enough shuffles that the Monte Carlo's smallest p-value, 1 / (N + 1), is a quarter of the level at most:
    # many parameters tested must not make the shuffles, rather than the tests, what names nothing
    n_permutations = max(n_permutations, math.ceil(4 / per_test) - 1)
    # the rarest order of n tests (the gradual statistic's: the order and its reverse), or of the shuffles drawn
    # (171! overflows a float, and 2 / 170! lies far below any Monte Carlo's 1 / (N + 1): the bound is exact)
    rarest = max(2.0 / math.factorial(min(n, 170)), 1.0 / (n_permutations + 1))
    note = (
        f"no order of {n} tests is rarer than {rarest:.2g} among their orders, above the level {per_test:.2g}: "
        "these tests cannot carry a change"
        if rarest > per_test
        else None
    )
    every = problem.subset(np.arange(n))
    place = np.arange(n) / (n - 1)
    rng = np.random.default_rng(seed)
    # test i of a shuffle takes the place of test ranks[i]
    ranks = np.array([rng.permutation(n) for _ in range(n_permutations)])
    linear: dict[int, tuple[list[str], np.ndarray, list[np.ndarray], list[np.ndarray], np.ndarray, np.ndarray]] = {}
    out = []
    for x, ks in own.items():
        f = tested[x]
        if id(f) not in linear:
            # one linearisation per fit: the named causes share the chosen model's
            names, x0, _, _, A, y = linearised(problem, every, f)
            AtA = np.array([a.T @ a for a in A])
            Aty = np.array([a.T @ b for a, b in zip(A, y)])
            linear[id(f)] = (names, x0, A, y, AtA, Aty)
        names, x0, A, y, AtA, Aty = linear[id(f)]
        log_n = math.log(max(f.n_obs, 2))
        for k in ks:
            j = names.index(k)
            cp, gr = _step_drops(AtA, Aty, np.arange(n), splits, j), float(_drops(AtA, Aty, place - 0.5, j))
            null_cp = _step_drops(AtA, Aty, ranks, splits, j).max(axis=-1)
            null_gr = _drops(AtA, Aty, place[ranks] - 0.5, j)
            # the observed order counts among the orders (a permutation p-value is never 0)
            p_cp = float((1 + np.sum(null_cp >= cp.max() * (1 - 1e-9))) / (1 + n_permutations))
            p_gr = float((1 + np.sum(null_gr >= gr * (1 - 1e-9))) / (1 + n_permutations))
            # BIC: a change point buys its jump and its place, a gradual change its slope
            dbic_cp, dbic_gr = -float(cp.max()) + 2 * log_n, -gr + log_n
            best = int(splits[int(np.argmax(cp))])
            change = SeriesChange(
                parameter=k,
                effect=x,
                n_tests=n,
                p_change_point=p_cp,
                p_gradual=p_gr,
                dbic_change_point=dbic_cp,
                dbic_gradual=dbic_gr,
                level=per_test,
                n_permutations=n_permutations,
                note=note,
            )
            # whether there is a change is the permutation test's (either kind at the level); which kind, the
            # information criterion's: a step near the end of ten tests has a permutation p-value no smaller
            # than 1 / C(10, 2), and its gradual reading, less significant as a step, must not name it
            kinds = ((dbic_cp, ChangeKind.CHANGE_POINT), (dbic_gr, ChangeKind.GRADUAL))
            passing = [(dbic, kind) for dbic, kind in kinds if dbic < -margin]
            if passing and min(p_cp, p_gr) <= per_test:
                kind = min(passing)[1]
                sized = (
                    _change_point(problem, f, k, best, test_ids)
                    if kind is ChangeKind.CHANGE_POINT
                    else _gradual(A, y, x0, j, place)
                )
                q = next(q for q in problem.params((x,)) if q.name == k)
                # a change too small to be worth naming is no change of the wall
                if q.practical is None or abs(cast(float, sized.size)) > q.practical:
                    change = dataclasses.replace(change, kind=kind, **_sized(sized))
            out.append(change)
            log.info(
                "%s of %s over %d tests: change point before test %d p = %.3g (dBIC %+.1f), gradual p = %.3g "
                "(dBIC %+.1f), level %.3g: %s",
                k,
                x,
                n,
                best,
                p_cp,
                dbic_cp,
                p_gr,
                dbic_gr,
                per_test,
                change.kind.value,
            )
    log.info("changes over %d tests of %d parameters in %.2f s", n, n_params, time.perf_counter() - t0)
    return out


def _sized(change: SeriesChange) -> dict[str, Any]:
    """The fields of ``change`` that say where and how much."""
    keys = ("where_index", "where_test", "before", "after", "ci95_before", "ci95_after", "size", "ci95_size")
    return {key: getattr(change, key) for key in keys}


def _change_point(problem: Problem[Any], fitted: Fit, k: str, split: int, test_ids: Sequence[str]) -> SeriesChange:
    """Parameter ``k`` before and after the change point at ``split`` (the first test after it): the model
    refitted on each side, warm from the series' fit, with each side's cluster-robust t intervals widened by
    the parameter's systematic standard uncertainty at the series' fit on its degrees of freedom
    (:func:`~rocklab.diagnosis.estimation.systematic.systematic_uncertainty`)."""
    n = problem.n_tests
    # what every test shares (the pulls of the residual groups, at the series' fit) moves both sides alike:
    # it widens each side's value, as it does the findings', and leaves their difference
    names, *_, groups = by_group(problem, fitted)
    u_all, nu_all = systematic_uncertainty(groups)
    u_sys, nu_sys = float(u_all[names.index(k)]), float(nu_all[names.index(k)])
    q = next(q for q in problem.params(fitted.ext) if q.name == k)
    sides = []
    for idx in (np.arange(split), np.arange(split, n)):
        f = fit(problem, idx, fitted.ext, x0=fitted.values)
        names, x0, lo, hi, A, y = linearised(problem, problem.subset(idx), f)
        j = names.index(k)
        stat = sandwich_intervals(names, x0, lo, hi, A, y)[k]
        ci = widened(stat, f.values[k], q.lower, q.upper, u_sys, df=max(len(idx) - 1, 1), df_sys=nu_sys)
        se = float(sandwich_errors(A, y)[j])
        sides.append((f.values[k], ci, se, len(idx)))
    (b, ci_b, se_b, n_b), (a, ci_a, se_a, n_a) = sides
    # the jump's interval on the fewer side's tests less one: Welch's degrees of freedom lie above it
    half = float(stats.t.ppf(0.975, min(n_b, n_a) - 1)) * math.hypot(se_b, se_a)
    return SeriesChange(
        parameter=k,
        where_index=split,
        where_test=test_ids[split] if split < len(test_ids) else None,
        before=float(b),
        after=float(a),
        ci95_before=list(ci_b),
        ci95_after=list(ci_a),
        size=float(a - b),
        ci95_size=[float(a - b - half), float(a - b + half)],
    )


def _gradual(
    A: Sequence[np.ndarray], y: Sequence[np.ndarray], x0: np.ndarray, j: int, place: np.ndarray
) -> SeriesChange:
    """Parameter ``j`` changing linearly over the tests' ``place`` (0 to 1), on the tests as units.

    Each test's own value of the parameter, the others held at the series' fit (one Gauss-Newton step of
    its linearised residuals ``A``, ``y`` along the parameter), and the least-squares line of those values
    over the place, with its t interval on the tests less two: its value at the first and the last test and
    the change between.  The tests' values, not their impacts, carry the slope: a test's own level (the
    residuals of a test alike) is in their scatter, where a cluster-robust interval of the impacts' slope
    on ten tests held 89 % of its truth in 300 series, not 95 % (tests/test_series_change.py).
    """
    a = [ai[:, j] for ai in A]
    seen = np.array([float(ai @ ai) > 0 for ai in a])
    own = np.array([x0[j] + float(ai @ yi) / float(ai @ ai) if ok else np.nan for ai, yi, ok in zip(a, y, seen)])
    z, v = place[seen], own[seen]
    fit_line = stats.linregress(z, v)
    half = float(stats.t.ppf(0.975, max(z.size - 2, 1))) * float(fit_line.stderr)
    slope, first = float(fit_line.slope), float(fit_line.intercept)
    return SeriesChange(
        parameter="",
        before=first,
        after=first + slope,
        size=slope,
        ci95_size=[slope - half, slope + half],
    )
