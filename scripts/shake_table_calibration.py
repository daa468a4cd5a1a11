"""Snakemake shim: the contact fitted to the outcomes, held-out scores against the PGV threshold and DEM, transfer."""

import pandas as pd
import xarray as xr

from rocklab import jobs
from rocklab.io import write_table
from rocklab.shake_table.asu_data import read_geometry, read_tests
from rocklab.shake_table.block import specimen_block
from rocklab.shake_table.evaluation import calibration_tables
from rocklab.shake_table.shake_table_summary import shake_table_summary
from rocklab.summaries import write_summary

job = jobs.start(snakemake)
p = snakemake.params
geometry = read_geometry(p.folder)
outcomes = {ds.attrs["specimen"]: ds for ds in map(xr.load_dataset, snakemake.input.outcomes)}
tests = read_tests(p.folder)
tables = calibration_tables(
    tests,
    pd.read_csv(snakemake.input.motions),
    outcomes,
    {s: specimen_block(geometry, s) for s in outcomes},
    p.folds,
    p.n_boot,
    p.n_boot_cv,
)
for name, df in tables.items():
    write_table(df, snakemake.output[name], p.schemas[name])
write_summary(shake_table_summary(snakemake.output, snakemake.input.outcomes, tests), snakemake.output.docs_summary)
job.finish()
