"""What a job leaves in the results folder (its manifest), the damage the check before
each run finds, and a job's end on a full disk (rocklab.jobs)."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from rocklab import jobs
from rocklab.disk import NoSpace


def _job(results, outputs):
    """A finished job with these outputs (file: text, or folder: {name: text})."""
    for rel, content in outputs.items():
        path = results / rel
        if isinstance(content, dict):
            path.mkdir(parents=True)
            for name, text in content.items():
                (path / name).write_text(text)
            (path / jobs.SNAKEMAKE_TIMESTAMP).touch()
        else:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(content)
    return jobs.record([results / rel for rel in outputs], results)


@pytest.fixture
def results(tmp_path):
    results = tmp_path / "results"
    _job(results, {"tests/job-a": {"T1.nc": "one", "T2.nc": "two"}, "reduction/job-a.json": "[]"})
    _job(results, {"qc.csv": "test_id\nT1\n"})
    return results


def test_a_job_s_manifest_lists_every_file_of_its_outputs(results):
    manifest = json.loads(jobs.manifest_path(results, results / "tests" / "job-a").read_text())
    assert manifest["outputs"] == ["tests/job-a", "reduction/job-a.json"]
    assert sorted(manifest["files"]) == ["reduction/job-a.json", "tests/job-a/T1.nc", "tests/job-a/T2.nc"]
    size, mtime_ns, blake = manifest["files"]["tests/job-a/T1.nc"]
    assert size == 3 and mtime_ns == (results / "tests/job-a/T1.nc").stat().st_mtime_ns
    assert blake == jobs.digest(results / "tests/job-a/T1.nc")
    assert jobs.damaged(results) == []


def test_a_file_deleted_from_a_folder_output_damages_its_job_only(results):
    (results / "tests/job-a/T2.nc").unlink()
    (d,) = jobs.damaged(results)
    assert (d.file, d.problem, d.outputs) == ("tests/job-a/T2.nc", "missing", ("tests/job-a", "reduction/job-a.json"))


def test_a_truncated_file_is_damage_with_its_sizes(results):
    os.truncate(results / "qc.csv", 4)
    (d,) = jobs.damaged(results)
    assert (d.file, d.problem) == ("qc.csv", "4 bytes where its job wrote 11")


def test_a_file_rewritten_with_other_bytes_of_its_size_is_damage(results):
    (results / "tests/job-a/T1.nc").write_text("ONE")
    assert [(d.file, d.problem) for d in jobs.damaged(results)] == [
        ("tests/job-a/T1.nc", "changed since its job wrote it")
    ]


def test_a_file_touched_or_copied_with_its_bytes_is_no_damage(results):
    os.utime(results / "qc.csv", ns=(1, 10**18))
    assert jobs.damaged(results) == []


def test_a_job_whose_outputs_are_all_gone_is_damaged_too(results):
    """Snakemake leaves a missing file alone while what was made from it is newer."""
    shutil.rmtree(results / "tests/job-a")
    (results / "reduction/job-a.json").unlink()
    assert [(d.file, d.problem, d.outputs[0]) for d in jobs.damaged(results)] == [
        ("reduction/job-a.json", "missing", "tests/job-a")
    ]


def test_checking_changes_nothing(results):
    os.truncate(results / "qc.csv", 4)
    before = sorted((p, p.stat().st_size) for p in results.rglob("*") if p.is_file())
    jobs.damaged(results)
    assert sorted((p, p.stat().st_size) for p in results.rglob("*") if p.is_file()) == before


def test_an_unreadable_manifest_is_the_damage_of_its_first_output_s_job(results):
    jobs.manifest_path(results, results / "tests" / "job-a").write_text("{")
    (d,) = jobs.damaged(results)
    assert (d.problem, d.outputs) == ("unreadable manifest", ("tests/job-a",))


def test_a_job_records_only_its_outputs_in_the_results_folder(tmp_path):
    (tmp_path / "elsewhere.txt").write_text("x")
    assert jobs.record([tmp_path / "elsewhere.txt"], tmp_path / "results") is None


def test_a_job_ends_on_a_full_disk_with_one_line_and_no_traceback(tmp_path):
    """The job's own code: a NoSpace that reaches the top says what and where, once."""
    log = tmp_path / "logs" / "job.log"
    script = f"""
from types import SimpleNamespace
from rocklab import jobs
from rocklab.disk import NoSpace
job = jobs.start(SimpleNamespace(log=[{str(log)!r}], output=[], input=[], config={{"results_dir": {str(tmp_path)!r}}}))
raise NoSpace({str(tmp_path / "qc.csv")!r}, 2_500_000, 0)
"""
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert run.returncode == 1
    assert run.stderr.strip() == f"rocklab: {NoSpace(tmp_path / 'qc.csv', 2_500_000, 0)}"
    assert "no space left to write" in log.read_text()


def test_finish_records_the_job_s_declared_outputs(tmp_path, monkeypatch):
    monkeypatch.setattr(jobs, "setup_logging", lambda path: None)  # this process's logging stays pytest's
    monkeypatch.setattr(sys, "excepthook", sys.excepthook)
    results = tmp_path / "results"
    (results / "a").mkdir(parents=True)
    (results / "a" / "x.nc").write_text("x")
    smk = SimpleNamespace(
        log=[str(tmp_path / "job.log")], output=[str(results / "a")], input=[], config={"results_dir": str(results)}
    )
    jobs.start(smk).finish()
    assert Path(jobs.manifest_path(results, results / "a")).is_file() and jobs.damaged(results) == []


def test_clearing_removes_the_damaged_job_and_what_was_made_from_it_and_nothing_else(results):
    (results / "other.csv").write_text("x")
    jobs.record([results / "other.csv"], results)  # a job that read nothing of job-a
    (results / "summary.csv").write_text("s")
    jobs.record([results / "summary.csv"], results, inputs=[results / "qc.csv", "/elsewhere/raw.csv"])
    manifest = jobs.manifest_path(results, results / "qc.csv")
    entry = json.loads(manifest.read_text())
    jobs.record([results / "qc.csv"], results, inputs=[results / "reduction/job-a.json"])  # qc read job-a
    assert json.loads(manifest.read_text())["inputs"] == ["reduction/job-a.json"] != entry["inputs"]
    (results / "tests/job-a/T2.nc").unlink()
    (cleared,) = jobs.clear_damage(results)
    assert cleared.outputs == ("tests/job-a", "reduction/job-a.json", "qc.csv", "summary.csv")
    assert str(cleared) == "missing; its job's outputs and the 2 made from them removed, to be made again"
    assert not any((results / o).exists() for o in cleared.outputs)
    assert (results / "other.csv").exists() and jobs.damaged(results) == []
    assert sorted(p.name for p in (results / jobs.MANIFESTS).rglob("*.json")) == ["other.csv.json"]


def test_a_job_reading_a_folder_output_or_a_file_in_it_is_downstream(results):
    (results / "fig.png").write_text("f")
    jobs.record([results / "fig.png"], results, inputs=[results / "tests/job-a"])
    os.truncate(results / "tests/job-a/T1.nc", 1)
    (cleared,) = jobs.clear_damage(results)
    assert "fig.png" in cleared.outputs and not (results / "fig.png").exists()


def test_a_manifest_that_names_a_path_outside_the_results_is_never_followed(results, tmp_path):
    outside = tmp_path / "precious.txt"
    outside.write_text("not ours")
    manifest = jobs.manifest_path(results, results / "qc.csv")
    entry = json.loads(manifest.read_text())
    for evil in ("../precious.txt", str(outside)):
        manifest.write_text(json.dumps({**entry, "outputs": [evil], "files": {evil: [1, 1, "x"]}}))
        (d,) = jobs.damaged(results)
        assert (d.file, d.problem, d.outputs) == (".manifests/qc.csv.json", "unreadable manifest", ("qc.csv",))
    manifest.write_text(json.dumps({**entry, "files": {"qc.csv": "12 bytes"}}))
    assert [d.problem for d in jobs.damaged(results)] == ["unreadable manifest"]
    jobs.clear_damage(results)
    assert outside.read_text() == "not ours" and not (results / "qc.csv").exists()


def test_damage_is_not_cleared_while_a_job_of_another_run_writes(results):
    os.truncate(results / "qc.csv", 4)
    script = f"""
import sys, time
from types import SimpleNamespace
from rocklab import jobs
smk = SimpleNamespace(log=[{str(results / "job.log")!r}], output=[], input=[])
smk.config = {{"results_dir": {str(results)!r}}}
job = jobs.start(smk)
print("writing", flush=True)
time.sleep(30)
"""
    job = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    try:
        assert job.stdout.readline() == "writing\n"
        assert jobs.clear_damage(results) is None and (results / "qc.csv").exists()
    finally:
        job.kill()
        job.wait()
    assert [c.damage.file for c in jobs.clear_damage(results)] == ["qc.csv"]
