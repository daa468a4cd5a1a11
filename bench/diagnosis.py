"""Benchmark: the diagnosis of every series of a reduced campaign, timed series by series.

    python bench/diagnosis.py --out results/bench [--results results]

Reads the reduced tests and their motion (``<results>/tests``, each file
with its motion inside, as the workflow's ``diagnose_series`` jobs do) and
times :func:`rocklab.diagnosis.diagnose_records` on each series with the
workflow's settings (``config/config.yaml``, defaults from its schema):
CPU and wall seconds, the verdict; then the boundary conditions summed up
over the series (:func:`rocklab.diagnosis.with_boundaries`, the checkpoint
job's work).  With the workflow's job benchmarks
(``<results>/benchmarks/diagnosis/<job>.tsv``, one per pack of series, and
``diagnosis.tsv``) it also sums the job times of the diagnosis, start-up
and reading included.  Writes
``<out>/diagnosis.json`` and prints the totals.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import pandas as pd
import yaml

from rocklab.config import SCHEMA, schema_defaults
from rocklab.diagnosis import CampaignDiagnosis, diagnose_records, jsonable, stored_records, with_boundaries

ROOT = Path(__file__).resolve().parents[1]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/bench"))
    ap.add_argument("--results", type=Path, default=Path("results"))
    args = ap.parse_args()
    cfg = schema_defaults(yaml.safe_load((ROOT / SCHEMA).read_text()))["diagnosis"]
    cfg |= (yaml.safe_load((ROOT / "config" / "config.yaml").read_text()) or {}).get("diagnosis", {})
    tests = args.results / "tests"
    series, entries = {}, []
    for key, records in stored_records(sorted(tests.rglob("*.nc"), key=lambda p: p.name)).items():
        t0, c0 = time.perf_counter(), time.process_time()
        entry = diagnose_records(records, key, n_boot=cfg["n_boot"], n_history=cfg["n_history"], seed=cfg["seed"])
        series[key] = {
            "cpu_s": time.process_time() - c0,
            "wall_s": time.perf_counter() - t0,
            "verdict": entry.verdict if entry else None,
            "unexplained": entry.unexplained if entry else None,
            "discovered": [f.effect for f in entry.discovered] if entry else [],
        }
        entries += [entry] if entry else []
        print(f"{key}: {series[key]['cpu_s']:.2f} s CPU")
    # the checkpoint reads the series' entries back from their JSON files
    entries = CampaignDiagnosis.from_dict(json.loads(json.dumps(jsonable(CampaignDiagnosis(entries).to_dict()))))
    c0 = time.process_time()
    with_boundaries(entries)
    boundaries_cpu_s = time.process_time() - c0
    # the workflow's jobs: one per pack of series (Campaign.diagnosis_jobs), then the checkpoint summing them up
    bench = args.results / "benchmarks"
    jobs = sorted((bench / "diagnosis").glob("*.tsv")) + [p for p in [bench / "diagnosis.tsv"] if p.exists()]
    job_s = [float(pd.read_csv(p, sep="\t")["s"].iloc[0]) for p in jobs]
    out = {
        "n_series": len(series),
        "cpu_s": sum(s["cpu_s"] for s in series.values()),
        "wall_s": sum(s["wall_s"] for s in series.values()),
        "longest_series_cpu_s": max(s["cpu_s"] for s in series.values()),
        "boundaries_cpu_s": boundaries_cpu_s,
        "jobs": len(job_s),
        "job_s": sum(job_s) if job_s else None,
        "series": series,
    }
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "diagnosis.json").write_text(json.dumps(out, indent=1))
    print(
        f"diagnosis of {out['n_series']} series: {out['cpu_s']:.1f} s CPU, {out['wall_s']:.1f} s wall; "
        f"boundary conditions {boundaries_cpu_s:.1f} s CPU"
        + (f"; {len(job_s)} workflow jobs {out['job_s']:.1f} s" if job_s else "")
    )


if __name__ == "__main__":
    main()
