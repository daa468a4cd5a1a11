"""Deferred imports (rocklab._imports): what a job that only reads the catalogue pays."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from rocklab._imports import lazy_module


def _run(code):
    """Run ``code`` in a fresh interpreter (nothing imported yet) and return its stdout."""
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, check=True)
    return out.stdout.strip()


def test_the_catalogue_and_the_calibrated_walls_load_no_scipy_until_used():
    # what Snakemake's own process and the calibrated map jobs import
    out = _run(
        """
        import sys
        from rocklab.diagnosis.catalogue import CAUSES, by_name
        from rocklab.seismic import calibrated
        from rocklab.simulation.reference import simulate_free
        params = {q.name for c in CAUSES for q in by_name(c.name).params}
        heavy = ["scipy.stats._stats_py", "scipy.optimize._optimize", "scipy.signal._savitzky_golay",
                 "scipy.integrate._ivp"]
        print(sorted(m for m in heavy if m in sys.modules), len(params) > 0)
        """
    )
    assert out == "[] True"


def test_a_lazy_module_loads_on_first_use_and_is_the_imported_one():
    out = _run(
        """
        import sys
        from rocklab._imports import lazy_module
        stats = lazy_module("scipy.stats")
        before = "scipy.stats._stats_py" in sys.modules
        value = stats.norm.ppf(0.975)
        import scipy.stats
        from scipy.stats import norm
        print(before, "scipy.stats._stats_py" in sys.modules, round(value, 4), scipy.stats is stats, norm is stats.norm)
        """
    )
    assert out == "False True 1.96 True True"


def test_a_module_already_imported_is_returned_as_it_is():
    assert lazy_module("numpy") is np


def test_a_missing_module_is_named():
    with pytest.raises(ModuleNotFoundError, match="no_such_module"):
        lazy_module("no_such_module")
