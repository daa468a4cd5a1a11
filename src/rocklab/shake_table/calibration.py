"""The block's contact fitted to the outcomes: a Bernoulli likelihood on the simulated grid.

The outcome of a test is a scalar (overturned or not), so the block is
simulated once per test at every node of its grid
(:func:`rocklab.shake_table.block.outcome_grid`) and every fit afterwards,
of every fold and every resample, reads that array: no fit simulates again.

Likelihood
----------
The contact of a convex base varies from test to test (where the block
lands, chips, dust), so the contact half-widths of a test are taken
lognormal about the fitted b_+ and b_-, each with a log-scatter ``sigma``;
with a lapse ``eps`` (an outcome the planar block cannot produce, e.g. the
out-of-plane coupling) the probability that test i overturns is::

    P_i = eps + (1 - 2 eps) sum_jk w_j(b_+, sigma) w_k(b_-, sigma) O_i(b_+j, b_-k, c)

with O_i the simulated outcome at the grid's nodes and w the lognormal
weights over the grid (Gaussian in ln b, normalised; sigma = 0 is the grid
node itself).  The log-likelihood sum_i [y_i ln P_i + (1 - y_i) ln(1 - P_i)]
is maximised over the grid of (b_+, b_-, c, sigma, eps).

What is chosen where
--------------------
The grid's bounds and nodes (:mod:`rocklab.shake_table.block`), the nodes
of sigma and eps (:data:`SIGMAS`, :data:`LAPSES`) are fixed in advance, from
the geometry and not from the outcomes.  Every value on them (contact, c,
sigma, eps) is chosen by the likelihood of the training tests only, so a
held-out score is that of the whole procedure (nested: nothing is chosen on
the tests it is scored on).

Uncertainty and held-out evaluation
-----------------------------------
Earthquake records are the unit of resampling and of the folds: the scaled
copies of one record, and its two horizontal components, are not
independent tests (:func:`rocklab.shake_table.asu_data.record_of`).
Intervals are percentiles of the fits to resampled records (bootstrap); the
fragility of a test, its probability of overturning, is the mean of P_i over
those fits.  The cross-validation (:func:`folds_by_group`) holds every test
of a record in one fold, and the difference of two predictors' held-out
accuracies has a paired bootstrap interval over records
(:func:`paired_accuracy_difference`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, TypeAlias

import numpy as np
from numpy.typing import ArrayLike
from scipy import optimize

from rocklab.diagnosis.parameters import Param
from rocklab.inference.intervals import percentile_interval
from rocklab.shake_table.block import PARAMS

#: Log-scatter of the contact half-widths from test to test [-] (ln units).
SIGMA = Param("sigma_ln_contact", 0.0, 0.8, 0.0, practical=0.05)
SIGMAS = np.array([0.0, 0.15, 0.3, 0.5, 0.8])

#: Probability of an outcome the planar block cannot produce [-].
LAPSE = Param("lapse", 0.001, 0.1, 0.0)
LAPSES = np.array([0.001, 0.005, 0.02, 0.05, 0.1])

#: Probabilities are clipped to [PROB_CLIP, 1 - PROB_CLIP] in the log loss.
PROB_CLIP = 1e-6

#: A node of the likelihood: the indices of eps, sigma and the flat grid index (:meth:`OutcomeLikelihood.fit`).
Node: TypeAlias = "tuple[int | np.integer[Any], ...]"


def folds_by_group(groups: ArrayLike, k: int = 5) -> np.ndarray:
    """Fold of every test, all tests of a group (record) in one fold.

    Groups are dealt, largest first, to the fold holding the fewest tests so
    far (ties: the lower fold): balanced and deterministic.

    Returns
    -------
    ndarray of int, shape (len(groups),)
    """
    groups = np.asarray(groups)
    names, counts = np.unique(groups, return_counts=True)
    k = int(min(k, names.size))
    if k < 2:
        raise ValueError(f"cross-validation needs at least 2 records, got {names.size}")
    load = np.zeros(k, int)
    fold_of: dict[Any, int] = {}
    for i in np.lexsort((names, -counts)):
        f = int(np.argmin(load))
        fold_of[names[i]] = f
        load[f] += counts[i]
    return np.array([fold_of[g] for g in groups], int)


def _kernel(ln_b: np.ndarray, sigma: float) -> np.ndarray:
    """Weights (centre, node) of the lognormal scatter over the nodes ``ln_b`` of one contact."""
    if sigma == 0:
        return np.eye(ln_b.size)
    w = np.exp(-0.5 * ((ln_b[None, :] - ln_b[:, None]) / sigma) ** 2)
    return w / w.sum(axis=1, keepdims=True)


class OutcomeLikelihood:
    """Bernoulli log-likelihood of every test at every node of (eps, sigma, b_+, b_-, c).

    Parameters
    ----------
    overturned : ndarray of bool, shape (tests, n_plus, n_minus, n_c)
        Simulated outcomes on the block's grid (:func:`~rocklab.shake_table.block.outcome_grid`).
    observed : array_like of bool, shape (tests,)
    grid : dict
        The grid values by parameter name (:data:`~rocklab.shake_table.block.PARAMS`, the axes of ``overturned``).
    """

    def __init__(self, overturned: ArrayLike, observed: ArrayLike, grid: Mapping[str, np.ndarray]) -> None:
        o = np.asarray(overturned, float)
        self.grid = grid
        self.shape = o.shape[1:]
        ln_p, ln_m = (np.log(grid[q.name]) for q in PARAMS[:2])
        # smoothed outcome S[sigma, test, b_+, b_-, c]
        smooth = np.stack([np.einsum("ai,bj,tijc->tabc", _kernel(ln_p, s), _kernel(ln_m, s), o) for s in SIGMAS])
        self.smooth = smooth.reshape(SIGMAS.size, o.shape[0], -1)
        y = np.asarray(observed, bool)[None, None, :, None]
        p = LAPSES[:, None, None, None] + (1 - 2 * LAPSES[:, None, None, None]) * self.smooth[None]
        # ll[eps, sigma, test, node]
        self.ll = np.where(y, np.log(p), np.log1p(-p))

    def fit(self, weights: ArrayLike) -> Node:
        """Node (eps, sigma, flat grid index) of the largest weighted log-likelihood.

        ``weights``: per test (0 leaves a test out; bootstrap counts resample).
        Ties go to the first node in grid order.
        """
        total = np.tensordot(self.ll, np.asarray(weights, float), axes=([2], [0]))
        return np.unravel_index(int(np.argmax(total)), total.shape)

    def probability(self, node: Node, idx: slice | np.ndarray = slice(None)) -> np.ndarray:
        """P_i of the tests ``idx`` at ``node`` (from :meth:`fit`)."""
        e, s, g = node
        return LAPSES[e] + (1 - 2 * LAPSES[e]) * self.smooth[s][idx, g]

    def node(self, values: Mapping[str, float]) -> Node:
        """The node (eps, sigma, flat grid index) of parameters ``values`` given on this grid's nodes."""
        ijk = tuple(int(np.flatnonzero(np.isclose(self.grid[q.name], values[q.name]))[0]) for q in PARAMS)
        e = int(np.flatnonzero(np.isclose(LAPSES, values[LAPSE.name]))[0])
        s = int(np.flatnonzero(np.isclose(SIGMAS, values[SIGMA.name]))[0])
        return e, s, int(np.ravel_multi_index(ijk, self.shape))

    def values(self, node: Node) -> dict[str, float]:
        """The parameters of ``node`` by name."""
        e, s, g = node
        ijk = np.unravel_index(g, self.shape)
        out = {q.name: float(self.grid[q.name][i]) for q, i in zip(PARAMS, ijk)}
        out[SIGMA.name] = float(SIGMAS[s])
        out[LAPSE.name] = float(LAPSES[e])
        return out


def resample_weights(groups: ArrayLike, idx: np.ndarray, n_boot: int, seed: int = 0) -> np.ndarray:
    """Bootstrap weights (n_boot, tests): the groups (records) of ``idx`` drawn with replacement, zero elsewhere."""
    groups = np.asarray(groups)
    rng = np.random.default_rng(seed)
    names = np.unique(groups[idx])
    member = {g: np.flatnonzero(groups == g) for g in names}
    out = np.zeros((n_boot, groups.size))
    for b in range(n_boot):
        for g in rng.choice(names, names.size, replace=True):
            out[b, member[g]] += 1
    return out


def calibrate(
    lik: OutcomeLikelihood, groups: Sequence[Any] | np.ndarray, idx: np.ndarray, n_boot: int = 200, seed: int = 0
) -> dict[str, Any]:
    """Fit on the tests ``idx``, resample their records, predict every test.

    Returns
    -------
    dict
        ``values`` (the fit on ``idx``), ``boot`` (list of the resamples'
        values), ``fragility`` (mean P of every test over the resamples),
        ``probability`` (P of every test at the fit), ``nodes`` (the
        resamples' nodes).
    """
    w = np.zeros(len(groups))
    w[idx] = 1.0
    node = lik.fit(w)
    nodes = [lik.fit(wb) for wb in resample_weights(groups, idx, n_boot, seed)]
    frag = np.mean([lik.probability(n) for n in nodes], axis=0) if nodes else lik.probability(node)
    return {
        "values": lik.values(node),
        "boot": [lik.values(n) for n in nodes],
        "fragility": frag,
        "probability": lik.probability(node),
        "nodes": nodes,
    }


def paired_accuracy_difference(
    y: ArrayLike,
    p_a: ArrayLike,
    p_b: ArrayLike,
    groups: ArrayLike,
    n_boot: int = 2000,
    seed: int = 0,
    level: float = 0.95,
) -> tuple[float, float, float]:
    """Accuracy of ``p_a`` minus that of ``p_b`` on the same tests, with a paired bootstrap interval over groups.

    Both predictors are scored on the same tests (P > 0.5 read as
    overturning); the groups (records) are drawn with replacement, each
    bringing all its tests and both predictors' calls on them, so the
    interval carries the correlation of tests within a record and of the two
    predictors on a test.

    Returns
    -------
    diff, lo, hi : float
        The difference on the tests as given and the percentile interval at ``level``.
    """
    y = np.asarray(y, bool)
    d = ((np.asarray(p_a) > 0.5) == y).astype(float) - ((np.asarray(p_b) > 0.5) == y).astype(float)
    names, inv = np.unique(np.asarray(groups), return_inverse=True)
    per_d, per_n = np.bincount(inv, d, names.size), np.bincount(inv, minlength=names.size).astype(float)
    draw = np.random.default_rng(seed).integers(0, names.size, (n_boot, names.size))
    boot = per_d[draw].sum(axis=1) / per_n[draw].sum(axis=1)
    lo, hi = percentile_interval(boot, level)
    return float(d.mean()), lo, hi


def intervals(boot: Sequence[Mapping[str, float]], level: float = 0.95) -> dict[str, tuple[float, float]]:
    """Percentile interval of every parameter over the resamples' values."""
    return {k: percentile_interval([b[k] for b in boot], level) for k in boot[0]}


def named(param: Param, ci: tuple[float, float]) -> bool:
    """Whether the interval ``ci`` stays clear of the parameter's null by its practical margin."""
    if param.practical is None:
        return False
    lo, hi = ci
    return lo > param.null + param.practical or hi < param.null - param.practical


def deterministic_probability(predicted: ArrayLike, train_error: float) -> np.ndarray:
    """A 0/1 prediction as a probability: the lapse is the predictor's error rate on its training tests.

    The rate is clipped to [0.005, 0.5]: a predictor without training errors
    keeps a finite log loss, and one wrong more often than not predicts no
    better than a coin.
    """
    eps = float(np.clip(train_error, 0.005, 0.5))
    return np.where(np.asarray(predicted, bool), 1.0 - eps, eps)


def logistic_threshold(x: ArrayLike, y: ArrayLike, weights: ArrayLike | None = None) -> tuple[float, float]:
    """Logistic regression of y on ln x: P = 1 / (1 + exp(-(ln x - ln x50) / beta)).

    The probabilistic form of a single threshold x50 (the PGV-threshold
    baseline); fitted by maximum likelihood.

    Returns
    -------
    x50, beta : float
    """
    lx, y = np.log(np.asarray(x, float)), np.asarray(y, float)
    w = np.ones_like(lx) if weights is None else np.asarray(weights, float)

    def nll(theta: np.ndarray) -> float:
        z = (lx - theta[0]) / np.exp(theta[1])
        return float(np.sum(w * (np.logaddexp(0.0, -z) * y + np.logaddexp(0.0, z) * (1 - y))))

    start = np.array([np.median(lx), np.log(0.2)])
    sol = optimize.minimize(nll, start, method="Nelder-Mead", options={"xatol": 1e-6, "fatol": 1e-9})
    return float(np.exp(sol.x[0])), float(np.exp(sol.x[1]))


def logistic_probability(x: ArrayLike, x50: float, beta: float) -> np.ndarray:
    """P of :func:`logistic_threshold`."""
    return 1.0 / (1.0 + np.exp(-(np.log(np.asarray(x, float)) - np.log(x50)) / beta))
