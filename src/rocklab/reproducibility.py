"""Floating-point environments, and how far the published numbers move between them.

Two x86-64 machines run the same code on other kernels: NumPy dispatches its
loops on the SIMD features of the CPU (SSE4.2, AVX2, AVX-512), OpenBLAS picks
its kernels by CPU family and splits its work over threads, and numba
compiles for the host CPU (vector width, fused multiply-adds). A result
differs in its last bits, and a chaotic computation (a rocking history near
an overturning boundary, a fit that stops by a tolerance) carries those bits
into digits a page prints.

:data:`ENVIRONMENTS` are machines of this kind that one machine can play:
each is a set of environment variables that changes those kernels for every
process of a run (Snakemake's jobs inherit them). :func:`moves` compares the
numbers of runs under several of them (``rocklab.report.pages.docs_numbers``),
number by number, against the tolerance each stage declares
(``rocklab.summaries``). ``bench/environments.py`` measures the spread on the
embedded campaign, docs/reproducibility.md shows it, and
``tests/test_environments.py`` reruns the workflow under
:data:`SECOND_ENVIRONMENT` and checks every number of the committed pages.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rocklab import summaries

#: NumPy's dispatched SIMD targets above its x86-64-v2 baseline (``numpy._core._multiarray_umath.__cpu_dispatch__``):
#: disabled, every loop runs its SSE4.2 kernel; a name the machine lacks is ignored.
_NUMPY_ABOVE_BASELINE = "X86_V3 X86_V4 AVX512_ICL AVX512_SPR"

#: Environments one machine can play, by name: the variables set for every
#: process of a run. ``native`` is the machine as it is; ``generic`` an
#: x86-64 of 2008 (SSE4.2, no AVX, no FMA: numba's generic CPU, NumPy's
#: baseline kernels, OpenBLAS's Nehalem kernels on one thread); ``avx2`` a
#: laptop of 2013-2020 (AVX2 and FMA, no AVX-512: Haswell for numba and
#: OpenBLAS, NumPy's x86-64-v3 kernels, two BLAS threads).
ENVIRONMENTS: dict[str, dict[str, str]] = {
    "native": {},
    "generic": {
        "NUMBA_CPU_NAME": "generic",
        "NPY_DISABLE_CPU_FEATURES": _NUMPY_ABOVE_BASELINE,
        "OPENBLAS_CORETYPE": "Nehalem",
        "OPENBLAS_NUM_THREADS": "1",
        "OMP_NUM_THREADS": "1",
    },
    "avx2": {
        "NUMBA_CPU_NAME": "haswell",
        "NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512_ICL AVX512_SPR",
        "OPENBLAS_CORETYPE": "Haswell",
        "OPENBLAS_NUM_THREADS": "2",
        "OMP_NUM_THREADS": "2",
    },
}
#: The environment the workflow test reruns the embedded campaign under: the
#: farthest from any machine that runs the tests today.
SECOND_ENVIRONMENT = "generic"


def environment(
    name: str, numba_cache: str | os.PathLike[str] | None = None, base: Mapping[str, str] | None = None
) -> dict[str, str]:
    """The process environment of a run under ``ENVIRONMENTS[name]``.

    ``numba_cache``: a folder for numba's compiled kernels (``NUMBA_CACHE_DIR``),
    so that kernels compiled for another CPU do not join the checkout's
    cache. ``base``: the environment to start from (``os.environ``).
    """
    if name not in ENVIRONMENTS:
        raise KeyError(f"no floating-point environment {name!r}: one of {', '.join(ENVIRONMENTS)}")
    env = {**(os.environ if base is None else base)}
    for key in {k for e in ENVIRONMENTS.values() for k in e}:
        env.pop(key, None)
    env.update(ENVIRONMENTS[name])
    if numba_cache is not None:
        env["NUMBA_CACHE_DIR"] = str(Path(numba_cache))
    return env


@dataclass(frozen=True)
class Move:
    """One published number under several environments.

    ``values``: environment -> value (``None`` where it was not measured);
    ``spread``: the largest absolute difference between two of them;
    ``tolerance``: what its stage declares (None: undeclared); ``admitted``:
    whether every pair of values lies within it.
    """

    section: str
    path: str
    values: dict[str, Any]
    spread: float
    tolerance: summaries.Tolerance | None
    admitted: bool

    @property
    def key(self) -> str:
        """The number's dotted path in the numbers file, section first."""
        return f"{self.section}.{self.path}"

    @property
    def headroom(self) -> float | None:
        """The spread over what the tolerance admits at the smallest value (1: at the edge), None if undeclared."""
        if self.tolerance is None:
            return None
        floats = [v for v in self.values.values() if isinstance(v, (int, float))]
        allowed = self.tolerance.abs + self.tolerance.rel * min(abs(v) for v in floats)
        return self.spread / allowed if allowed > 0 else (0.0 if self.spread == 0 else float("inf"))


def moves(
    numbers: Mapping[str, Mapping[str, Any]], tolerances: Mapping[str, Mapping[str, summaries.Tolerance]]
) -> list[Move]:
    """Every number that differs between the runs of ``numbers`` (environment ->
    numbers file), section by section (``tolerances``: section -> its
    stage's tolerances), in order of section and path.

    A text or count that differs is a move too (spread NaN, never admitted):
    only floats may move. A run without a section (its stage did not run)
    is left out of that section's comparison.
    """
    out = []
    for section, tol in tolerances.items():
        # an environment whose run did not make the section (a stage it did not run) says nothing of it
        trees = {e: dict(summaries.leaves(n[section])) for e, n in numbers.items() if n.get(section) is not None}
        envs = list(trees)
        for path in sorted(set().union(*(t.keys() for t in trees.values()))):
            # a leaf of a summary: a number, a text, a list's item, None (not measured or not in this run)
            values: dict[str, Any] = {e: trees[e].get(path) for e in envs}
            distinct = {repr(v) for v in values.values()}
            if len(distinct) == 1:
                continue
            floats = [v for v in values.values() if isinstance(v, float)]
            numeric = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values.values())
            declared = summaries.tolerance(path, tol) if floats else None
            spread = max(floats) - min(floats) if numeric and floats else float("nan")
            admitted = (
                numeric
                and declared is not None
                and all(declared.admits(a, b) for a in values.values() for b in values.values())
            )
            out.append(Move(section, path, values, spread, declared, admitted))
    return out
