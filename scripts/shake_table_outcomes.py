"""Snakemake shim: one specimen's block under every record at every node of the causes' grid."""

import numba
import pandas as pd

from rocklab import jobs
from rocklab.io import write_netcdf
from rocklab.shake_table.asu_data import read_geometry, read_tests
from rocklab.shake_table.block import outcome_grid, specimen_block
from rocklab.shake_table.evaluation import block_inputs

job = jobs.start(snakemake)
numba.set_num_threads(min(snakemake.threads, numba.config.NUMBA_NUM_THREADS))
folder, specimen = snakemake.params.folder, snakemake.wildcards.specimen
motions = pd.read_csv(snakemake.input.motions)
inputs, dts = block_inputs(folder, read_tests(folder), motions)
block = specimen_block(read_geometry(folder), specimen)
write_netcdf(outcome_grid(inputs, dts, block, motions.test, specimen=specimen), snakemake.output[0])
job.finish()
