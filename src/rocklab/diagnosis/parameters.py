"""The parameter of a cause: a leaf that causes, the estimation engine and the fits import.

It imports nothing of rocklab, so a cause module needs no engine to declare
its parameters.
"""

from __future__ import annotations

from typing import NamedTuple


class Param(NamedTuple):
    """A parameter of a cause: bounds of the fit, null value (the cause absent),
    and the smallest departure from the null worth naming the cause for (a
    parameter whose 95 % interval stays closer to the null than this is no
    cause; None: the parameter alone never names it)."""

    name: str
    lower: float
    upper: float
    null: float
    practical: float | None = None
