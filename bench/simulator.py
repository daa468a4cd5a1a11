"""Benchmark: batch engine vs a scipy.integrate.solve_ivp event-driven loop.

1,000 scaled histories (40 amplitude x 25 duration scales, 50-150 % of the
natural values, Sect. 5) of a recorded accelerogram acting on the wall of
Fig. 21 (alpha = 0.1 rad, R = 3 m, two-sided, Housner linear form, Eq. 2).
Both engines decide overturning cell by cell; a disagreement is accepted only
within the stated tolerance of the boundary: the reference itself changes its
decision when the cell's amplitude is scaled by 1 +/- ``--tol``.

Usage: python bench/simulator.py --out results/bench
"""

from __future__ import annotations

import argparse
import json
import os
import time
from multiprocessing import Pool
from pathlib import Path

import numpy as np

from rocklab.seismic.accelerograms import load_record
from rocklab.seismic.reference_check import reference_decisions
from rocklab.seismic.walls import named_model
from rocklab.simulation.batch import overturning_batch

#: El Centro 1940 N-S (Table 4 row 1), shipped in rocklab/data/accelerograms.
RECORD = "40EIC180"
MODEL = named_model("2s-housner")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="results/bench")
    ap.add_argument("--record", default=RECORD, help="manifest record name or path of any accelerogram obspy reads")
    ap.add_argument("--n-amp", type=int, default=40)
    ap.add_argument("--n-dur", type=int, default=25)
    ap.add_argument("--tol", type=float, default=0.01, help="relative amplitude tolerance of the boundary")
    ap.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    args = ap.parse_args(argv)
    tr = load_record(args.record)
    ag, dt = tr.data, tr.stats.delta
    amps = np.linspace(0.5, 1.5, args.n_amp)
    durs = np.linspace(0.5, 1.5, args.n_dur)
    overturning_batch(ag, dt, MODEL, amps[:2], durs[:2])  # compile / load the numba cache
    t0 = time.perf_counter()
    batch = overturning_batch(ag, dt, MODEL, amps, durs)
    t_batch = time.perf_counter() - t0
    with Pool(args.workers) as pool:
        t0 = time.perf_counter()
        ref = reference_decisions(ag, dt, MODEL, [(a, d) for a in amps for d in durs], pool=pool).reshape(batch.shape)
        t_ref = time.perf_counter() - t0
        bad = np.argwhere(batch != ref)
        around = [(amps[i] * f, durs[j]) for i, j in bad for f in (1 - args.tol, 1 + args.tol)]
        neighbours = reference_decisions(ag, dt, MODEL, around, pool=pool).reshape(-1, 2)
        unexplained = [
            [float(amps[i]), float(durs[j])] for (i, j), nb in zip(bad, neighbours) if (nb == ref[i, j]).all()
        ]
    speedup = t_ref / t_batch
    result = {
        "record": Path(args.record).name,
        "dt_s": dt,
        "npts": int(ag.size),
        "model": {"alpha": MODEL.alpha, "p": MODEL.p, "form": MODEL.form, "boundary": MODEL.boundary},
        "histories": int(batch.size),
        "workers": args.workers,
        "t_batch_s": t_batch,
        "t_reference_s": t_ref,
        "speedup": speedup,
        "overturned_batch": int(batch.sum()),
        "overturned_reference": int(ref.sum()),
        "mismatches": int(len(bad)),
        "boundary_tolerance_rel_amplitude": args.tol,
        "mismatches_beyond_tolerance": unexplained,
        "pass": bool(speedup >= 1000 and not unexplained),
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "simulator.json").write_text(json.dumps(result, indent=2))
    print(
        f"batch {t_batch:.3f} s, solve_ivp {t_ref:.1f} s, ratio {speedup:.0f}x; "
        f"{len(bad)} mismatches, {len(unexplained)} beyond tolerance"
    )
    return 0 if result["pass"] else 1


if __name__ == "__main__":
    raise SystemExit(main())
