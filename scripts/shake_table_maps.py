"""Snakemake shim: overturning maps of one calibrated specimen under two table records."""

import numba
import pandas as pd

from rocklab import jobs
from rocklab.io import write_netcdf
from rocklab.shake_table.asu_data import SPECIMENS, read_geometry, read_tests
from rocklab.shake_table.block import specimen_block
from rocklab.shake_table.evaluation import calibrated_maps

job = jobs.start(snakemake)
numba.set_num_threads(min(snakemake.threads, numba.config.NUMBA_NUM_THREADS))
p, specimen = snakemake.params, snakemake.wildcards.specimen
geometry = read_geometry(p.folder)
ds = calibrated_maps(
    p.folder,
    read_tests(p.folder),
    pd.read_csv(snakemake.input.predictions),
    pd.read_csv(snakemake.input.parameters),
    {s: specimen_block(geometry, s) for s in SPECIMENS},
    specimen,
    p.n,
)
write_netcdf(ds, snakemake.output[0])
job.finish()
