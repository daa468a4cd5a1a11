"""Snakemake shim: Figs. 10, 11, 13 and 16-20 from the dissipation tables and the Fig. 20a test."""

import pandas as pd
import xarray as xr

from rocklab import jobs
from rocklab.plots import dissipation as figures
from rocklab.plots import save_png

job = jobs.start(snakemake)
sample = None
if snakemake.params.sample:
    with xr.open_dataset(snakemake.params.sample[0]) as ds:
        sample = ds.load()
figs = figures.dissipation_figures(
    pd.read_csv(snakemake.input.tests), pd.read_csv(snakemake.input.e_by_n), pd.read_csv(snakemake.input.series), sample
)
for name, fig in figs.items():
    save_png(fig, snakemake.output[name], dpi=120)
job.finish()
