"""Snakemake shim: fragility curves and overturning maps of the shake-table specimens."""

import pandas as pd
import xarray as xr

from rocklab import jobs
from rocklab.plots import save_png
from rocklab.plots.shake_table import calibrated_maps, fragility_curves

job = jobs.start(snakemake)
save_png(fragility_curves(pd.read_csv(snakemake.input.predictions)), snakemake.output.fragility, dpi=150)
save_png(calibrated_maps([xr.load_dataset(p) for p in snakemake.input.maps]), snakemake.output.maps, dpi=150)
job.finish()
