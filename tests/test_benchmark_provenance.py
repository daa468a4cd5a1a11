"""What a benchmark measured (rocklab.benchmarks.measured_code): the commit, its code, uncommitted code."""

import subprocess

import pytest

from rocklab.benchmarks import measured_code


def _git(repo, *args):
    subprocess.run(["git", *args], cwd=repo, check=True, capture_output=True)


@pytest.fixture
def repo(tmp_path):
    _git(tmp_path, "init", "-q")
    _git(tmp_path, "config", "user.email", "lab@example.org")
    _git(tmp_path, "config", "user.name", "lab")
    (tmp_path / "src" / "rocklab").mkdir(parents=True)
    (tmp_path / "src" / "rocklab" / "wall.py").write_text("G = 9.80665\n")
    (tmp_path / "bench").mkdir()
    (tmp_path / "bench" / "scale.py").write_text("SIZES = (614, 6140)\n")
    (tmp_path / "CHANGELOG.md").write_text("# Changelog\n")
    _git(tmp_path, "add", "-A")
    _git(tmp_path, "commit", "-qm", "first")
    return tmp_path


def test_the_code_of_a_commit_is_that_of_its_library_and_benchmark_not_its_pages(repo):
    first = measured_code(repo, "bench/scale.py")
    assert not first["dirty"] and len(first["commit"]) == 40
    # pages and history change: the same code, another commit
    (repo / "CHANGELOG.md").write_text("# Changelog\n\n- timings\n")
    _git(repo, "commit", "-qam", "pages")
    pages = measured_code(repo, "bench/scale.py")
    assert pages["code"] == first["code"] and pages["commit"] != first["commit"]
    # the library changes: other code, and uncommitted it is measured on no commit
    (repo / "src" / "rocklab" / "wall.py").write_text("G = 9.81\n")
    assert measured_code(repo, "bench/scale.py")["dirty"]
    _git(repo, "commit", "-qam", "g")
    assert measured_code(repo, "bench/scale.py")["code"] != first["code"]
    # the benchmark's own script is its code too; another benchmark's is not
    (repo / "bench" / "scale.py").write_text("SIZES = (100, 1000)\n")
    _git(repo, "commit", "-qam", "sizes")
    assert measured_code(repo, "bench/scale.py")["code"] != measured_code(repo, "bench/fresh_clone.py")["code"]


def test_a_folder_that_is_no_checkout_is_said(tmp_path):
    with pytest.raises(RuntimeError, match="is no git checkout"):
        measured_code(tmp_path)
