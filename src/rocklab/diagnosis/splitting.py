"""Sample splitting of a long series: its model chosen on some tests, estimated on the others.

A series' diagnosis is one joint fit over all its tests, and the selection
of its causes (:func:`~rocklab.diagnosis.estimation.selection.select_effects`,
the search beyond the catalogue, the stand-ins and rivals) refits the
series some forty times: its cost grows with the tests.  Above
:data:`SPLIT_CAP` tests the series is split (:func:`split_series`): the
causes are chosen on at most that many tests spread over it, and the chosen
model's parameters and intervals are estimated on the others
(:func:`estimated`).  The tests that estimate the parameters took no part in
choosing them, so their estimate and its interval carry no selection
effect: the interval of a cause named because its interval on the same
tests cleared its null would be too short and its estimate too far from the
null (Cox 1975, "A note on data-splitting for the evaluation of significance
levels", Biometrika 62:441; Wasserman & Roeder 2009, "High-dimensional
variable selection", Ann. Stat. 37:2178).  What is lost is the selection's
power on the tests it leaves: a cause is named on :data:`SPLIT_CAP` tests,
which name at least what the series of that size do.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, TypeVar, cast

import numpy as np

from rocklab.diagnosis.estimation.fitting import fit
from rocklab.diagnosis.estimation.resampling import parameter_intervals

if TYPE_CHECKING:
    from rocklab.diagnosis.estimation.problem import Problem
    from rocklab.diagnosis.estimation.selection import Selection

T = TypeVar("T")

#: Tests of a series above which its causes are chosen on this many of them and estimated on the others
#: (:func:`split_series`).  At least the longest series whose results must stay as they were: those of
#: the embedded campaign (29 tests), of the discovery bench (at most 10) and of the scale bench's 614-test
#: campaign (93); a series ten times longer is then chosen at the cost of one of about a hundred tests,
#: and its job does not grow with the campaign but for the fits of its estimation.
SPLIT_CAP = 100


def spread_over(tests: Sequence[T], at_most: int) -> list[T]:
    """At most ``at_most`` of ``tests`` (in series order), evenly spread from the first to the last;
    all of them where there are no more."""
    return [tests[i] for i in _spread(len(tests), at_most)]


def _spread(n: int, at_most: int) -> np.ndarray:
    """The positions of :func:`spread_over` among ``n`` tests."""
    if n <= at_most:
        return np.arange(n)
    return np.unique(np.round(np.linspace(0, n - 1, at_most)).astype(int))


def split_series(tests: Sequence[T], cap: int = SPLIT_CAP) -> tuple[list[T], list[T]]:
    """The tests that choose a series' model and those that estimate it.

    At most ``cap`` tests spread over the series (:func:`spread_over`: a drift or a change of the wall
    state over the series is in both halves), and the others, each in series order; both are all the
    tests where there are no more than ``cap`` (no split).  Deterministic: the same tests give the same
    halves.
    """
    chosen = _spread(len(tests), cap)
    if chosen.size == len(tests):
        return list(tests), list(tests)
    rest = np.setdiff1d(np.arange(len(tests)), chosen)
    return [tests[i] for i in chosen], [tests[i] for i in rest]


def estimated(problem: Problem[Any], sel: Selection, *, n_boot: int = 40, seed: int = 0) -> Selection:
    """``sel`` (chosen on other tests) with its model fitted on ``problem``'s tests, and their intervals.

    The fit starts warm from the selection's parameters (:func:`~rocklab.diagnosis.estimation.fitting.fit`
    with ``x0``): the same model of the same wall, a few steps away on independent tests (on the 821
    estimation tests of the scale bench's 921-test series 5c-2s it ends 5 units of -2 log L below a cold
    start, at a third of its cost).  The intervals
    are those of the selection's fit (:func:`~rocklab.diagnosis.estimation.resampling.parameter_intervals`:
    the bootstrap over tests, the systematic part of the residual groups).  What decides (the causes,
    their held-out gains, what is rejected and why) stays the selection's.
    """
    f = fit(problem, np.arange(problem.n_tests), sel["fit"].ext, x0=sel["fit"].values)
    return cast("Selection", {**sel, "fit": f, "ci": parameter_intervals(problem, f, n_boot=n_boot, seed=seed)})
