"""Snakemake shim: Figs. 21 and 23 (maps of one record) and Fig. 22 (indices of all records)."""

import pandas as pd

from rocklab.io import load_datasets, setup_logging
from rocklab.plots import maps as map_figures

setup_logging(snakemake.log[0])
map_figures.overturning_maps(list(load_datasets(snakemake.input.two_sided))).savefig(snakemake.output.fig21, dpi=120)
map_figures.overturning_maps(list(load_datasets(snakemake.input.one_sided))).savefig(snakemake.output.fig23, dpi=120)
summary = pd.read_csv(snakemake.input.summary)
map_figures.map_indices_figure(summary).savefig(snakemake.output.fig22, dpi=120)
