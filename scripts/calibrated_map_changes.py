"""Snakemake shim: results/maps/calibrated.csv, what the lab's findings do to the maps."""

from rocklab import jobs
from rocklab.io import load_datasets, write_table
from rocklab.seismic.calibrated import calibrated_table
from rocklab.seismic.indices import summary_table
from rocklab.seismic.maps import subgrid
from rocklab.seismic.maps_summary import calibrated_summary
from rocklab.summaries import write_summary

job = jobs.start(snakemake)
paths = snakemake.params.maps
# the e-alone maps have the paper's grid: read on the calibrated walls' cells
summary = summary_table(subgrid(ds, snakemake.params.n) for ds in load_datasets(paths))
write_table(calibrated_table(summary, snakemake.input.diagnosis), snakemake.output.table, snakemake.params.schema)
write_summary(calibrated_summary(snakemake.output.table, snakemake.params.n), snakemake.output.docs_summary)
job.finish()
