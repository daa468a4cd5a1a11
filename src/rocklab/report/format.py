"""How a page prints one value of the numbers file, and a table of them."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

from jinja2 import Undefined

#: What a page says for a quantity the results do not hold.
NOT_MEASURED = "not measured"


def show(value: Any, spec: str = "") -> str:
    """One value as a page prints it.

    ``None`` (a quantity the stage did not measure) reads :data:`NOT_MEASURED`,
    a list its items joined by commas ("none" when empty), a boolean "yes" or
    "no", a number in Python's format mini-language ``spec`` (``g`` by default).
    A value that the numbers file does not hold (Jinja's undefined) is printed
    by its own rule: an error when the page is rendered strictly.
    """
    if isinstance(value, Undefined):
        return str(value)
    if value is None:
        return NOT_MEASURED
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, list):
        return ", ".join(show(v, spec) for v in value) or "none"
    if isinstance(value, str):
        return value
    return format(value, spec) if spec else format(value, "g")


def _row(cells: Iterable[str]) -> str:
    return "| " + " | ".join(cells) + " |"


def markdown_table(header: Sequence[str], rows: Iterable[Iterable[str]]) -> str:
    """A markdown table of strings."""
    return "\n".join([_row(header), _row(["---"] * len(header)), *(_row(r) for r in rows)])
