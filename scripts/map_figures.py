"""Snakemake shim: Figs. 21 and 23 (maps of one record) and Fig. 22 (indices of all records)."""

import pandas as pd

from rocklab import jobs
from rocklab.io import load_datasets
from rocklab.plots import maps as map_figures
from rocklab.plots import save_png

job = jobs.start(snakemake)
save_png(map_figures.overturning_maps(list(load_datasets(snakemake.params.two_sided))), snakemake.output.fig21, dpi=120)
save_png(map_figures.overturning_maps(list(load_datasets(snakemake.params.one_sided))), snakemake.output.fig23, dpi=120)
summary = pd.read_csv(snakemake.input.summary)
save_png(map_figures.map_indices_figure(summary), snakemake.output.fig22, dpi=120)
job.finish()
