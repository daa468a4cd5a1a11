"""Snakemake shim: fragility curves and overturning maps of the shake-table specimens."""

import pandas as pd
import xarray as xr

from rocklab.io import setup_logging
from rocklab.plots.shake_table import calibrated_maps, fragility_curves

setup_logging(snakemake.log[0])
fragility_curves(pd.read_csv(snakemake.input.predictions)).savefig(snakemake.output.fragility, dpi=150)
calibrated_maps([xr.load_dataset(p) for p in snakemake.input.maps]).savefig(snakemake.output.maps, dpi=150)
