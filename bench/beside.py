"""Benchmark: the default target beside a baseline commit's, on one machine, runs alternated (issue 44).

    python bench/beside.py --out results/bench [--baseline e341fb6] [--runs 2] [--cores 2]

Issue 44's target is relative: `make run` on the embedded campaign no slower
than at the baseline commit, measured on one idle machine.  A single run of
each says little on a shared machine (two runs of the same tree here differed
by a fifth), so the two trees are run in turn, baseline first, ``--runs``
times each, and the medians are compared: a load that drifts during the
benchmark weighs on both alike.

Both commits are cloned from this repository's HEAD history into a
temporary folder and installed (``make venv``, untimed: pip's cache and the
machine's disk differ from one run of the benchmark to the next, and
bench/fresh_clone.py times the install); each run then starts from an
empty results folder (``make run``, the numba kernels compiled at install).
Recorded per run: the wall time, the CPU time of all its processes and the
load average before it.  Target: the median of HEAD at most the baseline's
(``ratio`` <= 1); the JSON says which commits were measured.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from rocklab.benchmarks import measured_code

ROOT = Path(__file__).resolve().parents[1]
#: Issue 44: the commit whose default target the tree must not be slower than.
BASELINE = "e341fb6"


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _run(cmd: list[str], cwd: Path, log: Path) -> tuple[float, float]:
    """Wall and CPU time [s] of ``cmd`` (its whole process tree, waited for)."""
    cpu0, t0 = _children_cpu(), time.perf_counter()
    with open(log, "w") as fh:
        done = subprocess.run(cmd, cwd=cwd, stdout=fh, stderr=subprocess.STDOUT)
    wall, cpu = time.perf_counter() - t0, _children_cpu() - cpu0
    if done.returncode:
        sys.exit(f"{' '.join(cmd)} in {cwd} failed with exit status {done.returncode}: see {log}")
    return wall, cpu


def _checkout(repo: Path, commit: str, folder: Path) -> str:
    """Clone ``repo`` into ``folder`` at ``commit``; its full hash."""
    subprocess.run(["git", "clone", "--quiet", str(repo), str(folder)], check=True)
    subprocess.run(["git", "checkout", "--quiet", commit], cwd=folder, check=True)
    return subprocess.run(
        ["git", "rev-parse", "HEAD"], cwd=folder, capture_output=True, text=True, check=True
    ).stdout.strip()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="results/bench")
    ap.add_argument("--baseline", default=BASELINE, help="commit to compare with (default: issue 44's)")
    ap.add_argument("--runs", type=int, default=2, help="runs of each tree, alternated")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--repo", type=Path, default=ROOT, help="repository whose HEAD is measured (default: this one)")
    args = ap.parse_args(argv)
    out = Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=args.repo, capture_output=True, text=True).stdout.strip()
    runs: dict[str, list[dict[str, float]]] = {"baseline": [], "head": []}
    with tempfile.TemporaryDirectory(prefix="rocklab-beside-") as tmp:
        trees = {"baseline": Path(tmp) / "baseline", "head": Path(tmp) / "head"}
        wanted = {"baseline": args.baseline, "head": head}
        commits = {name: _checkout(args.repo, commit, trees[name]) for name, commit in wanted.items()}
        measured = measured_code(trees["head"], "bench/beside.py")
        make = ["make", f"CORES={args.cores}"]
        for name, tree in trees.items():
            _run([*make, "venv"], tree, out / f"beside_{name}_install.log")
        for k in range(args.runs):
            for name, tree in trees.items():
                shutil.rmtree(tree / "results", ignore_errors=True)
                load = os.getloadavg()[0]
                wall, cpu = _run([*make, "run"], tree, out / f"beside_{name}_run{k + 1}.log")
                runs[name].append({"wall_s": wall, "cpu_s": cpu, "load_1min_before": load})
                print(f"{name} {commits[name][:8]} run {k + 1}: {wall:.0f} s, CPU {cpu:.0f} s, load {load:.1f}")
    median = {name: statistics.median(r["wall_s"] for r in rs) for name, rs in runs.items()}
    ratio = median["head"] / median["baseline"]
    result = {
        "commit": head,
        "measured": measured,
        "baseline": commits["baseline"],
        "cores": args.cores,
        "runs": runs,
        "median_wall_s": median,
        "median_cpu_s": {name: statistics.median(r["cpu_s"] for r in rs) for name, rs in runs.items()},
        "ratio": ratio,
        "target_ratio": 1.0,
        "pass": ratio <= 1.0,
    }
    (out / "beside.json").write_text(json.dumps(result, indent=2) + "\n")
    print(
        f"default target, median of {args.runs}: {head[:8]} {median['head']:.0f} s, "
        f"{commits['baseline'][:8]} {median['baseline']:.0f} s: ratio {ratio:.2f} (target at most 1)"
    )
    return 0 if result["pass"] else 1


if __name__ == "__main__":
    sys.exit(main())
