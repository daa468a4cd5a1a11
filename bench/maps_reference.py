"""Validation: overturning maps against the converged event-driven reference.

For each of the five models of :data:`rocklab.seismic.overturning.MODELS` and each
record, the full 201 x 201 map is computed by the batch engine and every
10th cell in both directions (a 21 x 21 subgrid) is recomputed by
:func:`rocklab.simulation.reference.simulate_ground` with rtol 1e-10, atol 1e-12.  A cell
where they differ must lie on the boundary: the reference itself reaches the
map's decision at one of the cell's four neighbours of the 201 grid
(:func:`rocklab.seismic.overturning.check_against_reference`).

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
from rocklab.seismic.overturning import MODELS, check_against_reference, named_model, overturning_map

#: Pacoima Dam (short, pulse-like, Table 4 row 3) and El Centro (Fig. 21 wall's record, row 1).
RECORDS = ("Pac164", "40EIC180")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="results/bench")
    ap.add_argument("--records", nargs="*", default=list(RECORDS))
    ap.add_argument("--n", type=int, default=201)
    ap.add_argument("--every", type=int, default=10, help="subgrid stride")
    ap.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    maps = []
    with Pool(args.workers) as pool:
        for rec in args.records:
            tr = load_record(rec)
            for name in MODELS:
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
                print(
                    f"{rec} {name}: {res['agreement_pct']:.2f} % agree, {len(res['mismatches'])} differ, "
                    f"{res['unexplained']} off the boundary",
                    flush=True,
                )
    result = {
        "criterion": "a differing cell lies on the boundary when the reference reaches the map's decision at one of "
        "its four neighbours of the full grid (amplitude or duration scale moved by one grid step)",
        "reference": "rocklab.simulation.reference.simulate_ground, solve_ivp DOP853, rtol 1e-10, atol 1e-12",
        "grid": args.n,
        "every": args.every,
        "workers": args.workers,
        "maps": maps,
        "pass": all(m["unexplained"] == 0 for m in maps),
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "maps_reference.json").write_text(json.dumps(result, indent=2))
    return 0 if result["pass"] else 1


if __name__ == "__main__":
    raise SystemExit(main())
