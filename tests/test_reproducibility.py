"""Floating-point environments and the moves of the published numbers between them (rocklab.reproducibility)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from rocklab import summaries
from rocklab.report import pages
from rocklab.reproducibility import ENVIRONMENTS, SECOND_ENVIRONMENT, environment, moves
from rocklab.summaries import LAST_DIGIT, Tolerance

ROOT = Path(__file__).resolve().parents[1]
TOLERANCES = {"maps": {"*.N_O": Tolerance(abs=0.002), "*": LAST_DIGIT}, "qc": {"*": LAST_DIGIT}}


def test_the_environment_reaches_every_process(tmp_path):
    """numba compiles for the generic CPU and NumPy's SIMD kernels above its baseline are off, in a
    child process as in Snakemake's jobs; each environment replaces the variables of another."""
    probe = """
import json, numba
from numpy._core import _multiarray_umath as m
print(json.dumps({"numba": numba.config.CPU_NAME, "x86_v3": m.__cpu_features__["X86_V3"]}))
"""
    base = {"PATH": "/usr/bin", **ENVIRONMENTS["avx2"]}
    env = environment(SECOND_ENVIRONMENT, numba_cache=tmp_path, base=base)
    run = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True, check=True)
    assert json.loads(run.stdout) == {"numba": "generic", "x86_v3": False}
    assert env["OPENBLAS_CORETYPE"] == "Nehalem" and env["NUMBA_CACHE_DIR"] == str(tmp_path)
    assert "NUMBA_CPU_NAME" not in environment("native", base=base)
    with pytest.raises(KeyError, match="no floating-point environment 'sse'"):
        environment("sse")


def test_moves_are_the_numbers_that_differ_each_against_its_tolerance():
    a = {"maps": {"A": {"N_O": 0.5, "scatter": 0.2, "n": 3}}, "qc": {"x": 1.0}}
    b = {"maps": {"A": {"N_O": 0.501, "scatter": 0.20001, "n": 3}}, "qc": {"x": 1.0}}
    c = {"maps": {"A": {"N_O": 0.4995, "scatter": 0.2, "n": 4}}, "qc": None}
    found = {m.key: m for m in moves({"one": a, "two": b, "three": c}, TOLERANCES)}
    assert set(found) == {"maps.A.N_O", "maps.A.scatter", "maps.A.n"}
    n_o = found["maps.A.N_O"]
    assert n_o.spread == pytest.approx(0.0015) and n_o.admitted and n_o.headroom == pytest.approx(0.75)
    assert not found["maps.A.scatter"].admitted  # beyond the last digit kept
    assert not found["maps.A.n"].admitted  # a count may not move
    # a run that did not make a section is left out of it
    assert "qc.x" not in found


@pytest.mark.parametrize("section", sorted(pages.SECTIONS))
def test_every_float_of_the_pages_has_a_tolerance_its_stage_declares(section):
    """No float is compared digit for digit by default: the stage that makes it says how far
    two machines may take it apart (rocklab.summaries, docs/reproducibility.md)."""
    numbers = pages.read_numbers(ROOT / "docs" / "numbers.json")[section]
    assert numbers is not None, f"docs/numbers.json has no {section}: run `make docs` after the stage"
    missing = summaries.undeclared(numbers, pages.SECTIONS[section])
    assert not missing, f"floats of {section} whose stage declares no tolerance: {missing[:20]}"
