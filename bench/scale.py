"""Benchmark: the campaign workflow on virtual-lab campaigns of growing size.

    python bench/scale.py --out results/bench [--sizes 100 1000] [--cores 2]

Builds a virtual-lab campaign of each size (``rocklab.lab.virtual_lab``) and
runs the campaign's part of the main job on it (``snakemake campaign``:
reduction, QC, dissipation, diagnosis, their figures and pages; the maps and
the limestone blocks do not depend on the campaign) with ``--cores``.  For
each size: wall time, peak resident memory of the whole process tree
(Snakemake and its jobs, summed at each sample of ``psutil``, every 0.2 s)
and of its largest process, the CPU time of the whole tree (less sensitive
than the wall time to the load of a shared machine), and the job time of
each stage (Snakemake's benchmark files).  The CPU time per test between two sizes, and the CPU
time a campaign ten times the embedded one would take on that line, are
written to ``<out>/scale.json``; the extrapolation is only given when the
job time per test of the reduction, the largest stage, grows by less than
25 % between the sizes (at most linear).

To build large campaigns quickly, a few virtual tests are simulated (every
anomaly of ``default_plan`` among them) and their records copied under new
ids, each with its own ``# test_id`` line: every copy is reduced in full.
"""

from __future__ import annotations

import argparse
import gzip
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd
import psutil

from rocklab.benchmarks import benchmark_times, measured_code
from rocklab.lab import virtual_lab

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
#: Tests of the embedded campaign (raw/campaign/tests.csv), the unit of "ten times".
EMBEDDED = ROOT / "raw" / "campaign" / "tests.csv"
#: Distinct virtual tests simulated; the rest of a campaign are copies of their records.
DISTINCT = 20


def build_campaign(folder: Path, n_tests: int, seed: int = 0) -> None:
    """A campaign of ``n_tests`` tests from :data:`DISTINCT` simulated ones."""
    seeds = folder.parent / f"seed-{seed}"
    if not seeds.exists():
        virtual_lab.write_campaign(seeds, virtual_lab.default_plan(DISTINCT, seed=seed), seed=seed)
    (folder / "tests").mkdir(parents=True)
    for name in ("specimens.csv", "setups.csv"):
        shutil.copy(seeds / name, folder / name)
    base = pd.read_csv(seeds / "tests.csv", dtype=str, keep_default_na=False)
    rows = []
    for k in range(n_tests):
        row = base.iloc[k % len(base)].copy()
        blob = (seeds / row.file).read_bytes()
        test_id = f"S{k + 1:05d}"
        try:
            text = gzip.decompress(blob).decode()
        except EOFError:  # the plan's broken transfer: copied as it is
            pass
        else:
            text = text.replace(f"# test_id: {row.test_id}", f"# test_id: {test_id}", 1)
            blob = gzip.compress(text.encode(), compresslevel=1, mtime=0)
        row["test_id"], row["file"] = test_id, f"tests/{test_id}.csv.gz"
        (folder / row.file).write_bytes(blob)
        rows.append(row)
    pd.DataFrame(rows).to_csv(folder / "tests.csv", index=False)


def _tree_rss(proc: psutil.Process) -> tuple[int, int]:
    """Summed and largest resident memory [bytes] of a process and its descendants."""
    rss = []
    for p in [proc, *proc.children(recursive=True)]:
        try:
            rss.append(p.memory_info().rss)
        except psutil.Error:
            continue
    return sum(rss), max(rss, default=0)


def stage_times(results: Path) -> dict:
    """Per stage (the first folder or file of results/benchmarks): the job
    time [s] summed (``stage_s``), the jobs (``stage_jobs``) and the longest
    job [s] (``stage_longest_s``), which a cluster's projection spreads
    (:func:`rocklab.benchmarks.cluster_projection`)."""
    by_stage = benchmark_times(results).groupby("stage").s
    return {
        "stage_s": by_stage.sum().to_dict(),
        "stage_jobs": by_stage.size().to_dict(),
        "stage_longest_s": by_stage.max().to_dict(),
    }


def run_snakemake(args: list, log_path: Path) -> dict:
    """Run Snakemake in the checkout with ``args``: its wall time, the CPU
    time of Snakemake and all its jobs, that of Snakemake's own process
    (building the DAG, scheduling, checking outputs; sampled every 0.2 s),
    and the peak resident memory of them all together and of the largest."""
    cmd = [str(SNAKEMAKE), *args, "--quiet", "--directory", str(ROOT)]
    log = log_path.open("w")
    load = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT)
    ps = psutil.Process(proc.pid)
    peak_tree = peak_one = own = 0
    while proc.poll() is None:
        tree, one = _tree_rss(ps)
        peak_tree, peak_one = max(peak_tree, tree), max(peak_one, one)
        try:  # Snakemake's own process, its jobs aside: the last sample before it ends
            own = sum(ps.cpu_times()[:2])
        except psutil.Error:
            pass
        time.sleep(0.2)
    wall = time.perf_counter() - start
    # every process of the tree, once waited for, is counted in its parent's children
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if proc.returncode:
        raise RuntimeError(f"snakemake failed ({proc.returncode}), see {log.name}")
    return {
        "wall_s": wall,
        "cpu_s": cpu,
        "snakemake_cpu_s": own,
        "load_avg_1min_before": load,
        "peak_rss_tree_mb": peak_tree / 2**20,
        "peak_rss_process_mb": peak_one / 2**20,
    }


def run_workflow(campaign: Path, results: Path, cores: int) -> dict:
    """Wall time, peak memory and stage times of ``snakemake campaign``."""
    # Fig. 9b of a specimen of the virtual lab (the default is one of the embedded campaign)
    config = [f"raw_dir={campaign}", f"results_dir={results}", "figures={'fig9_specimen': '1a'}"]
    args = ["campaign", "--cores", str(cores), "--config", *config]
    return {**run_snakemake(args, results.parent / f"{results.name}.log"), **stage_times(results)}


def summary(runs: list, cores: int, baseline: dict | None = None) -> dict:
    """The runs, and the line through the smallest and the largest campaign;
    with ``baseline`` (another checkout's ``scale.json`` on the same sizes),
    its wall and CPU times and the ratio of the largest campaign's wall times."""
    out = {"cores": cores, "cpu_count": os.cpu_count(), "load_avg_1min": os.getloadavg()[0], "runs": runs}
    # the code these numbers are of: the README and the performance page quote them for it (tests/test_docs.py)
    out["measured"] = measured_code(ROOT, "bench/scale.py")
    if baseline is not None:
        old = {r["n_tests"]: r for r in baseline["runs"]}
        out["baseline"] = {
            "label": baseline.get("label"),
            "runs": [
                {k: old[r["n_tests"]][k] for k in ("n_tests", "wall_s", "cpu_s", "peak_rss_tree_mb")}
                for r in runs
                if r["n_tests"] in old
            ],
        }
        if runs[-1]["n_tests"] in old:
            out["baseline"]["largest_wall_ratio"] = runs[-1]["wall_s"] / old[runs[-1]["n_tests"]]["wall_s"]
    if len(runs) < 2:
        return out
    small, large = runs[0], runs[-1]
    per_test = (large["wall_s"] - small["wall_s"]) / (large["n_tests"] - small["n_tests"])
    fixed = small["wall_s"] - per_test * small["n_tests"]
    cpu_per_test = (large["cpu_s"] - small["cpu_s"]) / (large["n_tests"] - small["n_tests"])
    reduce_per_test = [r["stage_s"].get("reduce", 0.0) / r["n_tests"] for r in runs]
    # the start of each job spreads over more tests in a larger campaign: at most linear is the bound;
    # CPU time, not wall time, which the load of a shared machine blurs
    at_most_linear = reduce_per_test[-1] <= 1.25 * reduce_per_test[0] and cpu_per_test > 0
    n_ten = 10 * (len(pd.read_csv(EMBEDDED)) if EMBEDDED.exists() else 614)
    out.update(
        wall_s_per_test=per_test,
        fixed_s=fixed,
        cpu_s_per_test=cpu_per_test,
        cpu_fixed_s=small["cpu_s"] - cpu_per_test * small["n_tests"],
        reduce_s_per_test=reduce_per_test,
        memory_ratio=large["peak_rss_tree_mb"] / small["peak_rss_tree_mb"],
        at_most_linear=bool(at_most_linear),
        ten_times_embedded={
            "n_tests": n_ten,
            "cpu_s": small["cpu_s"] + cpu_per_test * (n_ten - small["n_tests"]) if at_most_linear else None,
        },
    )
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/bench"))
    ap.add_argument("--sizes", type=int, nargs="+", default=[100, 1000])
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument(
        "--baseline",
        type=Path,
        help="scale.json of another checkout (run there on the same sizes, on the same machine) to compare with",
    )
    ap.add_argument("--label", help="what --baseline measured (e.g. its commit)")
    ap.add_argument(
        "--workdir", type=Path, default=None, help="where campaigns and results go (default: a temp folder)"
    )
    args = ap.parse_args(argv)
    work = Path(args.workdir or tempfile.mkdtemp(prefix="rocklab-scale-"))
    baseline = {**json.loads(args.baseline.read_text()), "label": args.label} if args.baseline else None
    runs = []
    for n in sorted(args.sizes):
        campaign, results = work / f"campaign-{n}", work / f"results-{n}"
        shutil.rmtree(campaign, ignore_errors=True)
        shutil.rmtree(results, ignore_errors=True)
        t0 = time.perf_counter()
        build_campaign(campaign, n)
        built = time.perf_counter() - t0
        run = {"n_tests": n, "build_s": built, **run_workflow(campaign, results, args.cores)}
        print(f"{n} tests: {run['wall_s']:.1f} s, peak {run['peak_rss_tree_mb']:.0f} MB", flush=True)
        runs.append(run)
        # after each size, so that a long run cut short keeps what it measured
        out = summary(runs, args.cores, baseline)
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "scale.json").write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps({k: v for k, v in out.items() if k != "runs"}, indent=2))


if __name__ == "__main__":
    main()
