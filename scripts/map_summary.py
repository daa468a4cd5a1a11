"""Snakemake shim: indices of every map (Fig. 22) and reductions between models."""

import xarray as xr

from rocklab.overturning import reductions, summary_table
from rocklab.workflow import setup_logging, write_table


def maps(paths):
    for path in paths:
        with xr.open_dataset(path) as ds:
            yield ds.load()


setup_logging(snakemake.log[0])
summary = summary_table(maps(snakemake.input.maps))
write_table(summary, snakemake.output.summary, snakemake.params.summary_schema)
write_table(reductions(summary), snakemake.output.reductions, snakemake.params.reductions_schema)
