"""Interrupted and repeated runs of the workflow give the results of one uninterrupted run.

A tiny virtual-lab campaign and one small overturning map per model, up to
the tables of every stage (no figure).  Tables (CSV, JSON) must be
byte-identical; netCDF files identical in content, the attributes of
:data:`VOLATILE` aside: they record when a file was written and how long
it took, not what it holds.
"""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import psutil
import pytest
import xarray as xr

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")

pytest.importorskip("rocklab.simulation.model")
pytestmark = pytest.mark.skipif(not SNAKEMAKE.exists(), reason="snakemake not installed beside this interpreter")
from rocklab.lab import virtual_lab  # noqa: E402
from rocklab.lab.motion import MOTION_GROUP  # noqa: E402

CONFIG = {
    "figures": {"fig9_specimen": "1a"},
    "maps": {"records": ["Pac164"], "n": 5},
    "diagnosis": {"n_boot": 4, "n_history": 1},
}
#: The tables of every stage: reduction, QC, dissipation, diagnosis, maps.
TABLES = ["qc.csv", "kinematics.csv", "tests.csv", "series.csv", "impacts.csv", "diagnosis.json", "maps/summary.csv"]
#: netCDF attributes that differ from run to run: the time each file was written
#: (rocklab.io.write_netcdf) and the time a map took to compute.
VOLATILE = ("history", "compute_s")
#: Where a job of each stage writes its log as it starts (rocklab.io.setup_logging).
STAGES = {"reduction": "logs/reduce", "diagnosis": "logs/diagnosis", "map": "logs/maps"}


def _command(campaign, results, config):
    """The run of the tables into ``results``, in the folder of ``results``: each
    test's runs have a working directory (Snakemake's locks, its record of
    incomplete jobs) of their own."""
    cmd = [str(SNAKEMAKE), *(str(results / t) for t in TABLES), "--cores", "2", "--quiet", "--rerun-incomplete"]
    return cmd + ["--snakefile", str(ROOT / "Snakefile"), "--directory", str(results.parent), "--configfile",
                  str(config), "--config", f"raw_dir={campaign}", f"results_dir={results}"]  # fmt: skip


def _run(campaign, results, config):
    cmd = _command(campaign, results, config)
    run = subprocess.run(cmd, capture_output=True, text=True, cwd=results.parent, timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]


def _run_killed(campaign, results, config, stage, delay, sig, jobs_only=False):
    """Start the run, and once a job of ``stage`` has started and ``delay`` s
    more have passed, send ``sig`` to the run: to the whole process group,
    as a Ctrl-C or a killed session does, or with ``jobs_only`` to the
    running jobs alone (the kernel killing a job short of memory).
    Returns whether the run was cut."""
    proc = subprocess.Popen(
        _command(campaign, results, config),
        cwd=results.parent,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    folder = results / STAGES[stage]
    while proc.poll() is None and not (folder.is_dir() and any(folder.iterdir())):
        time.sleep(0.05)
    time.sleep(delay)
    cut = proc.poll() is None
    if cut and jobs_only:
        for job in psutil.Process(proc.pid).children(recursive=True):
            job.send_signal(sig)
    elif cut:
        os.killpg(proc.pid, sig)
    proc.wait(timeout=300)
    return cut


def _netcdf(path, group=None):
    with xr.open_dataset(path, group=group) as ds:
        ds = ds.load()
    for name in VOLATILE:
        ds.attrs.pop(name, None)
    return ds


def _same_results(a, b):
    for name in TABLES:
        assert (a / name).read_bytes() == (b / name).read_bytes(), name
    for folder in ("tests", "maps"):
        # every file, hidden ones too: a killed writer must leave no temporary file behind
        names = sorted(p.name for p in (a / folder).iterdir())
        assert names == sorted(p.name for p in (b / folder).iterdir()), folder
        for name in (n for n in names if n.endswith(".nc")):
            assert _netcdf(a / folder / name).identical(_netcdf(b / folder / name)), f"{folder}/{name}"
    for name in sorted(p.name for p in (a / "tests").glob("*.nc")):
        # the motion each test's file holds
        assert _netcdf(a / "tests" / name, MOTION_GROUP).identical(_netcdf(b / "tests" / name, MOTION_GROUP)), name


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """A campaign, its config and its results of one uninterrupted run."""
    box = tmp_path_factory.mktemp("interrupt")
    campaign = box / "campaign"
    virtual_lab.write_campaign(campaign, virtual_lab.default_plan(3, seed=5), seed=5)
    config = box / "config.yaml"
    config.write_text(json.dumps(CONFIG))
    _run(campaign, box / "reference", config)
    return campaign, config, box / "reference"


def test_two_runs_give_identical_results(reference, tmp_path):
    campaign, config, results = reference
    _run(campaign, tmp_path / "again", config)
    _same_results(results, tmp_path / "again")


def test_a_killed_run_resumes_to_the_same_results(reference, tmp_path):
    """Cut during a reduction, a diagnosis and a map, at random instants, each
    time resumed by the same command (``make run``'s --rerun-incomplete).

    Snakemake itself is stopped by SIGINT or SIGTERM (it then removes its
    locks); a SIGKILL of Snakemake itself leaves them, and ``snakemake
    --unlock`` must come before the next run.  Its jobs are killed outright.
    """
    campaign, config, reference_results = reference
    results = tmp_path / "results"
    rng = np.random.default_rng()
    cuts = []
    plan = [
        ("reduction", signal.SIGKILL, True),
        ("diagnosis", signal.SIGINT, False),
        ("map", signal.SIGTERM, False),
        ("map", signal.SIGKILL, True),
    ]
    for stage, sig, jobs_only in plan:
        delay = float(rng.uniform(0.0, 1.0))
        cuts.append((stage, sig, delay, _run_killed(campaign, results, config, stage, delay, sig, jobs_only)))
    _run(campaign, results, config)
    assert any(cut for *_, cut in cuts), cuts
    _same_results(reference_results, results)
