"""Benchmark: the main job, what `make run` runs once installed, stage by stage.

    python bench/workflow.py --out results/bench [--cores 2] [--workdir DIR]

Runs the whole workflow (``snakemake all``: the embedded campaign, the
overturning maps, the limestone blocks and the docs pages) from scratch
into an empty results folder with ``--cores``, and writes
``<out>/workflow.json``: the wall time of the run against the target of
issue 14 (at most :data:`TARGET_S` on two cores), the CPU time of
Snakemake and all its jobs (exact, from the kernel: the robust number on a
shared machine, where the wall time follows the load), the peak resident
memory, and per stage (a rule, or a folder of jobs of
``results/benchmarks``: the reduction, the diagnosis, the maps) the jobs,
their job time summed, the longest and their CPU time (Snakemake's samples:
a lower bound for jobs longer than 30 s).  The job times summed over the
wall time tell how busy the cores were kept (at most ``--cores``); the CPU
time of Snakemake's own process (building the DAG, again after each
checkpoint, scheduling, checking outputs) is measured apart.

Exits 1 when the run takes longer than the target.  The numba cache of the
checkout is kept (a fresh clone compiles once, in its first run).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import tempfile
from pathlib import Path

from scale import run_snakemake

from rocklab.benchmarks import benchmark_times

#: Wall time [s] of the main job on two cores, install aside (issue 14).
TARGET_S = 150.0


def stages(results: Path) -> dict:
    """Jobs, job time [s] summed and longest, and CPU time [s] of each stage of a run."""
    jobs = benchmark_times(results)
    grouped = jobs.groupby("stage", sort=False)
    table = grouped.agg(jobs=("s", "size"), job_s=("s", "sum"), longest_s=("s", "max"), cpu_s=("cpu_s", "sum"))
    table = table.sort_values("job_s", ascending=False)
    return {stage: {k: float(v) if k != "jobs" else int(v) for k, v in row.items()} for stage, row in table.iterrows()}


def summary(run: dict, by_stage: dict, cores: int) -> dict:
    """The run, its stages and the target."""
    job_s = sum(s["job_s"] for s in by_stage.values())
    job_cpu = sum(s["cpu_s"] for s in by_stage.values())
    return {
        "cores": cores,
        "cpu_count": os.cpu_count(),
        **run,
        "n_jobs": sum(s["jobs"] for s in by_stage.values()),
        "job_s": job_s,
        "job_cpu_s": job_cpu,
        # how many cores the jobs kept busy on average (at most `cores`)
        "job_s_over_wall": job_s / run["wall_s"],
        "stages": by_stage,
        "target_s": TARGET_S,
        "wall_over_target": run["wall_s"] / TARGET_S,
        "pass": bool(run["wall_s"] <= TARGET_S),
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/bench"))
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--workdir", type=Path, default=None, help="where the results go (default: a temp folder)")
    args = ap.parse_args(argv)
    work = Path(args.workdir or tempfile.mkdtemp(prefix="rocklab-workflow-"))
    work.mkdir(parents=True, exist_ok=True)
    results = work / "results"
    shutil.rmtree(results, ignore_errors=True)
    run = run_snakemake(
        ["all", "--cores", str(args.cores), "--config", f"results_dir={results}"], work / "workflow.log"
    )
    out = summary(run, stages(results), args.cores)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "workflow.json").write_text(json.dumps(out, indent=2) + "\n")
    for stage, s in out["stages"].items():
        print(f"{stage:28s} {s['jobs']:4d} jobs  {s['job_s']:7.1f} s job time  {s['cpu_s']:7.1f} s CPU")
    verdict = "pass" if out["pass"] else "FAIL"
    print(
        f"workflow: {out['wall_s']:.0f} s wall on {args.cores} cores, {out['cpu_s']:.0f} s CPU, "
        f"job time {out['job_s']:.0f} s ({out['job_s_over_wall']:.2f} x the wall); "
        f"target {TARGET_S:.0f} s: {out['wall_over_target']:.2f} of it ({verdict})"
    )
    if not out["pass"]:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
