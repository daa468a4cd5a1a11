"""Snakemake shim: results/maps/calibrated.csv, what the lab's findings do to the maps."""

from rocklab.io import load_datasets, setup_logging, write_table
from rocklab.seismic.calibrated import calibrated_table
from rocklab.seismic.overturning import summary_table

setup_logging(snakemake.log[0])
summary = summary_table(load_datasets(snakemake.input.maps))
write_table(calibrated_table(summary, snakemake.input.diagnosis), snakemake.output[0], snakemake.params.schema)
