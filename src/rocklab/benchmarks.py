"""What the workflow's own timings publish for the docs: the job times and ``make bench``.

Snakemake writes a job's benchmark file once the job is done, so the
timings of a run are complete only at its end: the docs rule makes this
summary (:func:`performance_summary`) from ``results/benchmarks`` and, when
``make bench`` has run, ``results/bench/*.json``. Timings change from run to
run: the pages quote them, the check of the committed pages leaves them out
(:data:`rocklab.report.docs.VOLATILE`).
"""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from rocklab.io import benchmark_times


def _benchmarks(results: Path) -> dict:
    """Job times of the workflow from Snakemake's benchmark files: one entry
    per single-job rule (``<rule>.tsv``) and one per folder of jobs
    (``<folder>/<job>.tsv``, keyed ``<folder>_jobs``)."""
    out = {}
    for job in benchmark_times(results).itertuples():
        rule = f"{job.stage}_jobs" if "/" in job.job else job.stage
        entry = out.setdefault(rule, {"jobs": 0, "total_s": 0.0, "longest_s": 0.0})
        entry["jobs"] += 1
        entry["total_s"] += job.s
        entry["longest_s"] = max(entry["longest_s"], job.s)
    return out


def _bench(results: Path, name: str):
    path = results / "bench" / f"{name}.json"
    return json.loads(path.read_text()) if path.is_file() else None


def _scale(bench: dict) -> dict:
    """The smallest and largest campaign of ``bench/scale.py`` and the line through them."""
    runs = {"small": bench["runs"][0], "large": bench["runs"][-1]}
    keys = {"n_tests": "n_tests", "s": "wall_s", "cpu_s": "cpu_s", "peak_mb": "peak_rss_tree_mb"}
    keys["load"] = "load_avg_1min_before"
    keys["snakemake_cpu_s"] = "snakemake_cpu_s"
    out = {f"{size}_{k}": run.get(key) for size, run in runs.items() for k, key in keys.items()}
    per_test = bench.get("reduce_s_per_test") or [None, None]
    out["small_reduce_s_per_test"], out["large_reduce_s_per_test"] = per_test[0], per_test[-1]
    ten = bench.get("ten_times_embedded") or {}
    cpu_ten = ten.get("cpu_s")
    return {
        "cores": bench["cores"],
        **out,
        "cpu_s_per_test": bench.get("cpu_s_per_test"),
        "memory_ratio": bench.get("memory_ratio"),
        "at_most_linear": bench.get("at_most_linear"),
        "ten_times_n_tests": ten.get("n_tests"),
        "ten_times_cpu_s": cpu_ten,
        "ten_times_wall_s_at_least": cpu_ten / bench["cores"] if cpu_ten is not None else None,
    }


def performance_summary(results) -> dict:
    """Timings: the workflow's job times and, when measured, ``make bench``.

    Parameters
    ----------
    results : str or pathlib.Path
        The results folder of a finished run.

    Returns
    -------
    dict
        ``jobs`` (jobs, total and longest time per rule or folder of jobs),
        ``n_jobs``, ``total_job_s``, ``shake_table`` (the job times of the
        target ``shake_table``, ``None`` where it did not run) and one entry
        per benchmark of ``make bench`` (``None`` where it did not run).
    """
    results = Path(results)
    jobs = _benchmarks(results)
    out = {
        "jobs": jobs,
        "n_jobs": sum(j["jobs"] for j in jobs.values()),
        "total_job_s": sum(j["total_s"] for j in jobs.values()),
    }
    kin = _bench(results, "kinematics")
    out["kinematics"] = (
        {k: kin[k] for k in ("record", "n_steps", "batched_s", "scipy_loop_s", "ratio", "max_abs_diff_theta_rad")}
        if kin
        else None
    )
    sim = _bench(results, "simulator")
    keys = ("histories", "t_batch_s", "t_reference_s", "speedup", "overturned_batch", "overturned_reference")
    out["simulator"] = (
        {
            **{k: sim[k] for k in keys},
            "mismatches": sim["mismatches"],
            "mismatches_beyond_tolerance": len(sim["mismatches_beyond_tolerance"]),
            "pass": sim["pass"],
        }
        if sim
        else None
    )
    mp = _bench(results, "maps")
    out["maps"] = (
        {
            "map_s": {m: v["map_s"] for m, v in mp["models"].items()},
            **{
                k: mp[k]
                for k in ("reference_s_per_history", "speedup_vs_reference", "all_maps_count", "all_maps_s", "pass")
            },
        }
        if mp
        else None
    )
    wf = _bench(results, "workflow")
    keys = ("cores", "wall_s", "cpu_s", "peak_rss_tree_mb", "load_avg_1min_before", "n_jobs", "job_s")
    keys += ("job_s_over_wall", "snakemake_cpu_s", "target_s", "wall_over_target", "pass", "stages")
    out["workflow"] = {k: wf[k] for k in keys} if wf else None
    fc = _bench(results, "fresh_clone")
    keys = ("cores", "load_before", "install_s", "workflow_s", "total_s", "install_cpu_s", "workflow_cpu_s")
    keys += ("target_total_s", "target_workflow_s", "total_over_target", "workflow_over_target")
    out["fresh_clone"] = {k: fc[k] for k in keys} | {"load_1min": fc["load_before"][0]} if fc else None
    sc = _bench(results, "scale")
    out["scale"] = _scale(sc) if sc else None
    ref = _bench(results, "maps_reference")
    out["maps_reference"] = (
        {
            "records": ref["records"],
            "workers": ref["workers"],
            "total_s": ref["total_s"],
            "complete": ref["complete"],
            "n_maps": len(ref["maps"]),
            "agreement_pct_min": min(m["agreement_pct"] for m in ref["maps"]),
            "n_full_agreement": sum(m["agreement_pct"] == 100 for m in ref["maps"]),
            "off_boundary": sum(m["unexplained"] for m in ref["maps"]),
            "pass": ref["pass"],
        }
        if ref
        else None
    )
    out["shake_table"] = shake_table_times(results)
    return out


def shake_table_times(results) -> dict | None:
    """Wall-clock and CPU time of each job of the target ``shake_table`` [s]; None where it did not run.

    Under a loaded machine the CPU time is the one that compares from run to run.
    """
    bench = {
        t.stem: pd.read_csv(t, sep="\t").iloc[0]
        for t in sorted((Path(results) / "benchmarks" / "shake_table").glob("*.tsv"))
    }
    if not bench:
        return None
    job_times = {k: float(b["s"]) for k, b in bench.items()}
    job_cpu = {k: float(b["cpu_time"]) for k, b in bench.items()}
    return {
        "job_time_s": sum(job_times.values()),
        "job_times_s": job_times,
        "job_cpu_s": job_cpu,
        "job_cpu_total_s": sum(job_cpu.values()),
    }
