"""Snakemake shim: the overturning maps (Sect. 5) of one record.

Rule ``overturning_maps``: the paper's models, one file per model.  Rule
``calibrated_maps``: the calibrated walls the campaign's diagnosis names,
one file per model in the output folder.
"""

from pathlib import Path

import numba

from rocklab.io import setup_logging, write_netcdf
from rocklab.seismic import calibrated
from rocklab.seismic.accelerograms import load_record
from rocklab.seismic.overturning import overturning_map

setup_logging(snakemake.log[0])
numba.set_num_threads(min(snakemake.threads, numba.config.NUMBA_NUM_THREADS))
p = snakemake.params
diagnosis = snakemake.input.get("diagnosis")
if diagnosis:
    folder = Path(snakemake.output[0])
    folder.mkdir(parents=True, exist_ok=True)
    names = calibrated.model_names(diagnosis)
    paths = [folder / f"{snakemake.wildcards.record}__{name}.nc" for name in names]
else:
    names, paths = p.models, snakemake.output
trace = load_record(snakemake.wildcards.record)
for name, path in zip(names, paths):
    ds = overturning_map(
        trace,
        model=name,
        n=p.n,
        lo=p.lo,
        hi=p.hi,
        alpha=p.alpha,
        R=p.R,
        form=p.form,
        eq17=(p.eq17["a"], p.eq17["b"]),
        diagnosis=diagnosis,
        polarity=p.polarity,
        chunks=p.chunks,
    )
    write_netcdf(ds, path)
