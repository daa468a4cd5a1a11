"""What a design can show: the smallest p-value its test reaches on the units it has.

A rank test of few units has a floor: however far apart the groups, its
p-value cannot fall below what the arrangement of ranks wholly apart gives.
Below the level of a test that floor makes its p no evidence either way: 3
walls of one material against 2 of another reach p = 0.083 at best
(Kruskal-Wallis, its chi-square law; 0.2 by the exact permutation law), so a
p of 1.00 there is no absence of an effect.  Such a row is not testable
(:class:`rocklab.inference.verdicts.ClaimVerdict`), not a p.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np

from rocklab._imports import lazy_module

stats = lazy_module("scipy.stats")

#: Groups a floor is computed for, at most (every order of the groups is tried).
MAX_GROUPS = 8


def smallest_kruskal_p(sizes: Sequence[int]) -> float:
    """The smallest p-value of the Kruskal-Wallis test on groups of ``sizes`` units [-].

    The test as :func:`scipy.stats.kruskal` makes it: H = 12 / (N (N + 1))
    sum R_i^2 / n_i - 3 (N + 1) (Kruskal & Wallis 1952), R_i the rank sum of
    group i of n_i units of N, against chi-square on k - 1 degrees of freedom.
    H is largest with no ties and the groups wholly apart, in the order of
    ranks that makes it largest: every order of the groups is tried.

    Parameters
    ----------
    sizes : sequence of int
        Units in each group (two groups at least).

    Returns
    -------
    float
        The p-value of that largest H.
    """
    n = np.asarray(sizes, int)
    if n.size < 2 or n.size > MAX_GROUPS or np.any(n < 1):
        raise ValueError(f"group sizes {list(sizes)}: 2 to {MAX_GROUPS} groups of one unit or more")
    N = int(n.sum())
    best = 0.0
    for order in itertools.permutations(range(n.size)):
        m = n[list(order)]
        last = np.cumsum(m)
        # the ranks first - n_i + 1 .. first of a group sum to n_i (2 last - n_i + 1) / 2
        R = m * (2 * last - m + 1) / 2.0
        best = max(best, 12.0 / (N * (N + 1)) * float(np.sum(R**2 / m)) - 3.0 * (N + 1))
    return float(stats.chi2.sf(best, n.size - 1))
