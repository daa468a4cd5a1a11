"""Restitution that drifts test after test within a series (a family of the scale, issue 12).

e = c e_an exp(d (n - 1/2)), n the test's place in the series from 0
(first) to 1 (last): hinge wear, or mortar debris gathering between tests
(the paper blames debris for the scatter of theta0/alpha).  Its member
d = 0 is the listed scale (:mod:`rocklab.diagnosis.causes.restitution_scale`).
The place may also be that of a column of the test log (a date, a time, a
value the operator wrote: :func:`along_log`): one family per column,
``restitution_drift[<column>]``, n the test's value between the series'
least (0) and largest (1), so that the engine chooses what the drift
follows as it chooses between causes.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from rocklab._imports import lazy_module
from rocklab.diagnosis.causes import Cause, Signature, restitution_scale
from rocklab.diagnosis.parameters import Param
from rocklab.lab.hierarchy import MIN_DF
from rocklab.physics.law import Restitution

if TYPE_CHECKING:
    from rocklab.diagnosis.evidence import MeasuredTest, Observed

stats = lazy_module("scipy.stats")

D = Param("drift", -1.0, 1.0, 0.0, practical=0.005)
NAME = "restitution_drift"
#: A drift is a slope over tests: the test is its unit, and the slope of n per-test medians has n - 2 degrees
#: of freedom, of which a verdict needs :data:`rocklab.lab.hierarchy.MIN_DF` (with three tests the 95 % t
#: quantile is 12.7: no drift of the lab's size can clear it).
MIN_TESTS = MIN_DF + 2


def column_of(name: str) -> str | None:
    """The test log's column a drift named ``name`` follows (None: the test order, or no drift): the
    reading of a name, for :func:`rocklab.diagnosis.catalogue.by_name` alone (a cause says it as
    :attr:`~rocklab.diagnosis.causes.Cause.log_column`)."""
    if name.startswith(f"{NAME}[") and name.endswith("]"):
        return name[len(NAME) + 1 : -1]
    return None


def _place(tests: Sequence[MeasuredTest], column: str | None) -> np.ndarray:
    """n of each test: its place in the series, or in the range of a column of the test log
    (of a model: :meth:`rocklab.diagnosis.wall_model.ModelParams.place`)."""
    return np.array([t.order if column is None else t.log[column] for t in tests], float)


def _cause(column: str | None, others: Sequence[str] = ()) -> Cause:
    def laws(v: Mapping[str, float]) -> tuple[Restitution]:
        return (Restitution(v["c"], drift=v["drift"], along=column),)

    what = "the test's place in the series" if column is None else f"the test's value of {column} in the test log"

    def signature(ob: Observed) -> Signature | None:
        """The per-test median of the measured e/e_an against n."""
        med = np.array([np.median(ob.ratio[i][ob.ok[i]]) if ob.ok[i].any() else np.nan for i in range(len(ob.tests))])
        order = _place(ob.tests, column)
        ok = np.isfinite(med)
        if ok.sum() < MIN_TESTS or np.ptp(order[ok]) == 0:
            return None
        fit = stats.linregress(order[ok], np.log(med[ok]))
        return {
            "value": float(fit.slope),
            "supports": bool(fit.pvalue < 0.01 and abs(fit.slope) > D.practical),
            "text": f"log of the per-test median e/e_an against {what}: slope "
            f"{fit.slope:+.4f} over the series (p = {fit.pvalue:.2g}, {ok.sum()} tests)",
        }

    name = NAME if column is None else f"{NAME}[{column}]"

    def starts(sig: Mapping[str, Signature]) -> dict[str, float]:
        return {"drift": sig.get(name, {}).get("value", 0.0)} if column is None else {}

    def closed_form(values: Mapping[str, float], ci: Mapping[str, Sequence[float]]) -> str:
        if CAUSE.holds(ci, "drift", 0.0):
            return "restitution_scale: e = c e_an, no drift"
        return "no closed form of the library"

    n = f"n the test's {column} (0 to 1 over the series)" if column else "n the test's place in the series (0 to 1)"
    return Cause(
        name=name,
        law=f"e = c e_an exp(d (n - 1/2)), {n}",
        params=(restitution_scale.C, D),
        laws=laws,
        signature=signature,
        starts=starts,
        replaces=(restitution_scale.CAUSE.name, *(o for o in others if o != name)),
        family=restitution_scale.CAUSE.name,
        closed_form=closed_form,
        short="drift",
        drifts=True,
        log_column=column,
        not_identifiable=too_few_tests,
    )


def too_few_tests(ob: Observed) -> str:
    """Why the tests of a series cannot carry a drift between them ("" where they can)."""
    n = len(ob.tests)
    return f"a drift is a slope over tests and needs {MIN_TESTS} of them, the series has {n}" if n < MIN_TESTS else ""


@lru_cache(maxsize=64)
def along_log(columns: tuple[str, ...]) -> tuple[Cause, ...]:
    """The drifts along each column of the test log ``columns`` (a tuple), each replacing the other drifts."""
    names = (NAME, *(f"{NAME}[{c}]" for c in columns))
    return tuple(_cause(c, names) for c in columns)


CAUSE = _cause(None)
