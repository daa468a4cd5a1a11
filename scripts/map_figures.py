"""Snakemake shim: Figs. 21 and 23 (maps of one record) and Fig. 22 (indices of all records)."""

import pandas as pd
import xarray as xr

from rocklab import map_figures
from rocklab.workflow import setup_logging


def load(paths):
    out = []
    for path in paths:
        with xr.open_dataset(path) as ds:
            out.append(ds.load())
    return out


setup_logging(snakemake.log[0])
map_figures.overturning_maps(load(snakemake.input.two_sided)).savefig(snakemake.output.fig21, dpi=120)
map_figures.overturning_maps(load(snakemake.input.one_sided)).savefig(snakemake.output.fig23, dpi=120)
summary = pd.read_csv(snakemake.input.summary)
map_figures.map_indices_figure(summary).savefig(snakemake.output.fig22, dpi=120)
