"""Snakemake shim: indices of every map (Fig. 22) and reductions between models."""

from rocklab.io import load_datasets, setup_logging, write_table
from rocklab.seismic.overturning import reductions, summary_table

setup_logging(snakemake.log[0])
summary = summary_table(load_datasets(snakemake.input.maps))
write_table(summary, snakemake.output.summary, snakemake.params.summary_schema)
write_table(reductions(summary), snakemake.output.reductions, snakemake.params.reductions_schema)
