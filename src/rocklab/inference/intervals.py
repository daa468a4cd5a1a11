"""Intervals of a mean over units and of resampled values, and what a value without one says.

The rules every stage applies to the units it rests on (tests, series,
walls: :mod:`rocklab.lab.hierarchy`): Student's t on the units' degrees of
freedom (:func:`t_interval`, :func:`mean_over_units`; with the units'
standard errors, :func:`random_effects_mean`), the cluster-robust
mean of tests with walls as clusters (:func:`clustered_mean`), percentile
bootstrap intervals expanded for few units (:func:`percentile_interval`,
:func:`expanded`, :func:`bootstrap_ci`), and the fewest units an interval
is given from (:data:`MIN_BOOTSTRAP`).  The dissipation's tables
(:mod:`rocklab.dissipation.statistics`) and the diagnosis
(:mod:`rocklab.diagnosis`) both import them: they live below both.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from rocklab._imports import lazy_module
from rocklab.lab.hierarchy import too_few_units

stats = lazy_module("scipy.stats")


#: Fewest units resampled (tests for the interval of a series or for a
#: parameter of the diagnosis) from which a percentile bootstrap 95 % interval is given.
#: Every resampled mean lies between the smallest and the largest of the n
#: values resampled, and n draws of a symmetric population leave its centre
#: outside that range with probability 2^(1-n): the interval can cover at
#: most 50 % from 2 values, 75 % from 3, 88 % from 4 and 94 % from 5, the
#: first within reach of the nominal 95 %.  From one value it is a point.
MIN_BOOTSTRAP = 5


def t_interval(est: float, se: float, df: float, level: float = 0.95, null: float = 0.0) -> tuple[float, float, float]:
    """Two-sided Student's t interval of ``est`` and the p-value of ``est = null``."""
    if se == 0:
        return est, est, 1.0 if est == null else 0.0
    q = stats.t.ppf(0.5 + level / 2, df)
    return est - q * se, est + q * se, float(2 * stats.t.sf(abs(est - null) / se, df))


def mean_over_units(values: ArrayLike, units: ArrayLike, level: str) -> tuple[float, float, int, str]:
    """The mean over units of ``level`` of ``values``, each unit the mean of its values
    (a wall the mean of its series), and its standard error on units - 1 df.

    Parameters
    ----------
    values : sequence of float
    units : sequence
        The unit of each value.
    level : str
        The level of the units (:data:`rocklab.lab.hierarchy.LEVELS`).

    Returns
    -------
    mean, se : float
    n_units : int
    reason : str
        Why no verdict or interval rests on these units
        (:func:`rocklab.lab.hierarchy.too_few_units`); "" when it can.
    """
    by_unit = pd.Series(np.asarray(values, float), index=np.asarray(units)).groupby(level=0).mean()
    k = len(by_unit)
    se = float(by_unit.std(ddof=1) / np.sqrt(k)) if k > 1 else np.nan
    return float(by_unit.mean()), se, k, too_few_units(level, k, k - 1)


def random_effects_mean(
    values: ArrayLike, se: ArrayLike, units: ArrayLike, level: str
) -> tuple[float, float, int, str, float]:
    """The random-effects mean over units of ``level`` of estimates with standard errors, on units - 1 df.

    Each unit is the mean of its estimates (a wall the mean of its series:
    they measure the same wall), its variance the mean of their squared
    standard errors over their number.  Between units the truth itself
    varies: the mean weighs unit j by 1 / (v_j + tau^2), tau^2 the
    DerSimonian-Laird moment estimate of the variance between units, and its
    standard error is that of Hartung & Knapp (2001; Sidik & Jonkman 2002),
    sum_j w_j (m_j - mean)^2 / ((k - 1) sum_j w_j), on k - 1 degrees of
    freedom, never below the DerSimonian-Laird 1 / sum_j w_j (the floor of
    Knapp & Hartung 2003: k units that agree by chance would otherwise claim
    a precision their own errors deny).  Where the units scatter far more
    than their errors, tau^2 dominates, the weights are equal and this is
    :func:`mean_over_units`; where they agree within their errors, the mean
    is the inverse-variance one.  A standard error that is missing, not
    finite or zero gives no weight: the plain mean over units
    (:func:`mean_over_units`) stands instead.

    Parameters
    ----------
    values : sequence of float
        The estimates [their unit].
    se : sequence of float
        Their standard errors [the same unit]; NaN where unknown.
    units : sequence
        The unit of each estimate.
    level : str
        The level of the units (:data:`rocklab.lab.hierarchy.LEVELS`).

    Returns
    -------
    mean, se : float
        ``se`` NaN from one unit.
    n_units : int
    reason : str
        Why no verdict or interval rests on these units
        (:func:`rocklab.lab.hierarchy.too_few_units`); "" when it can.
    tau : float
        The standard deviation between units [the values' unit]; NaN where the plain mean stands.
    """
    x = np.asarray(values, float)
    s = np.asarray(se, float)
    if not (np.isfinite(s).all() and (s > 0).all()):
        m, e, k, reason = mean_over_units(x, units, level)
        return m, e, k, reason, np.nan
    frame = pd.DataFrame({"x": x, "v": s**2, "u": np.asarray(units)}).groupby("u", sort=False)
    m_j = frame["x"].mean().to_numpy()
    # the mean of n estimates of one unit: the sum of their variances over n^2
    v_j = (frame["v"].sum() / frame["v"].count() ** 2).to_numpy()
    k = len(m_j)
    reason = too_few_units(level, k, k - 1)
    if k < 2:
        return float(m_j[0]), np.nan, k, reason, np.nan
    w = 1.0 / v_j
    fixed = np.sum(w * m_j) / w.sum()
    q = float(np.sum(w * (m_j - fixed) ** 2))
    tau2 = max(0.0, (q - (k - 1)) / (w.sum() - np.sum(w**2) / w.sum()))
    w = 1.0 / (v_j + tau2)
    mean = float(np.sum(w * m_j) / w.sum())
    var = max(float(np.sum(w * (m_j - mean) ** 2)) / ((k - 1) * w.sum()), 1.0 / float(w.sum()))
    return mean, float(np.sqrt(var)), k, reason, float(np.sqrt(tau2))


def clustered_mean(values: ArrayLike, units: ArrayLike, level: str) -> tuple[float, float, float, int, str]:
    """The mean over all ``values`` and its standard error with the units of ``level`` as clusters.

    The cluster-robust standard error with the bias reduction CR2 of Bell &
    McCaffrey (2002), and its degrees of freedom by Imbens & Kolesar (2016):
    the mean over tests weighs a wall by its tests, w_j = n_j / N, and with
    few, unequal walls the usual CR1 error on walls - 1 df is too small
    (simulated walls that scatter five times more than their tests: on the
    campaign's two-sided walls, 13-69 tests each, a 95 % interval covers
    about 91 %, on one wall of 60 tests beside three of 5, 62 %; CR2 on
    these df, 95 %).  For
    the mean (an intercept-only least squares)

        se^2 = sum_j w_j^2 (m_j - mean)^2 / (1 - w_j),
        df = 1 / (sum_j w_j^2 + (sum_j a_j)^2 - sum_j a_j^2),  a_j = w_j^2 / (1 - w_j),

    over the unit means m_j (df from the working model of independent
    values); for equal weights se^2 = sd(m_j)^2 / k and df = k - 1, the t
    interval of the unit means (:func:`mean_over_units`), and below it when
    one wall holds most of the values.

    Parameters
    ----------
    values : sequence of float
    units : sequence
        The unit of each value.
    level : str
        The level of the units (:data:`rocklab.lab.hierarchy.LEVELS`).

    Returns
    -------
    mean, se, df : float
        ``se`` and ``df`` NaN from one unit.
    n_units : int
    reason : str
        Why no interval rests on these units (:func:`rocklab.lab.hierarchy.too_few_units`
        on units - 1 df); "" when it can.
    """
    x = np.asarray(values, float)
    codes, uniques = pd.factorize(np.asarray(units))
    k = len(uniques)
    n = np.bincount(codes, minlength=k)
    w = n / n.sum()
    mean = float(x.mean())
    if k < 2:
        return mean, np.nan, np.nan, k, too_few_units(level, k, k - 1)
    by_unit = np.bincount(codes, x, minlength=k) / n
    se = float(np.sqrt((w**2 * (by_unit - mean) ** 2 / (1 - w)).sum()))
    a = w**2 / (1 - w)
    df = float(1 / ((w**2).sum() + a.sum() ** 2 - (a**2).sum()))
    return mean, se, df, k, too_few_units(level, k, k - 1)


def interval_note(n: int, unit: str = "tests") -> str:
    """Why a value resting on ``n`` ``unit`` has no bootstrap interval; "" when it has one."""
    return f"too few {unit} for an interval ({n} < {MIN_BOOTSTRAP})" if n < MIN_BOOTSTRAP else ""


def no_interval_note(reason: str) -> str:
    """The note of a value given without an interval because of :func:`rocklab.lab.hierarchy.too_few_units`'s
    ``reason``: "2 walls, 1 residual df (2 needed): no interval"; "" for no reason."""
    return f"{reason}: no interval" if reason else ""


def small_sample_expansion(n_units: int, level: float = 0.95) -> float:
    """The factor by which a percentile bootstrap interval over ``n_units`` resampled units is too narrow.

    The bootstrap distribution of a mean over n units has the spread of
    the plug-in standard error, sqrt((n - 1) / n) of the unbiased one, and
    its percentiles are normal quantiles where the mean over few units is
    Student's t on n - 1 degrees of freedom; the expanded percentile
    interval (Hesterberg 2015, The American Statistician 69, 371-386) makes
    up both, sqrt(n / (n - 1)) t_{n-1} / z: 1.58 from 5 units, 1.22 from 10,
    1.10 from 20 at 95 %.  A percentile interval of a mean over 5 normal
    units at the plain percentiles holds about 85 %.

    Returns
    -------
    float
        >= 1; 1 for an infinite number of units.
    """
    q = 0.5 + level / 2
    return float(np.sqrt(n_units / (n_units - 1)) * stats.t.ppf(q, n_units - 1) / stats.norm.ppf(q))


def expanded(interval: Sequence[float], centre: float, n_units: int, level: float = 0.95) -> tuple[float, float]:
    """A percentile ``interval`` over ``n_units`` resampled units, each side's distance from the estimate
    ``centre`` widened by :func:`small_sample_expansion` (the expanded percentile interval with its
    quantiles read off a normal approximation: 40 resamples cannot reach the 0.3 % percentile that
    5 units need).

    Returns
    -------
    (low, high) : float
    """
    f = small_sample_expansion(n_units, level)
    lo, hi = interval
    return float(centre - f * (centre - lo)), float(centre + f * (hi - centre))


def percentile_interval(draws: ArrayLike, level: float = 0.95, axis: int | None = None) -> tuple[Any, Any]:
    """Percentile interval of resampled values whose expected content of their distribution is ``level``.

    The quantiles (1 -+ level) / 2 of the ``n`` draws at the plotting
    position p (n + 1) (numpy's ``method="weibull"``): the order statistics
    j < k of n draws hold on average (k - j) / (n + 1) of the distribution
    they are drawn from, so these hold ``level``; numpy's default position
    p (n - 1) + 1 holds (n - 1) level / (n + 1): 0.904 of it from 40
    resamples for a 95 % interval, 0.941 from 200.  Below
    n = 2 / (1 - level) - 1 draws (39 at 95 %) the interval is their range,
    whose content (n - 1) / (n + 1) falls short of ``level``.

    Returns
    -------
    (low, high) : float, or arrays along the axes left
    """
    q = (1.0 - level) / 2.0
    lo, hi = np.quantile(np.asarray(draws, float), [q, 1.0 - q], axis=axis, method="weibull")
    return (float(lo), float(hi)) if np.ndim(lo) == 0 else (lo, hi)


def bootstrap_ci(values: ArrayLike, n_boot: int = 4000, level: float = 0.95, seed: int = 0) -> tuple[float, float]:
    """Percentile bootstrap interval of the mean (vectorised, seeded), expanded for its few values
    (:func:`expanded`).

    Returns (low, high); NaN for fewer than :data:`MIN_BOOTSTRAP` finite values.
    """
    x = np.asarray(values, float)
    x = x[np.isfinite(x)]
    if x.size < MIN_BOOTSTRAP:
        return np.nan, np.nan
    rng = np.random.default_rng(seed)
    means = x[rng.integers(0, x.size, size=(n_boot, x.size))].mean(axis=1)
    return expanded(percentile_interval(means, level), x.mean(), x.size, level)
