"""The numbers of the committed pages hold on another machine: the main job rerun under a
second floating-point environment (rocklab.reproducibility) gives every number within the
tolerance its stage declares."""

import subprocess
import sys
from pathlib import Path

import pytest

from rocklab.report import pages
from rocklab.reproducibility import SECOND_ENVIRONMENT, environment

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
pytestmark = pytest.mark.skipif(not SNAKEMAKE.exists(), reason="snakemake not installed beside this interpreter")


def test_the_committed_numbers_hold_under_a_second_floating_point_environment(tmp_path):
    """The main job's numbers on the embedded campaign (maps, calibrated maps, diagnosis, every
    fit and every numba kernel) on kernels other than the machine's own: every number of
    docs/numbers.json within its stage's tolerance (bench/environments.py measures the spread).
    Its targets are the stages' summaries, what the numbers are made of: the figures and the
    report, which print none, are left out (a third of the run's jobs)."""
    results = tmp_path / "results"
    targets = [str(path) for name, path in pages.summary_paths(results).items() if name not in pages.VOLATILE]
    cmd = [str(SNAKEMAKE), *targets, "--cores", "2", "--quiet", "--snakefile", str(ROOT / "Snakefile")]
    cmd += ["--directory", str(tmp_path), "--config", f"raw_dir={ROOT / 'raw' / 'campaign'}", f"results_dir={results}"]
    env = environment(SECOND_ENVIRONMENT, numba_cache=tmp_path / "numba-cache")
    run = subprocess.run(cmd, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=1500)
    assert run.returncode == 0, run.stderr[-3000:]
    diff = pages.differences(pages.docs_numbers(results), pages.read_numbers(ROOT / "docs" / "numbers.json"))
    assert not diff, f"{len(diff)} numbers beyond their stage's tolerance:\n" + "\n".join(diff[:40])
