"""The tables of docs/reproducibility.md: the published numbers under other floating-point
environments (``bench/environments.py``, :func:`rocklab.benchmarks.performance_summary`)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rocklab.report.format import markdown_table, show


def _environments(n: Mapping[str, Any]) -> Any:
    return (n.get("performance") or {}).get("environments")


NOT_RUN_ENVIRONMENTS = (
    "Not measured: `bench/environments.py` has not run on these results (`results/bench/environments.json`)."
)


def environment_sections(n: Mapping[str, Any]) -> str:
    """Per section of the numbers file: its floats, how many moved between environments, the nearest to tolerance."""
    env = _environments(n)
    if env is None:
        return NOT_RUN_ENVIRONMENTS
    rows = [
        [f"`{name}`", show(s["n_floats"]), show(s["n_moved"]), show(s["max_headroom"], ".2f"), show(s["n_beyond"])]
        for name, s in env["sections"].items()
    ]
    header = ["section", "floats", "moved", "largest move / its tolerance", "beyond it"]
    return markdown_table(header, rows)


def _tolerance(tol: Mapping[str, Any] | None) -> str:
    if tol is None:
        return "none declared"
    parts = [
        f"{show(tol['abs'], '.3g')}" if tol["abs"] else "",
        f"{show(tol['rel'], '.3g')} × value" if tol["rel"] else "",
    ]
    return " + ".join(p for p in parts if p) or "exact"


def environment_moves(n: Mapping[str, Any]) -> str:
    """The numbers that came nearest their tolerance: their value in each environment, spread and tolerance."""
    env = _environments(n)
    if env is None:
        return NOT_RUN_ENVIRONMENTS
    names = env["runs"]
    rows = [
        [
            f"`{m['number']}`",
            *(show(m["values"].get(e), ".6g") for e in names),
            show(m["spread"], ".3g"),
            _tolerance(m["tolerance"]),
            show(m["headroom"], ".2f"),
        ]
        for m in env["nearest"]
    ]
    return markdown_table(["number", *names, "spread", "tolerance", "spread / tolerance"], rows)
