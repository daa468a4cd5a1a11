"""bench/beside.py, issue 44's relative target: both trees installed once, run in turn, medians compared."""

import importlib.util
import json
import subprocess
from pathlib import Path

_spec = importlib.util.spec_from_file_location("beside", Path(__file__).parents[1] / "bench" / "beside.py")
beside = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(beside)

# a project whose `make run` takes as long as its SLEEP says, and logs each run two folders up
# (beside the benchmark's temporary folder: the test's own)
MAKEFILE = """CORES ?= 2
venv:
\ttouch installed
run: installed
\ttest ! -e results
\tmkdir results && sleep $$(cat SLEEP) && echo $(CORES) >> ../../runs-$$(cat SLEEP)
"""


def _git(repo, *args):
    return subprocess.run(["git", *args], cwd=repo, check=True, capture_output=True, text=True).stdout.strip()


def _project(tmp_path, first_sleep, then_sleep):
    """A repository of two commits whose `make run` sleeps ``first_sleep``, then ``then_sleep`` [s]:
    the first commit's hash (the baseline)."""
    repo = tmp_path / "repo"
    repo.mkdir()
    _git(repo, "init", "-q")
    _git(repo, "config", "user.email", "lab@example.org")
    _git(repo, "config", "user.name", "lab")
    (repo / "Makefile").write_text(MAKEFILE)
    (repo / ".gitignore").write_text("installed\nresults/\n")
    (repo / "SLEEP").write_text(f"{first_sleep}\n")
    _git(repo, "add", "-A")
    _git(repo, "commit", "-qm", "first")
    baseline = _git(repo, "rev-parse", "HEAD")
    (repo / "SLEEP").write_text(f"{then_sleep}\n")
    _git(repo, "commit", "-qam", "then")
    return repo, baseline


def test_the_trees_run_in_turn_from_empty_results_and_their_medians_are_compared(tmp_path, monkeypatch):
    repo, slow = _project(tmp_path, 0.6, 0.05)
    out = tmp_path / "out"
    monkeypatch.setattr(beside.tempfile, "tempdir", str(tmp_path))
    rc = beside.main(["--repo", str(repo), "--baseline", slow[:7], "--runs", "2", "--cores", "3", "--out", str(out)])
    result = json.loads((out / "beside.json").read_text())
    assert rc == 0 and result["pass"]
    assert result["baseline"] == slow and result["commit"] == _git(repo, "rev-parse", "HEAD")
    assert [len(result["runs"][k]) for k in ("baseline", "head")] == [2, 2]
    assert result["median_wall_s"]["baseline"] > 0.6 > 0.3 > result["median_wall_s"]["head"]
    assert result["ratio"] == result["median_wall_s"]["head"] / result["median_wall_s"]["baseline"] < 0.5
    # each run from an empty results folder (the Makefile refuses another), with the cores asked for
    runs = sorted(tmp_path.glob("runs-*"))
    assert [p.read_text().split() for p in runs] == [["3", "3"], ["3", "3"]]


def test_a_slower_tree_fails_its_target(tmp_path, monkeypatch):
    repo, fast = _project(tmp_path, 0.05, 0.6)
    out = tmp_path / "out"
    monkeypatch.setattr(beside.tempfile, "tempdir", str(tmp_path))
    assert beside.main(["--repo", str(repo), "--baseline", fast, "--runs", "1", "--out", str(out)]) == 1
    assert not json.loads((out / "beside.json").read_text())["pass"]
