"""End to end: the workflow on a campaign it has never seen, and the QC against known truth."""

import hashlib
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pandas as pd
import pytest

from rocklab.lab.campaign import open_campaign
from rocklab.lab.motion import read_stored_motion
from rocklab.lab.reduction import qc_table, reduce_test, reduce_tests

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")

rocking = pytest.importorskip("rocklab.simulation.rocking_model")
from rocklab.lab import virtual_lab  # noqa: E402


def _tree_hash(folder):
    h = hashlib.sha256()
    for p in sorted(Path(folder).rglob("*")):
        if p.is_file():
            h.update(p.relative_to(folder).as_posix().encode() + p.read_bytes() + str(p.stat().st_mtime_ns).encode())
    return h.hexdigest()


@pytest.fixture(scope="module")
def virtual_campaign(tmp_path_factory):
    out = tmp_path_factory.mktemp("virtual") / "campaign"
    truth = virtual_lab.write_campaign(out, virtual_lab.default_plan(20, seed=3), seed=3)
    return out, truth


def test_qc_matches_the_hidden_truth(virtual_campaign):
    """Every injected fault, disturbed release and residual is found, with the lab's reason."""
    folder, truth = virtual_campaign
    c = open_campaign(folder)
    qc = qc_table([reduce_test(c, t) for t in c.tests.test_id], c).set_index("test_id")
    expected = truth.set_index("test_id").expected_reason.replace({"valid": ""})
    got = qc.reject_reason.reindex(expected.index)
    assert (got == expected).all(), pd.DataFrame({"expected": expected, "got": got})[got != expected]


def test_the_qc_tables_from_the_jobs_rows_are_those_of_the_files(virtual_campaign, tmp_path):
    """What a reduction job writes beside its netCDF files gives qc.csv and kinematics.csv as the files would."""
    import netCDF4

    from rocklab.io import write_netcdf
    from rocklab.lab.reduction import kinematics_table, read_row_attrs, row_attrs, write_row_attrs

    folder, truth = virtual_campaign
    c = open_campaign(folder)
    reduced = dict(reduce_tests(c, c.test_ids))
    assert {ds.attrs["reject_reason"] for ds in reduced.values()} >= {"", "unreadable"}
    files = []
    for test_id, ds in reduced.items():
        write_netcdf(ds, tmp_path / f"{test_id}.nc")
        with netCDF4.Dataset(tmp_path / f"{test_id}.nc") as nc:
            files.append(SimpleNamespace(attrs={k: nc.getncattr(k) for k in nc.ncattrs()}))
    ids = list(reduced)
    write_row_attrs([row_attrs(reduced[t]) for t in ids[:5]], tmp_path / "a.json")
    write_row_attrs([row_attrs(reduced[t]) for t in ids[5:]], tmp_path / "b.json")
    # the jobs' files in any order: the tables follow tests.csv
    rows = read_row_attrs([tmp_path / "b.json", tmp_path / "a.json"])
    pd.testing.assert_frame_equal(qc_table(rows, c), qc_table(files, c))
    kinematics = kinematics_table(rows, c)
    pd.testing.assert_frame_equal(kinematics, kinematics_table(files, c))
    readable = [t for t in ids if reduced[t].attrs["reject_reason"] != "unreadable"]
    assert kinematics.test_id.tolist() == readable and kinematics.peak_theta.notna().any()


def _snakemake(target, folder, results, *options, output="stdout", returncode=0):
    """Run Snakemake on a campaign folder; its standard output (or ``output="stderr"``, its log).

    The working directory (Snakemake's locks and metadata) is the folder of
    ``results``: a test's own, so that tests running at once share nothing.
    """
    workdir = Path(results).parent
    workdir.mkdir(parents=True, exist_ok=True)
    cmd = [
        str(SNAKEMAKE),
        target,
        *options,
        "--snakefile",
        str(ROOT / "Snakefile"),
        "--directory",
        str(workdir),
        "--config",
        f"raw_dir={folder}",
        f"results_dir={results}",
        "figures={'fig9_specimen': '1a'}",
        # the overturning maps of one short record only (test_overturning covers the stage)
        "maps={'records': ['Pac164']}",
    ]
    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    run = subprocess.run(cmd, capture_output=True, text=True, cwd=workdir, env=env)
    assert run.returncode == returncode, run.stderr[-3000:]
    return getattr(run, output)


def _planned_jobs(target, folder, results):
    """Jobs per rule that a dry run of target plans (before its checkpoints run)."""
    out = _snakemake(target, folder, results, "--dry-run", "--quiet", "rules")
    if "Job stats:" not in out:  # nothing to be done
        return {}
    stats = out.split("Job stats:")[1]
    return {rule: int(n) for rule, n in re.findall(r"^(\w+)\s+(\d+)$", stats.split("\ntotal")[0], re.M)}


@pytest.mark.skipif(not SNAKEMAKE.exists(), reason="snakemake not installed beside this interpreter")
def test_the_campaign_target_plans_no_map_and_no_limestone_job(tmp_path):
    folder, results = tmp_path / "campaign", tmp_path / "results"
    virtual_lab.write_campaign(folder, virtual_lab.default_plan(3, seed=3), seed=3)
    campaign = _planned_jobs("campaign", folder, results)
    assert not {"map_summary", "limestone_diagnosis", "docs", "overturning_maps", "calibrated_maps"} & set(campaign)
    assert {"reduce", "diagnose_series", "qc_table", "dissipation_tables", "diagnosis_figures", "qc_pages"} <= set(
        campaign
    ), campaign
    everything = _planned_jobs("all", folder, results)
    # one record: one job of the paper's maps
    assert everything["overturning_maps"] == 1 and everything["limestone_diagnosis"] == 1
    del campaign["campaign"]
    assert {r: everything[r] for r in campaign} == campaign  # the same jobs for the campaign's part


@pytest.mark.skipif(not SNAKEMAKE.exists(), reason="snakemake not installed beside this interpreter")
def test_the_rules_are_the_same_on_every_campaign(tmp_path):
    """`--list-rules`, `--forcerun` and `--until` name the same rules whatever the campaign:
    its jobs are the wildcards of rules of fixed names, packed as before (one reduction job
    per few specimens, one diagnosis job per few series)."""
    rules = []
    for n, seed in ((3, 3), (6, 5)):
        folder, results = tmp_path / f"campaign{n}", tmp_path / f"results{n}" / "results"
        virtual_lab.write_campaign(folder, virtual_lab.default_plan(n, seed=seed), seed=seed)
        rules.append(_snakemake("all", folder, results, "--list-rules").split())
        c = open_campaign(folder)
        planned = _planned_jobs("all", folder, results)
        assert planned["reduce"] == len(c.reduction_jobs()), planned
        assert planned["diagnose_series"] == len(c.diagnosis_jobs()), planned
    assert rules[0] == rules[1] and "reduce" in rules[0] and "overturning_maps" in rules[0]


@pytest.mark.skipif(not SNAKEMAKE.exists(), reason="snakemake not installed beside this interpreter")
def test_the_workflow_lints_clean(tmp_path):
    """`snakemake --lint` finds nothing but the missing conda environments: the
    environment is requirements.lock installed in the venv (no conda channel
    is reachable where the project is developed and tested)."""
    out = _snakemake("all", ROOT / "raw" / "campaign", tmp_path / "results", "--lint", output="stderr", returncode=1)
    lints = re.findall(r"^    \* (.+?):?$", out, re.M)
    assert lints, out[-2000:]  # the conda lint is still seen: the lint ran
    assert set(lints) == {"Specify a conda environment or container for each rule."}, out[-3000:]


@pytest.mark.skipif(not SNAKEMAKE.exists(), reason="snakemake not installed beside this interpreter")
def test_workflow_reduces_any_campaign_and_never_writes_to_it(virtual_campaign, tmp_path):
    folder, truth = virtual_campaign
    before = _tree_hash(folder)
    results = tmp_path / "results"
    start = time.monotonic()
    log = _snakemake("campaign", folder, results, "--cores", "2", "--verbose", output="stderr")
    wall = time.monotonic() - start
    assert _tree_hash(folder) == before
    # Snakemake schedules when a job ends, and with its job-rate limit
    # (profiles/default) once a second more for each job that has ended
    # while another waited for a core: at most that many rounds
    rounds, jobs = log.count("Ready jobs:"), log.count("Finished jobid")
    assert 0 < rounds <= jobs * (wall + 2), (rounds, jobs, wall)
    # the campaign alone: nothing of the maps or of the limestone blocks
    assert not (results / "maps").exists() and not (results / "limestone_diagnosis.json").exists()
    qc = pd.read_csv(results / "qc.csv", keep_default_na=False)
    assert len(qc) == len(truth)
    assert (qc.reject_reason == "unreadable").sum() == (truth.expected_reason == "unreadable").sum()
    tests = pd.read_csv(results / "tests.csv")
    assert set(tests.test_id) == set(qc.test_id[qc.valid.astype(str) == "True"])
    for name in ("impacts.csv", "series.csv", "figures/fig09.png", "report/qc.html", "report/diagnosis.html"):
        assert (results / name).exists()
    # the motion of every test, extracted once by its reduction job and stored in the test's file
    assert {read_stored_motion(p).attrs["test_id"] for p in (results / "tests").rglob("*.nc")} == set(qc.test_id)
    # every series with valid tests is diagnosed from those stored motions, each with its figure
    diagnosed = {e["key"] for e in json.loads((results / "diagnosis.json").read_text()) if e["scope"] == "series"}
    assert diagnosed and diagnosed <= set(tests.series)
    assert {p.stem for p in (results / "figures" / "diagnosis").glob("*.png")} == diagnosed
    # then everything else, the campaign's jobs being done
    _snakemake("all", folder, results, "--cores", "2", "--quiet")
    assert _tree_hash(folder) == before
    for name in ("maps/summary.csv", "figures/fig21.png", "report/map_summary.html", "limestone_diagnosis.json"):
        assert (results / name).exists()


@pytest.mark.skipif(not SNAKEMAKE.exists(), reason="snakemake not installed beside this interpreter")
def test_a_changed_record_reduces_its_job_again(tmp_path):
    """The records are params of their reduction job (their size and mtime), not inputs: still tracked."""
    folder, results = tmp_path / "campaign", tmp_path / "results"
    virtual_lab.write_campaign(folder, virtual_lab.default_plan(3, seed=3), seed=3)
    _snakemake(str(results / "qc.csv"), folder, results, "--cores", "2", "--quiet")
    assert _planned_jobs(str(results / "qc.csv"), folder, results) == {}
    record = open_campaign(folder).record_path(open_campaign(folder).test_ids[0])
    st = record.stat()
    os.utime(record, ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))
    planned = _planned_jobs(str(results / "qc.csv"), folder, results)
    assert planned.get("reduce") == 1 and planned.get("qc_table") == 1, planned


def test_a_reduction_that_fails_does_not_stop_the_series(virtual_campaign, monkeypatch):
    """An error no rule foresaw becomes that test's unreadable entry, with the file and the error."""
    from rocklab.lab import kinematics, reduction

    folder, _ = virtual_campaign
    c = open_campaign(folder)
    ids = list(c.tests.test_id[:3])
    solve = kinematics.solve_wall_motion
    calls = []

    def flaky(*args, **kw):
        calls.append(1)
        if len(calls) == 2:
            raise FloatingPointError("singular transducer geometry")
        return solve(*args, **kw)

    monkeypatch.setattr(kinematics, "solve_wall_motion", flaky)
    out = dict(reduction.reduce_tests(c, ids))
    assert list(out) == ids
    bad = [t for t, ds in out.items() if "reduction failed" in ds.attrs["reject_detail"]]
    assert len(bad) == 1 and out[bad[0]].attrs["reject_reason"] == "unreadable"
    assert "FloatingPointError" in out[bad[0]].attrs["reject_detail"]
    assert str(c.record_path(bad[0])) in out[bad[0]].attrs["reject_detail"]


def test_valid_tests_by_qc_table_or_by_their_own_verdict(tmp_path):
    import xarray as xr

    from rocklab.io import valid_tests

    paths = []
    for tid, valid in (("T1", 1), ("T2", 0), ("T3", 1)):
        paths.append(tmp_path / f"{tid}.nc")
        xr.Dataset(attrs={"test_id": tid, "valid": valid}).to_netcdf(paths[-1])
    assert [ds.attrs["test_id"] for ds in valid_tests(paths)] == ["T1", "T3"]
    qc = tmp_path / "qc.csv"
    pd.DataFrame({"test_id": ["T1", "T2", "T3"], "valid": [False, True, True]}).to_csv(qc, index=False)
    assert [ds.attrs["test_id"] for ds in valid_tests(paths, qc)] == ["T2", "T3"]
