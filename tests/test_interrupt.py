"""Interrupted, repeated and damaged runs of the workflow give the results of one uninterrupted run.

A tiny virtual-lab campaign and small overturning maps of two records, up to
the tables of every stage (no figure), in several jobs per stage (one per
specimen, series, record).  Tables (CSV, JSON) must be byte-identical;
netCDF files identical in content, the attributes of :data:`VOLATILE` aside:
they record when a file was written and how long it took, not what it holds.

A run killed, a result file deleted or truncated, a results folder whose
disk fills up half-way or that cannot be written at all: each ends, once
the cause is gone, in those results, and a damaged file has its job and
what reads its outputs run again, nothing else.
"""

import json
import os
import re
import shlex
import shutil
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

pytest.importorskip("rocklab.simulation.rocking_model")
pytestmark = pytest.mark.skipif(not SNAKEMAKE.exists(), reason="snakemake not installed beside this interpreter")
from rocklab.lab import virtual_lab  # noqa: E402
from rocklab.lab.campaign import open_campaign  # noqa: E402
from rocklab.lab.motion import MOTION_GROUP  # noqa: E402

CONFIG = {
    "figures": {"fig9_specimen": "1a"},
    "maps": {"records": ["Pac164", "RRS228"], "n": 5, "calibrated_n": 5, "records_per_job": 1},
    "reduction": {"max_tests_per_job": 1},
    "diagnosis": {"n_boot": 4, "n_history": 1, "max_tests_per_job": 1},
}
#: The tables of every stage: reduction, QC, dissipation, diagnosis, maps.
TABLES = [
    "qc.csv",
    "kinematics.csv",
    "tests.csv",
    "series.csv",
    "impacts.csv",
    "diagnosis.json",
    "maps/summary.csv",
    "maps/calibrated.csv",
]
#: netCDF attributes that differ from run to run: the time each file was written
#: (rocklab.io.write_netcdf) and the time a map took to compute.
VOLATILE = ("history", "compute_s")
#: Where a job of each stage writes its log as it starts (rocklab.io.setup_logging).
STAGES = {"reduction": "logs/reduce", "diagnosis": "logs/diagnosis", "map": "logs/maps"}


def _command(campaign, results, config, workdir=None):
    """The run of the tables into ``results``, in ``workdir`` (the folder of
    ``results`` by default): each test's runs have a working directory
    (Snakemake's locks, its record of incomplete jobs) of their own."""
    cmd = [str(SNAKEMAKE), *(str(results / t) for t in TABLES), "--cores", "2", "--quiet", "--rerun-incomplete"]
    return cmd + ["--snakefile", str(ROOT / "Snakefile"), "--directory", str(workdir or results.parent),
                  "--configfile", str(config), "--config", f"raw_dir={campaign}", f"results_dir={results}"]  # fmt: skip


def _run(campaign, results, config):
    """Run the tables; the jobs it ran, as (rule, wildcards) pairs."""
    cmd = [c for c in _command(campaign, results, config) if c != "--quiet"]
    run = subprocess.run(cmd, capture_output=True, text=True, cwd=results.parent, timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    return _jobs_run(run.stderr)


def _jobs_run(log):
    """The jobs of a Snakemake log, as (rule, its wildcards or "") pairs (target rules aside)."""
    jobs = re.findall(r"^(?:local)?(?:rule|checkpoint) (\w+):\n((?:    .*\n)*)", log, re.M)
    return {(rule, (re.findall(r"^    wildcards: (.*)$", block, re.M) or [""])[0]) for rule, block in jobs}


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
        names = sorted(p.relative_to(a / folder) for p in (a / folder).rglob("*") if p.is_file())
        assert names == sorted(p.relative_to(b / folder) for p in (b / folder).rglob("*") if p.is_file()), folder
        for name in (n for n in names if n.suffix == ".nc"):
            assert _netcdf(a / folder / name).identical(_netcdf(b / folder / name)), f"{folder}/{name}"
    for name in sorted(p.relative_to(a / "tests") for p in (a / "tests").rglob("*.nc")):
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


def test_a_killed_run_resumes_to_the_same_results(reference, tmp_path):
    """Cut during a reduction, a diagnosis and a map, at random instants, each
    time resumed by the same command (``make run``'s --rerun-incomplete); the
    results are those of the reference run, so two runs also agree.

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


# --- a damaged results folder ------------------------------------------------------------------

#: Jobs that read nothing of the campaign: a damaged test, diagnosis or map never runs them again.
APART = {"limestone_diagnosis", "instrument_accuracy"}


def test_a_damaged_result_has_its_job_and_what_reads_it_run_again(reference, tmp_path):
    """A test's file deleted from its job's folder, a map truncated, a diagnosis job's file
    truncated: each rebuilt by its own job, the jobs downstream of it run again, no other
    job of its stage, and the results those of an undisturbed run."""
    campaign, config, reference_results = reference
    results = tmp_path / "results"
    _run(campaign, results, config)
    c = open_campaign(campaign)

    test = sorted((results / "tests").rglob("*.nc"))[-1]
    test.unlink()
    ran = _run(campaign, results, config)
    assert {w for r, w in ran if r == "reduce"} == {f"job={test.parent.name}"}, ran
    series = {s for s, ids in c.reduction_groups().items() if test.stem in ids}
    jobs_of_series = {f"job={j}" for j, ss in c.diagnosis_jobs(1).items() if series & set(ss)}
    assert {w for r, w in ran if r == "diagnose_series"} == jobs_of_series, ran
    assert not {r for r, _ in ran} & (APART | {"overturning_maps"}), ran
    _same_results(reference_results, results)

    paper_map = sorted((results / "maps").glob("records-*/*.nc"))[-1]
    os.truncate(paper_map, paper_map.stat().st_size // 2)
    ran = _run(campaign, results, config)
    batch = paper_map.parent.name.removeprefix("records-")
    assert {(r, w) for r, w in ran if r.endswith("_maps")} == {("overturning_maps", f"batch={batch}")}, ran
    assert not {r for r, _ in ran} & (APART | {"reduce", "qc_table", "diagnose_series", "diagnosis"}), ran
    _same_results(reference_results, results)

    diagnosis_job = sorted((results / "diagnosis").glob("series-*.json"))[0]
    os.truncate(diagnosis_job, 10)
    ran = _run(campaign, results, config)
    assert {w for r, w in ran if r == "diagnose_series"} == {f"job={diagnosis_job.stem}"}, ran
    assert not {r for r, _ in ran} & (APART | {"reduce", "qc_table", "dissipation_tables", "overturning_maps"}), ran
    _same_results(reference_results, results)


# --- a full disk, a read-only folder -----------------------------------------------------------


def _namespace():
    """The command prefix that runs a shell in a mount namespace of its own (root's, or
    a user namespace's), None where the machine allows neither: there the writers'
    fault injection (tests/test_disk.py) stands in."""
    if not shutil.which("unshare"):
        return None
    for prefix in (
        ["unshare", "--mount", "--propagation", "private"],
        ["unshare", "--user", "--map-root-user", "--mount"],
    ):
        probe = subprocess.run([*prefix, "sh", "-c", "mount -t tmpfs -o size=1m tmpfs /mnt"], capture_output=True)
        if probe.returncode == 0:
            return prefix
    return None


NAMESPACE = _namespace()
needs_mounts = pytest.mark.skipif(
    NAMESPACE is None, reason="no mount namespace here: a small filesystem cannot be mounted"
)


def _in_namespace(script, timeout=900):
    """Run a shell script in a mount namespace of its own (its mounts go with it)."""
    return subprocess.run([*NAMESPACE, "sh", "-c", script], capture_output=True, text=True, timeout=timeout)


def _size(folder):
    """Bytes a folder's files take on a filesystem of 4 kB pages."""
    return sum(-(-p.stat().st_size // 4096) * 4096 for p in Path(folder).rglob("*") if p.is_file())


@needs_mounts
def test_a_results_folder_on_a_disk_that_fills_up_resumes_once_space_is_freed(reference, tmp_path):
    """The run stops, naming the file it could not write and the space it needed, leaves
    no partial result, and once space is freed the same command completes to the results
    of an undisturbed run."""
    campaign, config, reference_results = reference
    need = _size(reference_results)
    mnt, out, work = tmp_path / "disk", tmp_path / "out", tmp_path / "work"
    for d in (mnt, out, work):
        d.mkdir()
    results = mnt / "results"
    cmd = " ".join(shlex.quote(c) for c in _command(campaign, results, config, workdir=work))
    # the disk holds a ballast file and room for half the results; the ballast is then deleted
    script = f"""
mount -t tmpfs -o size={2 * need + 2**23} tmpfs {mnt} || exit 90
head -c {2 * need + 2**23 - need // 2} /dev/zero > {mnt}/ballast
cd {work}
{cmd} > {out}/first.out 2> {out}/first.err; echo $? > {out}/first.rc
cp -a {results} {out}/partial
rm {mnt}/ballast
{cmd} > {out}/second.out 2> {out}/second.err; echo $? > {out}/second.rc
cp -a {results} {out}/results
"""
    run = _in_namespace(script)
    assert run.returncode == 0, run.stderr
    first = (out / "first.err").read_text()
    assert (out / "first.rc").read_text().strip() != "0", first[-3000:]
    stops = re.findall(r"^rocklab: no space left to write (\S+): .*free on its disk\. Free some space", first, re.M)
    assert stops and all(Path(f).is_relative_to(results) for f in stops), first[-3000:]
    assert "Traceback" not in first, first[-3000:]
    assert (out / "second.rc").read_text().strip() == "0", (out / "second.err").read_text()[-3000:]
    _same_results(reference_results, out / "results")
    # what the full disk left was complete: each result of it is the rerun's own, unchanged
    partial = out / "partial"
    left = [p.relative_to(partial) for p in partial.rglob("*") if p.is_file()]
    assert not [p for p in left if p.name.endswith(".tmp")], left
    for rel in left:
        if rel.parts[0] in ("logs", "benchmarks", ".manifests") or rel.name == ".snakemake_timestamp":
            continue
        if rel.suffix == ".nc":
            assert _netcdf(partial / rel).identical(_netcdf(out / "results" / rel)), rel
        else:
            assert (partial / rel).read_bytes() == (out / "results" / rel).read_bytes(), rel


@needs_mounts
def test_a_results_folder_that_cannot_be_written_is_refused_before_any_job(reference, tmp_path):
    campaign, config, _ = reference
    mnt, work = tmp_path / "disk", tmp_path / "work"
    mnt.mkdir()
    work.mkdir()
    results = mnt / "results"
    cmd = " ".join(shlex.quote(c) for c in _command(campaign, results, config, workdir=work))
    script = f"""
mount -t tmpfs -o size=4m tmpfs {mnt} && mkdir {results} && mount -o remount,ro {mnt} || exit 90
cd {work} && {cmd}
"""
    run = _in_namespace(script)
    assert run.returncode not in (0, 90), run.stderr
    assert f"results_dir '{results}' cannot be written (Read-only file system)" in run.stderr, run.stderr[-3000:]
    assert not re.search(r"^(local)?(rule|checkpoint) ", run.stderr, re.M), run.stderr[-3000:]
