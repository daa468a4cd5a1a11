"""What the estimation engine fits: the base class of a problem.

A problem hands the engine its tests, its residual groups (log ratios,
model over measured), the noise covariate of each residual and its
candidate causes (objects with ``name``, ``params``
(:class:`rocklab.diagnosis.parameters.Param`) and ``replaces``); the engine
knows nothing of walls.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from typing import TYPE_CHECKING, Generic, TypeVar

import numpy as np

if TYPE_CHECKING:
    from rocklab.diagnosis.causes import Cause
    from rocklab.diagnosis.parameters import Param
    from rocklab.diagnosis.result import Structure

#: What a problem's :meth:`Problem.subset` gives: its tests, as the problem holds them.
Sub = TypeVar("Sub")


class Problem(Generic[Sub]):
    """A set of tests and the residual groups of models over them.

    Subclasses set ``causes`` (the candidates, in the order they are
    reported when tied, each with ``name``, ``params`` and ``replaces``) and
    define :meth:`residuals` (group -> (tests, k) arrays for a subset made by
    :meth:`subset`), :meth:`noise`, :meth:`starts` (data-driven starting
    values) and, optionally, :meth:`heldout_measures` and :meth:`covariates`.
    """

    n_tests: int
    causes: tuple[Cause, ...] = ()

    def subset(self, idx: np.ndarray) -> Sub:
        raise NotImplementedError

    def residuals(self, sub: Sub, ext: Collection[str], values: Mapping[str, float]) -> dict[str, np.ndarray]:
        raise NotImplementedError

    def residuals_at(
        self, sub: Sub, ext: Collection[str], values: Sequence[Mapping[str, float]]
    ) -> list[dict[str, np.ndarray]]:
        """:meth:`residuals` at each set of parameter ``values``, in order: the points of a
        finite-difference Jacobian.  A subclass whose evaluation is dominated by its fixed cost
        evaluates them together; the results are those of :meth:`residuals`, value for value."""
        return [self.residuals(sub, ext, v) for v in values]

    def candidates(self, families: bool = False) -> list[str]:
        """Names of the candidate causes (the listed ones; with ``families``, the generalised families too)."""
        return [c.name for c in self.causes if families or not getattr(c, "family", None)]

    def starts(self, ext: Collection[str]) -> dict[str, float]:
        return {}

    def heldout_measures(self, sub: Sub, ext: Collection[str], values: Mapping[str, float]) -> dict[str, np.ndarray]:
        return {}

    def covariates(self, sub: Sub) -> dict[str, dict[str, np.ndarray]]:
        """Group -> {label: array like its residuals} for the structure tests."""
        return {}

    def noise(self, sub: Sub) -> dict[str, np.ndarray]:
        """Noise covariate (threshold over amplitude) of every residual of :meth:`residuals`."""
        raise NotImplementedError

    def extra_structure(self, sub: Sub, ext: Collection[str], values: Mapping[str, float]) -> list[Structure]:
        """Structure outside the residual groups (list of statements)."""
        return []

    def form_structure(self, ext: Collection[str]) -> list[Structure]:
        """Fit-free evidence that a cause of ``ext`` has the wrong form (list of statements)."""
        return []

    def resolution(self, x: np.ndarray) -> float:
        """Typical resolution [log units] of a group from its noise covariates ``x``."""
        return float(np.median(x))

    def params(self, ext: Collection[str]) -> list[Param]:
        """The :class:`~rocklab.diagnosis.parameters.Param` of the causes ``ext`` this problem can see, in order."""
        return [q for c in self.causes if c.name in ext for q in c.params]

    def combine(self, current: Sequence[str], eff: str) -> tuple[str, ...] | None:
        """The causes ``current`` plus ``eff`` in catalogue order, less those ``eff``
        replaces; None where a cause of ``current`` replaces ``eff``."""
        by_name = {c.name: c for c in self.causes}
        if any(eff in by_name[c].replaces for c in current):
            return None
        new = (set(current) | {eff}) - set(by_name[eff].replaces)
        return tuple(c.name for c in self.causes if c.name in new)
