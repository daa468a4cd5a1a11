"""Benchmark: `make run` on a fresh clone, the install included (issue 14, item 5).

    python bench/fresh_clone.py --out results/bench [--cores 2]

Clones the repository's committed HEAD into a temporary folder (what a user
gets; the working tree's changes are not in it), then times ``make venv``
(the virtual environment and the pinned dependencies, from pip's download
cache where it has them) and ``make run`` (the whole workflow on the
embedded campaign) with ``CORES``. Targets: 4 min for both, 150 s for the
workflow, on 2 cores. Also recorded: the CPU time of every process the two
commands started (less sensitive than the wall time to a shared machine),
and the load average before the run, since the wall time is only
comparable between runs on an idle machine.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from rocklab.benchmarks import measured_code

ROOT = Path(__file__).resolve().parents[1]
#: Issue 14, item 5: install and workflow, and the workflow alone [s].
TARGET_TOTAL_S, TARGET_WORKFLOW_S = 240.0, 150.0


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _timed(cmd, cwd, log):
    """Wall and CPU time [s] of ``cmd`` (its whole process tree, waited for)."""
    cpu0, t0 = _children_cpu(), time.perf_counter()
    with open(log, "w") as fh:
        run = subprocess.run(cmd, cwd=cwd, stdout=fh, stderr=subprocess.STDOUT)
    wall, cpu = time.perf_counter() - t0, _children_cpu() - cpu0
    if run.returncode:
        sys.exit(f"{' '.join(cmd)} failed with exit status {run.returncode}: see {log}")
    return wall, cpu


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="results/bench")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--keep", type=Path, help="clone into this new folder and keep it (its results/ for make docs)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    load = os.getloadavg()
    with tempfile.TemporaryDirectory(prefix="rocklab-clone-") as tmp:
        clone = args.keep or Path(tmp) / "rocklab"
        subprocess.run(["git", "clone", "--quiet", str(ROOT), str(clone)], check=True)
        # the clone is HEAD's code: what the README and the performance page quote (tests/test_docs.py)
        measured = measured_code(clone, "bench/fresh_clone.py")
        make = ["make", f"CORES={args.cores}"]
        install_s, install_cpu = _timed([*make, "venv"], clone, out / "fresh_clone_install.log")
        workflow_s, workflow_cpu = _timed([*make, "run"], clone, out / "fresh_clone_run.log")
    total = install_s + workflow_s
    result = {
        "commit": commit,
        "measured": measured,
        "cores": args.cores,
        "load_before": list(load),
        "install_s": install_s,
        "workflow_s": workflow_s,
        "total_s": total,
        "install_cpu_s": install_cpu,
        "workflow_cpu_s": workflow_cpu,
        "target_total_s": TARGET_TOTAL_S,
        "target_workflow_s": TARGET_WORKFLOW_S,
        "total_over_target": total / TARGET_TOTAL_S,
        "workflow_over_target": workflow_s / TARGET_WORKFLOW_S,
    }
    (out / "fresh_clone.json").write_text(json.dumps(result, indent=2) + "\n")
    print(
        f"fresh clone of {commit[:8]}: install {install_s:.0f} s + workflow {workflow_s:.0f} s "
        f"(CPU {workflow_cpu:.0f} s) = {total:.0f} s on {args.cores} cores, load before {load[0]:.1f}; "
        f"ratio to target: total {result['total_over_target']:.2f}, workflow {result['workflow_over_target']:.2f}"
    )
    return 0 if total <= TARGET_TOTAL_S and workflow_s <= TARGET_WORKFLOW_S else 1


if __name__ == "__main__":
    sys.exit(main())
