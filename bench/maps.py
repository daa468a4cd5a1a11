"""Benchmark: overturning maps of Sect. 5 (201 x 201 histories) against a solve_ivp loop.

Times one map per model of :data:`rocklab.seismic.walls.MODELS` on El Centro
(40EIC180, Table 4 row 1), the scipy event-driven reference
(:func:`rocklab.simulation.reference.simulate_ground`) on ``--histories`` cells of the
same grid drawn at random, and every map of every shipped record (measured,
not extrapolated, unless ``--records`` restricts them: the JSON says which).
Targets: one map < 2 s and all maps (16 records x 6 models, issue 13) < 60 s
on two cores; ``all_maps_vs_reference`` is the speed-up over the solve_ivp
loop timed in the same run, the measure that does not depend on the
machine's load; ``all_maps_cpu_s`` is their CPU time, all threads together.

Usage: python bench/maps.py --out results/bench
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import time
from pathlib import Path

import numba
import numpy as np

from rocklab.seismic.accelerograms import load_record, read_manifest
from rocklab.seismic.maps import overturning_map, scales
from rocklab.seismic.walls import MODELS, named_model
from rocklab.simulation.reference import simulate_ground

RECORD = "40EIC180"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="results/bench")
    ap.add_argument("--n", type=int, default=201)
    ap.add_argument("--histories", type=int, default=20, help="solve_ivp histories timed")
    ap.add_argument("--records", nargs="*", help="records of the all-maps timing (default: every shipped one)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    tr = load_record(RECORD)
    ag, dt = tr.data, tr.stats.delta
    grid = scales(args.n)
    for name in MODELS:  # compile / load the numba cache outside the timings
        overturning_map(tr, model=name, n=2)
    per_model = {}
    for name in MODELS:
        t0 = time.perf_counter()
        ds = overturning_map(tr, model=name, n=args.n)
        per_model[name] = {"map_s": time.perf_counter() - t0, "N_O": float(ds.overturned.mean())}
    rng = np.random.default_rng(args.seed)
    cells = rng.integers(0, args.n, size=(args.histories, 2))
    names = list(MODELS)
    t0 = time.perf_counter()
    for k, (i, j) in enumerate(cells):
        simulate_ground(named_model(names[k % len(names)]), grid[i] * ag, dt * grid[j])
    t_hist = (time.perf_counter() - t0) / args.histories
    records = args.records or list(read_manifest().record)
    t0, c0 = time.perf_counter(), time.process_time()
    for rec in records:
        trace = load_record(rec)
        for name in MODELS:
            overturning_map(trace, model=name, n=args.n)
    t_all, cpu_all = time.perf_counter() - t0, time.process_time() - c0
    n_cells = args.n**2
    mean_map = float(np.mean([v["map_s"] for v in per_model.values()]))
    result = {
        "record": RECORD,
        "grid": [args.n, args.n],
        "histories_per_map": n_cells,
        "numba_threads": numba.get_num_threads(),
        "cpu_count": os.cpu_count(),
        "form": "linear",
        "models": per_model,
        "reference_histories_timed": args.histories,
        "reference_s_per_history": t_hist,
        "reference_s_per_map_estimated": t_hist * n_cells,
        "speedup_vs_reference": t_hist * n_cells / mean_map,
        "all_maps_records": records,
        "all_maps_count": len(records) * len(MODELS),
        "all_maps_s": t_all,
        "all_maps_cpu_s": cpu_all,
        "all_maps_measured": True,
        "all_maps_vs_reference": t_hist * n_cells * len(records) * len(MODELS) / t_all,
        "target_map_s": 2.0,
        "target_all_maps_s": 60.0,
        "pass": bool(max(v["map_s"] for v in per_model.values()) < 2.0 and t_all < 60.0 and not args.records),
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "maps.json").write_text(json.dumps(result, indent=2))
    for name, v in per_model.items():
        print(f"{name:11s} map {v['map_s']:.2f} s  N_O {v['N_O']:.3f}")
    print(
        f"solve_ivp {t_hist:.3f} s/history ({args.histories} timed), ratio {result['speedup_vs_reference']:.0f}x; "
        f"{result['all_maps_count']} maps of {len(records)} records in {t_all:.1f} s ({cpu_all:.1f} s of CPU)"
    )
    return 0 if result["pass"] else 1


if __name__ == "__main__":
    raise SystemExit(main())
