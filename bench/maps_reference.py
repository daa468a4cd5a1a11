"""Validation: overturning maps against the converged event-driven reference.

For each model of :data:`rocklab.seismic.walls.MODELS` and each record, the
full 201 x 201 map is computed by the batch engine and every 10th cell in
both directions (a 21 x 21 subgrid) is recomputed by
:func:`rocklab.simulation.reference.simulate_ground` with rtol 1e-10, atol 1e-12,
the histories spread over a Pool of ``--workers`` processes.  A cell where they
differ must lie on the boundary: the reference itself reaches the map's
decision at one of the cell's four neighbours of the 201 grid
(:func:`rocklab.seismic.reference_check.check_against_reference`).  The check passes
when every map agrees on at least 99 % of its cells and every difference
lies on the boundary.

Records (:data:`RECORDS`): El Centro 1940 (row 1, long and far-field), Pacoima
Dam (row 3, truncated after 20.5 s) and Rinaldi 228 (row 13), the pulse-like
record: the near-fault forward-directivity pulse of Northridge 1994, its
peak velocity in one half cycle shorter than a second, 2.5 s into a record
of 19.9 s, so that overturning is decided by one pulse and a wall can still
be rocking when the record ends (where the end-of-record test of the
engines matters most).  Rinaldi rather than Takatori (row 19, also
pulse-like): it is half as long, so its reference costs about half as much.

Writes ``maps_reference.json`` into ``--out``: per map the agreement, the
differing cells and the time of the reference; rewritten after every map
(``complete`` false until the last), so that an interrupted run keeps what
it checked.

Usage: python bench/maps_reference.py --out results/bench   (about 15 min on two cores)
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import time
from multiprocessing import Pool
from pathlib import Path

from rocklab.seismic.accelerograms import load_record
from rocklab.seismic.maps import overturning_map
from rocklab.seismic.reference_check import check_against_reference
from rocklab.seismic.walls import MODELS, named_model

#: The pulse-like Rinaldi 228 (row 13), Pacoima Dam (row 3) and El Centro (row 1): see the module doc.
RECORDS = ("RRS228", "Pac164", "40EIC180")

#: Lowest share of a map's cells [%] on which map and reference must agree.
MIN_AGREEMENT_PCT = 99.0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="results/bench")
    ap.add_argument("--records", nargs="*", default=list(RECORDS))
    ap.add_argument("--models", nargs="*", default=list(MODELS))
    ap.add_argument("--n", type=int, default=201)
    ap.add_argument("--every", type=int, default=10, help="subgrid stride")
    ap.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    maps = []
    start = time.perf_counter()

    def write(complete):
        """The JSON so far: rewritten after every map, so that an interrupted run keeps what it checked."""
        result = {
            "criterion": "a differing cell lies on the boundary when the reference reaches the map's decision at one "
            "of its four neighbours of the full grid (amplitude or duration scale moved by one grid step); pass: every "
            f"map agrees on at least {MIN_AGREEMENT_PCT:g} % of its cells and no difference lies off the boundary",
            "reference": "rocklab.simulation.reference.simulate_ground, solve_ivp DOP853, rtol 1e-10, atol 1e-12",
            "grid": args.n,
            "every": args.every,
            "workers": args.workers,
            "records": args.records,
            "models": args.models,
            "complete": complete,
            "total_s": time.perf_counter() - start,
            "maps": maps,
            "pass": complete and all(m["unexplained"] == 0 and m["agreement_pct"] >= MIN_AGREEMENT_PCT for m in maps),
        }
        (out / "maps_reference.json").write_text(json.dumps(result, indent=2))
        return result

    with Pool(args.workers) as pool:
        for rec in args.records:
            tr = load_record(rec)
            for name in args.models:
                ds = overturning_map(tr, model=name, n=args.n)
                sub = ds.isel(
                    amplitude_scale=slice(None, None, args.every), duration_scale=slice(None, None, args.every)
                )
                step = float(ds.amplitude_scale[1] - ds.amplitude_scale[0])
                t0 = time.perf_counter()
                res = check_against_reference(
                    tr.data,
                    tr.stats.delta,
                    named_model(name),
                    sub.amplitude_scale.values,
                    sub.duration_scale.values,
                    sub.overturned.values,
                    step,
                    pool=pool,
                    rtol=1e-10,
                    atol=1e-12,
                )
                res.pop("reference")
                maps.append(
                    {
                        "record": rec,
                        "model": name,
                        "subgrid": list(sub.overturned.shape),
                        "reference_s": time.perf_counter() - t0,
                        **res,
                    }
                )
                write(complete=False)
                print(
                    f"{rec} {name}: {res['agreement_pct']:.2f} % agree, {len(res['mismatches'])} differ, "
                    f"{res['unexplained']} off the boundary, {maps[-1]['reference_s']:.0f} s",
                    flush=True,
                )
    result = write(complete=True)
    print(
        f"{len(maps)} maps, lowest agreement {min(m['agreement_pct'] for m in maps):.2f} %, "
        f"{sum(m['unexplained'] for m in maps)} differences off the boundary, {result['total_s']:.0f} s: "
        f"{'pass' if result['pass'] else 'FAIL'}",
        flush=True,
    )
    return 0 if result["pass"] else 1


if __name__ == "__main__":
    raise SystemExit(main())
