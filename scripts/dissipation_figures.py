"""Snakemake shim: Figs. 10, 11, 13 and 16-20 from the dissipation tables."""

from pathlib import Path

import pandas as pd
import xarray as xr

from rocklab.io import setup_logging
from rocklab.plots import dissipation as figures

setup_logging(snakemake.log[0])
tests = pd.read_csv(snakemake.input.tests)
sample_id = snakemake.params.sample_test or figures.fig20_sample(tests)
sample = None
if sample_id is not None:
    path = {Path(p).stem: p for p in snakemake.input.tests_nc}[sample_id]
    with xr.open_dataset(path) as ds:
        sample = ds.load()
figs = figures.dissipation_figures(
    tests, pd.read_csv(snakemake.input.e_by_n), pd.read_csv(snakemake.input.series), sample
)
for name, fig in figs.items():
    fig.savefig(snakemake.output[name], dpi=120)
