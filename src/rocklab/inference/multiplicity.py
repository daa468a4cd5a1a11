"""Many statements at once: family-wise p-values and simultaneous intervals."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rocklab._imports import lazy_module

stats = lazy_module("scipy.stats")


def simultaneous_factor(k: int, df: float, level: float = 0.95) -> float:
    """The factor that widens ``k`` intervals of ``level`` each into intervals that hold all ``k`` at ``level``.

    Šidák's rule: each interval at level^(1/k) (0.9747 for two at 95 %),
    exact for independent estimates and conservative for correlated ones;
    the factor is the ratio of Student's t quantiles on ``df`` degrees of
    freedom (normal quantiles for ``df`` infinite): 1 for one interval,
    1.14 for two at large df, 1.43 for two on 2 df.

    Returns
    -------
    float
    """
    if k <= 1:
        return 1.0
    joint = level ** (1.0 / k)
    return float(stats.t.ppf(0.5 + joint / 2, df) / stats.t.ppf(0.5 + level / 2, df))


def holm(pvalues: ArrayLike) -> NDArray[np.float64]:
    """Holm step-down adjusted p-values (family-wise error control)."""
    p = np.asarray(pvalues, float)
    order = np.argsort(p)
    m = p.size
    adj = np.minimum(1.0, np.maximum.accumulate((m - np.arange(m)) * p[order]))
    out = np.empty_like(adj)
    out[order] = adj
    return out
