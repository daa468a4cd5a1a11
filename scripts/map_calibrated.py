"""Snakemake shim: results/maps/calibrated.csv, what the lab's findings do to the maps."""

from pathlib import Path

from rocklab.io import load_datasets, setup_logging, write_table
from rocklab.seismic.calibrated import calibrated_table
from rocklab.seismic.indices import summary_table
from rocklab.seismic.maps import subgrid
from rocklab.seismic.summary import calibrated_summary
from rocklab.summaries import write_summary

setup_logging(snakemake.log[0])
# the paper's e-alone maps are files, the calibrated ones the files of a folder per record
paths = [
    q for path in map(Path, snakemake.params.maps) for q in (sorted(path.glob("*.nc")) if path.is_dir() else [path])
]
# the e-alone maps have the paper's grid: read on the calibrated walls' cells
summary = summary_table(subgrid(ds, snakemake.params.n) for ds in load_datasets(paths))
write_table(calibrated_table(summary, snakemake.input.diagnosis), snakemake.output.table, snakemake.params.schema)
write_summary(calibrated_summary(snakemake.output.table, snakemake.params.n), snakemake.output.docs_summary)
