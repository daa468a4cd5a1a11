"""Benchmark: the reduction of a campaign, and its results against another checkout's.

    python bench/reduction.py --out DIR [--campaign raw/campaign] [--reference DIR]

Runs every reduction job of the campaign (``Campaign.reduction_jobs`` with
the schema's ``reduction.max_tests_per_job``) as the workflow does: the shim
``scripts/reduce_tests.py`` in a Python process of its own per job, run
from the checkout's root with the campaign named relative to it (as each
test's ``source_file`` records it), then the tables made of its outputs (``scripts/qc_table.py``,
``scripts/dissipation_tables.py``), into ``DIR/results``.  The CPU time of
each job (start-up and imports included: the kernel's count of the child
process, robust on a shared machine) and the size of ``tests/`` (each
test with its motion) go to ``DIR/reduction.json``.

With ``--reference``, a ``DIR/results`` of the same campaign written by
another checkout (run this file there with that checkout's sources) or
the ``results/`` of a workflow run (``make run``), every
netCDF file is compared with its namesake, each group (the motion) as the
root: dimensions, variables (in order: dtype, dimensions, attributes, every
value bit for bit, NaN where NaN) and global attributes (in order; the time
of the ``history`` line aside); the compression filters are listed, not compared.  The tables are
compared byte for byte.  Exits 1 on any difference.
"""

from __future__ import annotations

import argparse
import json
import re
import resource
import subprocess
import sys
from pathlib import Path

import netCDF4
import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_CAMPAIGN = ROOT / "raw" / "campaign"
TABLES = ("qc", "kinematics", "tests", "impacts", "e_by_n", "series", "laws", "effects", "table3", "summary")
#: Runs a workflow shim with its ``snakemake`` object from JSON (argv[1]: script, argv[2]: object).
SHIM = """
import json, runpy, sys
class Names(list):
    # like Snakemake's: a list whose items are also named
    def __init__(self, items):
        # a named list is flattened into the positional items, as Snakemake does
        values = items.values() if isinstance(items, dict) else items
        super().__init__([x for v in values for x in (v if isinstance(v, list) else [v])])
        self.__dict__.update(items if isinstance(items, dict) else {})
    def __getitem__(self, key):
        return self.__dict__[key] if isinstance(key, str) else super().__getitem__(key)
obj = json.loads(sys.argv[2])
snakemake = type("Snakemake", (), {k: Names(v) for k, v in obj.items() if k != "config"})()
snakemake.config = obj["config"]
runpy.run_path(sys.argv[1], init_globals={"snakemake": snakemake}, run_name="__main__")
"""


def run_shim(script, **snakemake) -> float:
    """Run ``scripts/<script>`` in a process of its own; its CPU time [s] (user + system)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(
        [sys.executable, "-c", SHIM, str(ROOT / "scripts" / script), json.dumps(snakemake)], check=True, cwd=ROOT
    )
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def run(campaign: Path, results: Path) -> dict:
    """Every reduction job of ``campaign`` and the tables, into ``results``; CPU times [s]."""
    from rocklab.config import SCHEMA, schema_defaults
    from rocklab.lab.campaign import open_campaign
    from rocklab.lab.hierarchy import walls_of_specimens

    config = schema_defaults(yaml.safe_load((ROOT / SCHEMA).read_text()))
    jobs = open_campaign(campaign).reduction_jobs(config["reduction"]["max_tests_per_job"])
    options = {"channels": config["channels"], "validity": config["validity"]}
    # named as the workflow names it, from the checkout (each test's `source_file`)
    raw_dir = campaign.relative_to(ROOT) if campaign.is_relative_to(ROOT) else campaign
    cpu = {}
    for job, ids in jobs.items():
        cpu[job] = run_shim(
            "reduce_tests.py",
            input={},
            output={
                "tests": str(results / "tests" / job),
                "rows": str(results / "reduction" / f"{job}.json"),
                "dissipation": str(results / "reduction" / f"{job}.dissipation.json"),
            },
            params={"tests": {t: {} for t in ids}, "raw_dir": str(raw_dir), "options": options},
            log=[str(results / "logs" / "reduce" / f"{job}.log")],
            config={"results_dir": str(results)},
        )
    tables = {name: str(results / f"{name}.csv") for name in TABLES}
    tables["laws"] = str(results / "amplitude_laws.csv")
    run_shim(
        "qc_table.py",
        input={
            "rows": [str(results / "reduction" / f"{job}.json") for job in jobs],
            "log": str(campaign / "tests.csv"),
        },
        output={
            "qc": tables["qc"],
            "kinematics": tables["kinematics"],
            "docs_summary": str(results / "summaries" / "quality_control.json"),
        },
        params={"raw_dir": str(raw_dir), "schema": str(ROOT / "workflow" / "schemas" / "qc.schema.yaml")},
        log=[str(results / "logs" / "qc_table.log")],
        config={"results_dir": str(results)},
    )
    run_shim(
        "dissipation_tables.py",
        input={
            "qc": tables["qc"],
            "analysed": [str(results / "reduction" / f"{job}.dissipation.json") for job in jobs],
        },
        output={
            **{k: v for k, v in tables.items() if k not in ("qc", "kinematics")},
            "table3_md": tables["table3"][:-3] + "md",
            "docs_summary": str(results / "summaries" / "dissipation.json"),
        },
        params={
            "test_ids": open_campaign(campaign).test_ids,
            "walls": walls_of_specimens(open_campaign(campaign)),
            "schemas": str(ROOT / "workflow" / "schemas"),
            **config["statistics"],
        },
        log=[str(results / "logs" / "dissipation_tables.log")],
        config={"results_dir": str(results)},
    )
    return cpu


def _same(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype != b.dtype or a.shape != b.shape:
        return False
    if a.dtype.kind == "f":
        return bool(np.array_equal(a.view(f"u{a.itemsize}"), b.view(f"u{b.itemsize}")))
    return bool(np.array_equal(a, b))


def _attrs(obj) -> list:
    return [(k, obj.getncattr(k)) for k in obj.ncattrs()]


def netcdf_differences(path, ref) -> list:
    """What differs between two netCDF files, in words (empty when identical)."""
    with netCDF4.Dataset(path) as a, netCDF4.Dataset(ref) as b:
        if list(a.groups) != list(b.groups):
            return [f"groups {list(a.groups)} != {list(b.groups)}"]
        out = _group_differences(a, b)
        for name in a.groups:
            out += [f"group {name}: {d}" for d in _group_differences(a.groups[name], b.groups[name])]
    return out


def _group_differences(a, b) -> list:
    """:func:`netcdf_differences` of one group (or the root) of each file."""
    out = []
    for nc in (a, b):
        nc.set_auto_maskandscale(False)
        nc.set_auto_chartostring(False)
    dims = [[(d.name, d.size) for d in nc.dimensions.values()] for nc in (a, b)]
    if dims[0] != dims[1]:
        out.append(f"dimensions {dims[0]} != {dims[1]}")
    if list(a.variables) != list(b.variables):
        out.append(f"variables {list(a.variables)} != {list(b.variables)}")
    for name in set(a.variables) & set(b.variables):
        va, vb = a.variables[name], b.variables[name]
        if va.dimensions != vb.dimensions or not _same(va[...], vb[...]):
            out.append(f"{name}: values")
        ka, kb = _attrs(va), _attrs(vb)
        if [k for k, _ in ka] != [k for k, _ in kb] or not all(_same(x, y) for (_, x), (_, y) in zip(ka, kb)):
            out.append(f"{name}: attributes")
    # the history line's time is when the file was written
    ga, gb = (
        [(k, re.sub(r"^\S+Z ", "", v, flags=re.M) if k == "history" else v) for k, v in _attrs(nc)] for nc in (a, b)
    )
    if [k for k, _ in ga] != [k for k, _ in gb] or not all(_same(x, y) for (_, x), (_, y) in zip(ga, gb)):
        out.append("global attributes")
    return out


def _tests(results: Path) -> dict:
    """The reduced tests of a results folder (in their jobs' folders, or flat before issue 39), by file name."""
    return {p.name: p for p in sorted((results / "tests").rglob("*.nc"))}


def compare(results: Path, reference: Path) -> dict:
    """Every netCDF file and table of ``results`` against ``reference``."""
    report = {"files": 0, "different": {}}
    ours, theirs = _tests(results), _tests(reference)
    if sorted(ours) != sorted(theirs):
        report["different"]["tests"] = "not the same files"
    for name in sorted(ours):
        report["files"] += 1
        diff = netcdf_differences(ours[name], theirs[name])
        if diff:
            report["different"][f"tests/{name}"] = diff
    for table in sorted(results.glob("*.csv")) + sorted(results.glob("*.md")):
        report["files"] += 1
        if table.read_bytes() != (reference / table.name).read_bytes():
            report["different"][table.name] = "bytes"
    with (
        netCDF4.Dataset(next(iter(ours.values()))) as a,
        netCDF4.Dataset(next(iter(theirs.values()))) as b,
    ):
        report["filters"] = {"results": a.variables["theta"].filters(), "reference": b.variables["theta"].filters()}
    return report


def size_mb(folder: Path) -> float:
    return sum(p.stat().st_size for p in folder.rglob("*.nc")) / 1e6


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--campaign", type=Path, default=DEFAULT_CAMPAIGN)
    ap.add_argument("--reference", type=Path, help="results folder of another checkout's run of this benchmark")
    args = ap.parse_args(argv)
    results = args.out / "results"
    cpu = run(args.campaign.resolve(), results)
    out = {
        "jobs": len(cpu),
        "cpu_s": sum(cpu.values()),
        "cpu_s_by_job": cpu,
        "tests_mb": size_mb(results / "tests"),
    }
    print(f"reduction: {out['jobs']} jobs, {out['cpu_s']:.1f} s of CPU; tests {out['tests_mb']:.1f} MB")
    if args.reference:
        out["comparison"] = compare(results, args.reference)
        print(f"{out['comparison']['files']} files compared, {len(out['comparison']['different'])} different")
    (args.out / "reduction.json").write_text(json.dumps(out, indent=2, default=str) + "\n")
    return 1 if out.get("comparison", {}).get("different") else 0


if __name__ == "__main__":
    sys.exit(main())
