"""What the workflow's own timings publish for the docs: the job times and ``make bench``.

Snakemake writes a job's benchmark file once the job is done, so the
timings of a run are complete only at its end: the docs rule makes this
summary (:func:`performance_summary`) from ``results/benchmarks`` and, when
``make bench`` has run, ``results/bench/*.json``. Timings change from run to
run: the pages quote them, the check of the committed pages leaves them out
(:data:`rocklab.report.docs.VOLATILE`).
"""

from __future__ import annotations

import hashlib
import json
import math
import subprocess
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import yaml

#: What can change a benchmark's numbers: the library, the workflow, its scripts, settings and
#: build, the pinned packages (and the benchmark's own script, :func:`measured_code`'s ``extra``).
CODE_PATHS = (
    "src/rocklab",
    "scripts",
    "workflow",
    "Snakefile",
    "config",
    "requirements.lock",
    "pyproject.toml",
    "Makefile",
)
#: The benchmarks whose numbers the README quotes: each must be a measurement of the code it describes.
QUOTED = {"fresh_clone": "bench/fresh_clone.py", "scale": "bench/scale.py"}


def benchmark_times(results: str | Path) -> pd.DataFrame:
    """The jobs of a workflow run from Snakemake's benchmark files.

    Parameters
    ----------
    results : path-like
        A results folder; its ``benchmarks/`` holds one ``<rule>.tsv`` per
        single-job rule and ``<folder>/<job>.tsv`` per job of a stage of
        many jobs (the reduction, the diagnosis, the maps).

    Returns
    -------
    pandas.DataFrame
        One row per job: ``stage`` (the rule or the folder), ``job`` (the
        file's path under ``benchmarks/`` without ``.tsv``), ``s`` (wall time
        of the job [s]) and ``cpu_s`` (its CPU time [s], NaN where the file
        has none: Snakemake samples it once a second for the first 30 s of a
        job and every 30 s after, so it is a lower bound for a long job).
    """
    root = Path(results) / "benchmarks"
    rows = []
    for tsv in sorted(root.rglob("*.tsv")) if root.is_dir() else []:
        job = tsv.relative_to(root).with_suffix("")
        last = pd.read_csv(tsv, sep="\t").iloc[-1]
        rows.append(
            {
                "stage": job.parts[0],
                "job": job.as_posix(),
                "s": float(last["s"]),
                "cpu_s": float(last.get("cpu_time", np.nan)),
            }
        )
    return pd.DataFrame(rows, columns=["stage", "job", "s", "cpu_s"])


def measured_code(checkout: str | Path, *extra: str) -> dict[str, Any]:
    """The code a benchmark measures in the git checkout ``checkout``.

    Returns
    -------
    dict
        ``commit`` (HEAD), ``code`` (a hash of the git objects of :data:`CODE_PATHS` and ``extra`` at
        HEAD: two commits whose code is the same have the same, whatever else they change: the
        pages a measurement regenerates, the changelog), ``dirty`` (whether the working tree's code
        differs from HEAD's: then the numbers are those of no commit) and ``paths``.

    Raises
    ------
    RuntimeError
        Where ``checkout`` is no git checkout: what was measured cannot be told.
    """
    paths = [*CODE_PATHS, *extra]

    def git(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(["git", *args], cwd=checkout, capture_output=True, text=True)

    head, tree = git("rev-parse", "HEAD"), git("ls-tree", "-r", "HEAD", "--", *paths)
    if head.returncode or tree.returncode:
        raise RuntimeError(f"{checkout} is no git checkout: {(head.stderr or tree.stderr).strip()}")
    dirty = git("diff", "--quiet", "HEAD", "--", *paths).returncode != 0
    code = hashlib.sha256(tree.stdout.encode()).hexdigest()[:16]
    return {"commit": head.stdout.strip(), "code": code, "dirty": dirty, "paths": paths}


def _benchmarks(results: Path) -> dict[str, dict[str, float]]:
    """Job times of the workflow from Snakemake's benchmark files: one entry
    per single-job rule (``<rule>.tsv``) and one per folder of jobs
    (``<folder>/<job>.tsv``, keyed ``<folder>_jobs``)."""
    out: dict[str, dict[str, float]] = {}
    for job in benchmark_times(results).itertuples():
        rule = f"{job.stage}_jobs" if "/" in job.job else job.stage
        entry = out.setdefault(rule, {"jobs": 0, "total_s": 0.0, "longest_s": 0.0})
        entry["jobs"] += 1
        entry["total_s"] += job.s
        entry["longest_s"] = max(entry["longest_s"], job.s)
    return out


def _bench(results: Path, name: str) -> Any:
    """The JSON of the benchmark ``name`` (``results/bench/<name>.json``), None where it did not run."""
    path = results / "bench" / f"{name}.json"
    return json.loads(path.read_text()) if path.is_file() else None


def _scale(bench: Mapping[str, Any]) -> dict[str, Any]:
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
    # another checkout's run on the same sizes and machine (bench/scale.py --baseline)
    base = bench.get("baseline") or {}
    old = {r["n_tests"]: r for r in base.get("runs", [])}
    for size, run in runs.items():
        out[f"baseline_{size}_s"] = old.get(run["n_tests"], {}).get("wall_s")
        out[f"baseline_{size}_cpu_s"] = old.get(run["n_tests"], {}).get("cpu_s")
        out[f"baseline_{size}_peak_mb"] = old.get(run["n_tests"], {}).get("peak_rss_tree_mb")
    out["baseline_label"] = base.get("label")
    out["large_over_baseline"] = base.get("largest_wall_ratio")
    return {
        "cores": bench["cores"],
        "measured": bench.get("measured"),
        **out,
        "cpu_s_per_test": bench.get("cpu_s_per_test"),
        "memory_ratio": bench.get("memory_ratio"),
        "at_most_linear": bench.get("at_most_linear"),
        "ten_times_n_tests": ten.get("n_tests"),
        "ten_times_cpu_s": cpu_ten,
        "ten_times_wall_s_at_least": cpu_ten / bench["cores"] if cpu_ten is not None else None,
    }


#: The project's SLURM profile (workflow/profiles/slurm), relative to the checkout the workflow runs in.
SLURM_PROFILE = Path("workflow") / "profiles" / "slurm"
#: Nodes and cores per node of the clusters the projection spreads the work on (an assumption: a
#: common compute node; the profile's jobs ask no more than that).
CLUSTER_NODES = (1, 4, 16)
CORES_PER_NODE = 32
#: Projected campaign: this many times the embedded one.
CAMPAIGN_FACTOR = 100
#: Projected maps: every shipped record, every map model (the paper's and the calibrated walls'),
#: on this many cells a side.
MAP_CELLS = 801
#: Map models of each map job: the paper's (rule overturning_maps) and the calibrated walls'
#: (rule calibrated_maps, at most 9: workflow/rules/seismic.smk).
MAP_JOB_MODELS = {"overturning_maps": 5, "calibrated_maps": 9}


def slurm_profile(root: str | Path) -> dict[str, Any]:
    """What the SLURM profile of the checkout ``root`` asks for each job: ``mem_mb``,
    ``runtime`` [min] and ``cpus_per_task`` by default, ``jobs`` (at most at once),
    and the map jobs' ``threads`` and ``records_per_job`` (its ``maps.yaml``)."""
    folder = Path(root) / SLURM_PROFILE
    profile = yaml.safe_load((folder / "config.yaml").read_text())
    maps = yaml.safe_load((folder / "maps.yaml").read_text())["maps"]
    return {**profile["default-resources"], "jobs": profile["jobs"], **{f"maps_{k}": v for k, v in maps.items()}}


def _waves(jobs: int, slots: int) -> int:
    return math.ceil(jobs / max(slots, 1))


def campaign_projection(
    scale: Mapping[str, Any], profile: Mapping[str, Any], n_embedded: int, max_tests_per_job: int
) -> dict[str, Any]:
    """A campaign :data:`CAMPAIGN_FACTOR` times the embedded one on a SLURM cluster.

    From the two campaigns of ``bench/scale.py`` (``scale``): each stage's
    job time on the line through them (linear in the tests: the bench's
    ``at_most_linear``); the reduction in jobs of ``max_tests_per_job``
    tests, every other stage in as many jobs as in the larger campaign, its
    longest job grown with the stage.  On ``N`` nodes of
    :data:`CORES_PER_NODE` cores, each job one core (the profile's
    ``cpus_per_task``), a stage takes its job time over the cores or its
    longest job, whichever is longer, and the stages follow one another: an
    upper bound (the dissipation and diagnosis branches run at once),
    without SLURM's queueing and start of each job.
    """
    small, large = scale["runs"][0], scale["runs"][-1]
    n = CAMPAIGN_FACTOR * n_embedded
    stages: dict[str, dict[str, float]] = {}
    for stage, s_large in large["stage_s"].items():
        s_small = small["stage_s"].get(stage, 0.0)
        slope = (s_large - s_small) / (large["n_tests"] - small["n_tests"])
        job_s = max(s_large + slope * (n - large["n_tests"]), s_large)
        if stage == "reduce":
            jobs = math.ceil(n / max_tests_per_job)
            longest = job_s / jobs
        else:
            jobs = large["stage_jobs"][stage]
            longest = large["stage_longest_s"][stage] * job_s / s_large if s_large else 0.0
        stages[stage] = {"jobs": jobs, "job_s": job_s, "longest_s": longest}
    slots = {nodes: nodes * CORES_PER_NODE // profile["cpus_per_task"] for nodes in CLUSTER_NODES}
    return {
        "n_tests": n,
        "stages": stages,
        "jobs": sum(st["jobs"] for st in stages.values()),
        "job_s": sum(st["job_s"] for st in stages.values()),
        "largest_process_mb": large["peak_rss_process_mb"],
        "mem_mb": profile["mem_mb"],
        "fits_mem": large["peak_rss_process_mb"] <= profile["mem_mb"],
        "longest_job_s": max(st["longest_s"] for st in stages.values()),
        "runtime_min": profile["runtime"],
        "wall_s": [sum(max(st["job_s"] / k, st["longest_s"]) for st in stages.values()) for k in slots.values()],
    }


def maps_projection(maps: Mapping[str, Any], profile: Mapping[str, Any]) -> dict[str, Any]:
    """Every map model of every shipped record on :data:`MAP_CELLS` x
    :data:`MAP_CELLS` cells on a SLURM cluster.

    From ``bench/maps.py`` (``maps``): the CPU time of one history, its maps'
    CPU time over their cells (the same kind of histories on a finer grid:
    linear in the cells); the profile's map jobs, one per record and rule
    (``maps_records_per_job``), each on ``maps_threads`` cores, which numba
    keeps busy (the job's wall time its CPU time over its threads).  On
    ``N`` nodes of :data:`CORES_PER_NODE` cores, as many jobs at once as
    fit, in waves of the longest (calibrated) job.
    """
    n_records = len(maps["all_maps_records"])
    per_cell = maps["all_maps_cpu_s"] / (maps["all_maps_count"] * maps["grid"][0] * maps["grid"][1])
    map_cpu_s = per_cell * MAP_CELLS**2
    threads = profile["maps_threads"]
    per_job = profile["maps_records_per_job"]
    jobs = {rule: math.ceil(n_records / per_job) for rule in MAP_JOB_MODELS}
    job_wall_s = {rule: map_cpu_s * models * per_job / threads for rule, models in MAP_JOB_MODELS.items()}
    slots = {nodes: nodes * (CORES_PER_NODE // threads) for nodes in CLUSTER_NODES}
    return {
        "records": n_records,
        "models": sum(MAP_JOB_MODELS.values()),
        "cells": MAP_CELLS,
        "measured_grid": maps["grid"][0],
        "map_cpu_s": map_cpu_s,
        "cpu_s": map_cpu_s * n_records * sum(MAP_JOB_MODELS.values()),
        "jobs": sum(jobs.values()),
        "threads": threads,
        "job_wall_s": job_wall_s,
        # one variable of the map: float64 per cell
        "grid_mb": 8 * MAP_CELLS**2 / 1e6,
        "wall_s": [_waves(sum(jobs.values()), k) * max(job_wall_s.values()) for k in slots.values()],
    }


def performance_summary(results: str | Path, checkout: str | Path | None = None) -> dict[str, Any]:
    """Timings: the workflow's job times and, when measured, ``make bench``.

    Parameters
    ----------
    results : str or pathlib.Path
        The results folder of a finished run.
    checkout : str or pathlib.Path, optional
        The repository whose SLURM profile, configuration and embedded
        campaign the cluster projection reads; without it, no projection.

    Returns
    -------
    dict
        ``jobs`` (jobs, total and longest time per rule or folder of jobs),
        ``n_jobs``, ``total_job_s``, ``shake_table`` (the job times of the
        target ``shake_table``, ``None`` where it did not run) and one entry
        per benchmark of ``make bench`` (``None`` where it did not run;
        ``discovery``, the diagnosis' calibration, with its series one by one
        and what each missed; ``video_tracking`` and ``native_accuracy``, the
        native files of issue 43), and ``projection`` (``None`` without ``checkout``).
    """
    results = Path(results)
    jobs = _benchmarks(results)
    out: dict[str, Any] = {
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
    keys: tuple[str, ...] = (
        "histories",
        "t_batch_s",
        "t_reference_s",
        "speedup",
        "overturned_batch",
        "overturned_reference",
    )
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
    out["fresh_clone"] = (
        {k: fc[k] for k in keys} | {"load_1min": fc["load_before"][0], "measured": fc.get("measured")} if fc else None
    )
    sc = _bench(results, "scale")
    out["scale"] = _scale(sc) if sc else None
    out["projection"] = _projection(sc, mp, checkout) if checkout is not None else None
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
    disc = _bench(results, "discovery")
    out["discovery"] = _discovery(disc) if disc else None
    env = _bench(results, "environments")
    out["environments"] = _environments(env) if env else None
    vt = _bench(results, "video_tracking")
    keys = ("seconds", "fps", "frames", "frame_px", "track_cpu_s", "frames_per_s", "frames_tracked", "target_s", "pass")
    out["video_tracking"] = {k: vt[k] for k in keys} if vt else None
    na = _bench(results, "native_accuracy")
    keys = ("n_tests", "film_px", "marker_px", "resolved_e", "formats", "target_e", "pass")
    out["native_accuracy"] = {k: na[k] for k in keys} if na else None
    return out


#: Moves the docs list one by one: those nearest their tolerance.
SHOWN_MOVES = 25


def _environments(bench: Mapping[str, Any]) -> dict[str, Any]:
    """The published numbers under other floating-point environments (``bench/environments.py``):
    per section, the floats, how many moved and the nearest any came to its tolerance; the moves
    nearest their tolerance one by one."""
    moves = bench["moves"]
    sections: dict[str, dict[str, Any]] = {}
    for section, n in bench["n_floats"].items():
        mine = [m for m in moves if m["number"].split(".", 1)[0] == section]
        sections[section] = {
            "n_floats": n,
            "n_moved": len(mine),
            "max_headroom": max((m["headroom"] for m in mine if m["headroom"] is not None), default=0.0),
            "n_beyond": sum(not m["admitted"] for m in mine),
        }
    nearest = sorted(moves, key=lambda m: -(m["headroom"] if m["headroom"] is not None else float("inf")))
    return {
        "commit": bench["commit"][:8],
        "cpu": bench["cpu"],
        "environments": bench["environments"],
        # the order of the columns (a summary's keys are sorted when written)
        "runs": list(next(iter(moves), {"values": {}})["values"]),
        "wall_s": bench["wall_s"],
        "sections": sections,
        "n_moved": len(moves),
        "n_beyond": sum(not m["admitted"] for m in moves),
        "nearest": nearest[:SHOWN_MOVES],
    }


def _miss(cell: Mapping[str, Any]) -> str:
    """What a series of ``bench/discovery.py`` got wrong, in words ("" where it was named right); a series
    whose design cannot carry its hidden cause says so and why."""
    if cell["named_right"]:
        return ""
    out: list[str] = []
    if cell["not_identifiable"]:
        out.append(f"not identifiable: {cell['why_not_identifiable']}")
    elif cell["missing"]:
        out.append(f"not named: {', '.join(cell['missing'])}")
    if cell["wrong"]:
        stand = cell["may_stand_in_for"]
        flag = {c: "flagged unexplained" if cell["unexplained"] else "not flagged" for c in cell["wrong"]}
        flag |= {
            c: f"may stand in for {', '.join(v)}, which the design cannot identify or these tests cannot tell from it"
            for c, v in stand.items()
        }
        out.append("named beside the truth: " + "; ".join(f"{c} ({why})" for c, why in flag.items()))
    if cell["outside_joint"]:
        out.append(f"the verdict's intervals miss the truth: {'; '.join(cell['outside_joint'])}")
    return "; ".join(out)


def _discovery(bench: Mapping[str, Any]) -> dict[str, Any]:
    """The calibration of the diagnosis (``bench/discovery.py``): its four rates against their targets, each
    with its binomial interval, the series whose design cannot carry their cause, and one row per series
    with what it missed."""
    keys: tuple[str, ...] = (
        "n_series",
        "n_null",
        "n_caused",
        "n_not_identifiable",
        "not_identifiable",
        "n_params_named",
    )
    keys += ("n_params_widened_by_systematic", "n_skipped", "design", "design_seeds", "wall_s", "workers")
    keys += ("named_right_rate", "false_name_rate_null", "confident_misname_rate", "coverage_95", "pass")
    keys += ("named_right_ci95", "false_name_ci95", "confident_misname_ci95", "coverage_ci95")
    keys += ("verdict_right_rate", "verdict_right_ci95", "named_right_marginal_rate", "named_right_at_coverage")
    cols: tuple[str, ...] = (
        "design_seed",
        "cause",
        "boundary",
        "fs",
        "wall",
        "h_over_b",
        "n_tests",
        "n_impacts",
        "verdict",
    )
    cols += ("named_right",)
    gens = bench.get("by_generator", {})
    return {
        **{k: bench[k] for k in keys},
        "pooled_bias": bench.get("pooled_bias"),
        "targets": bench["targets"],
        "missed": [t for t, v in bench["targets"].items() if not v["met"]],
        "cells": [{**{k: c[k] for k in cols}, "miss": _miss(c)} for c in _of(bench, "virtual")],
        "contact": _generator(gens["contact"], _of(bench, "contact"), CONTACT_COLUMNS) if "contact" in gens else None,
        "recorded": _generator(gens["recorded"], _of(bench, "recorded"), RECORDED_COLUMNS)
        if "recorded" in gens
        else None,
    }


#: The columns of a contact-lab series and of a recorded one on the performance page.
CONTACT_COLUMNS = ("design_seed", "knob", "fs", "wall", "n_tests", "verdict", "named_right")
RECORDED_COLUMNS: tuple[str, ...] = ("design_seed", "class", "cause", "boundary", "instrument", "fs", "wall")
RECORDED_COLUMNS += ("n_tests", "verdict", "named_right")
#: The rates of a class of the recorded cells on the performance page.
CLASS_RATES: tuple[str, ...] = (
    "n_series",
    "n_null",
    "named_right_rate",
    "false_name_rate_null",
    "confident_misname_rate",
)
CLASS_RATES += ("coverage_95",)


def _of(bench: Mapping[str, Any], generator: str) -> list[Mapping[str, Any]]:
    """The series of ``bench/discovery.py`` that ``generator`` made (the virtual lab's carry no name)."""
    return [c for c in bench["cells"] if c.get("generator", "virtual") == generator]


def _generator(rates: Mapping[str, Any], cells: list[Mapping[str, Any]], cols: Sequence[str]) -> dict[str, Any]:
    """Another generator's rates (the same score: the contact lab, :mod:`rocklab.lab.contact_lab`, another
    physics; the virtual lab through its files, :mod:`rocklab.diagnosis.recorded`, the whole chain) and its
    series: ``cols``, the truth, the verdict and what it missed; the recorded cells' rates by class."""
    keys: tuple[str, ...] = ("n_series", "n_null", "n_caused", "n_not_identifiable", "n_params_named", "n_skipped")
    keys += ("pooled_bias",)
    keys += ("named_right_rate", "named_right_ci95", "verdict_right_rate", "verdict_right_ci95")
    keys += ("false_name_rate_null", "false_name_ci95", "confident_misname_rate", "confident_misname_ci95")
    keys += ("coverage_95", "coverage_ci95", "pass")
    by_class = rates.get("by_class") or {}
    return {
        **{k: rates.get(k) for k in keys},
        "missed": [t for t, v in rates["targets"].items() if not v["met"]],
        "cells": [
            {**{k: c.get(k) for k in cols}, "truth": _truth(c.get("truth") or {}), "miss": _miss(c)} for c in cells
        ],
        "by_class": [{"class": k} | {q: r.get(q) for q in CLASS_RATES} for k, r in by_class.items()],
    }


def _truth(truth: Mapping[str, Mapping[str, float]]) -> str:
    """A series' truth in words: cause.parameter = value, or "none worth naming"."""
    return "; ".join(f"{c}.{k} = {v:.4g}" for c, p in truth.items() for k, v in p.items()) or "none worth naming"


def _projection(
    scale: Mapping[str, Any] | None, maps: Mapping[str, Any] | None, checkout: str | Path
) -> dict[str, Any]:
    """:func:`campaign_projection` and :func:`maps_projection` of the
    benchmarks that ran (``None`` for one that did not), on the profile and
    the workflow's configuration of the checkout."""
    from rocklab.config import SCHEMA, schema_defaults

    checkout = Path(checkout)
    profile = slurm_profile(checkout)
    config = schema_defaults(yaml.safe_load((checkout / SCHEMA).read_text()))["reduction"]
    config |= (yaml.safe_load((checkout / "config" / "config.yaml").read_text()) or {}).get("reduction", {})
    n_embedded = len(pd.read_csv(checkout / "raw" / "campaign" / "tests.csv"))
    has_stages = scale is not None and len(scale["runs"]) > 1 and "stage_jobs" in scale["runs"][-1]
    from rocklab.seismic.accelerograms.manifest import read_manifest

    return {
        "nodes": list(CLUSTER_NODES),
        "cores_per_node": CORES_PER_NODE,
        "factor": CAMPAIGN_FACTOR,
        "n_tests": CAMPAIGN_FACTOR * n_embedded,
        "cells": MAP_CELLS,
        "records": len(read_manifest()),
        "models": sum(MAP_JOB_MODELS.values()),
        "profile": profile,
        "campaign": campaign_projection(scale, profile, n_embedded, config["max_tests_per_job"])
        if has_stages and scale is not None
        else None,
        "maps": maps_projection(maps, profile) if maps else None,
    }


def shake_table_times(results: str | Path) -> dict[str, Any] | None:
    """Wall-clock and CPU time of each job of the target ``shake_table`` [s]; None where it did not run.

    Under a loaded machine the CPU time is the one that compares from run to run.
    """
    jobs = benchmark_times(results)
    jobs = jobs[jobs.stage == "shake_table"]
    if jobs.empty:
        return None
    names = [Path(job).name for job in jobs.job]
    job_times = dict(zip(names, jobs.s.astype(float)))
    job_cpu = dict(zip(names, jobs.cpu_s.astype(float)))
    return {
        "job_time_s": sum(job_times.values()),
        "job_times_s": job_times,
        "job_cpu_s": job_cpu,
        "job_cpu_total_s": sum(job_cpu.values()),
    }
