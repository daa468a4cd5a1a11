"""Snakemake shim: one overturning map (record x model) of Sect. 5."""

import numba

from rocklab.io import setup_logging, write_netcdf
from rocklab.seismic.accelerograms import load_record
from rocklab.seismic.overturning import overturning_map

setup_logging(snakemake.log[0])
numba.set_num_threads(min(snakemake.threads, numba.config.NUMBA_NUM_THREADS))
p = snakemake.params
ds = overturning_map(
    load_record(snakemake.wildcards.record),
    model=snakemake.wildcards.model,
    n=p.n,
    lo=p.lo,
    hi=p.hi,
    alpha=p.alpha,
    R=p.R,
    form=p.form,
    eq17=(p.eq17["a"], p.eq17["b"]),
    # the calibrated walls read the campaign's diagnosis
    diagnosis=snakemake.input.diagnosis[0] if snakemake.input.diagnosis else None,
    polarity=p.polarity,
    chunks=p.chunks,
)
write_netcdf(ds, snakemake.output[0])
