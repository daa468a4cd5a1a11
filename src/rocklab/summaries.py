"""What each stage publishes for the documentation: its summary file.

Each stage of the workflow writes, beside its tables, the numbers the docs
quote of them (``results/summaries/<stage>.json``): a nested dictionary made
by the stage's own summary function (``rocklab.lab.qc_summary``,
``rocklab.dissipation.dissipation_summary``, ``rocklab.diagnosis.diagnosis_summary``,
``rocklab.seismic.maps_summary``, ``rocklab.shake_table.shake_table_summary``,
``rocklab.benchmarks``). A quantity that the stage does not hold is ``None``
(the pages say "not measured").

Floats are kept to :data:`SIGNIFICANT` significant digits, enough for any
number a page prints, so that a file reads well and two files compare.
Two summaries of the same stage agree when every number is within the
tolerance that the stage declares for it (:func:`differences`). Every float
has one, declared beside the function that makes it (the stage's
``TOLERANCES``): :data:`LAST_DIGIT` for a float that floating point only
rounds, a wider one for a chaotic computation such as the overturning maps,
from the spread measured between floating-point environments
(``bench/environments.py``, docs/reproducibility.md); a float without one is
an error of its stage (:func:`undeclared`), never compared digit for digit.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator, Mapping
from fnmatch import fnmatchcase
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from rocklab.disk import write_text

#: Significant digits kept of every float.
SIGNIFICANT = 6


def number(x: Any) -> float | int | bool | None:
    """A float kept to :data:`SIGNIFICANT` digits, an int as is, NaN as ``None``."""
    if x is None:
        return None
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    x = float(x)
    if not math.isfinite(x):
        return None
    return float(f"{x:.{SIGNIFICANT}g}")


def rounded(x: Any) -> Any:
    """``x`` with every number passed through :func:`number`, mappings with text keys."""
    if isinstance(x, Mapping):
        return {str(k): rounded(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [rounded(v) for v in x]
    if isinstance(x, str):
        return x
    return number(x)


def dumps(tree: Any) -> str:
    """A summary's text: sorted keys, so that a change shows as a diff."""
    return json.dumps(tree, indent=1, sort_keys=True, ensure_ascii=False) + "\n"


def write_summary(summary: Any, path: str | Path) -> None:
    """Write a stage's summary (:func:`rounded`) as JSON at ``path``."""
    write_text(path, dumps(rounded(summary)))


def read_summary(path: str | Path) -> Any:
    """A summary file, or ``None`` where the stage did not run (no file)."""
    path = Path(path)
    return json.loads(path.read_text()) if path.is_file() else None


class Tolerance(NamedTuple):
    """How far two runs may take a quantity apart: ``|new - old| <= abs + rel * |old|``."""

    abs: float = 0.0
    rel: float = 0.0

    def admits(self, new: float, old: float) -> bool:
        # a few units of the last bit beyond the bound: one unit of the sixth
        # digit, 1.00001 - 1.0, is itself a float a hair above 1e-5
        return abs(new - old) <= (self.abs + self.rel * abs(old)) * (1 + 1e-9)


#: A float that floating point cannot move: a setting, a constant of the
#: paper, a count or a ratio of counts (one correctly rounded division).
EXACT = Tolerance()
#: One unit of the last digit kept (:data:`SIGNIFICANT`): a float computed
#: in floating point may differ in its last bits between two machines (other
#: SIMD kernels of NumPy and OpenBLAS, other code from numba), which rounds
#: it to either neighbour of its kept digits. The least a computed float is
#: held to.
LAST_DIGIT = Tolerance(rel=10.0 ** (1 - SIGNIFICANT))


def tolerance(path: str, tolerances: Mapping[str, Tolerance]) -> Tolerance | None:
    """The tolerance of the quantity at the dotted ``path`` of a summary: that of
    the first pattern of ``tolerances`` (:func:`fnmatch.fnmatchcase`, ``*``
    spans dots) that matches it; None where none does (an undeclared float
    is an error of the stage that made it, :func:`undeclared`)."""
    return next((tol for pattern, tol in tolerances.items() if fnmatchcase(path, pattern)), None)


def leaves(tree: Any, path: str = "") -> Iterator[tuple[str, Any]]:
    """Every (dotted path, value) of a summary that is not a mapping or a list."""
    if isinstance(tree, Mapping):
        for k, v in tree.items():
            yield from leaves(v, f"{path}.{k}")
    elif isinstance(tree, list):
        for k, v in enumerate(tree):
            yield from leaves(v, f"{path}.{k}")
    else:
        yield path.lstrip("."), tree


def undeclared(summary: Any, tolerances: Mapping[str, Tolerance]) -> list[str]:
    """Dotted paths of the floats of ``summary`` whose stage declares no tolerance."""
    return [p for p, v in leaves(summary) if isinstance(v, float) and tolerance(p, tolerances) is None]


def differences(a: Any, b: Any, tolerances: Mapping[str, Tolerance] = {}, path: str = "") -> list[str]:
    """Dotted paths where the summaries ``a`` (new) and ``b`` (old) differ
    beyond the tolerance of the quantity (:func:`tolerance`), and the floats
    whose stage declares none (compared at no tolerance at all: each such
    float is reported, equal or not). A count (an integer) and a text are
    exact whatever the tolerances say."""
    if isinstance(a, Mapping) and isinstance(b, Mapping):
        return [d for k in sorted(set(a) | set(b)) for d in differences(a.get(k), b.get(k), tolerances, f"{path}.{k}")]
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        return [
            d for k, (x, y) in enumerate(zip(a, b, strict=True)) for d in differences(x, y, tolerances, f"{path}.{k}")
        ]
    key = path.lstrip(".")
    measured = isinstance(a, float) or isinstance(b, float)
    numeric = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (a, b))
    declared = tolerance(key, tolerances)
    if measured and declared is None:
        return [f"{key}: a float with no declared tolerance ({b!r} committed, {a!r} from the results)"]
    if a == b or (measured and numeric and declared is not None and declared.admits(a, b)):
        return []
    return [f"{key}: {b!r} committed, {a!r} from the results"]
