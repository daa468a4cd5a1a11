"""Snakemake shim: Figs. 6, 8 and 9 from the sample test and kinematics.csv."""

import pandas as pd
import xarray as xr

from rocklab import jobs
from rocklab.io import valid_test_ids
from rocklab.plots import kinematics as figures
from rocklab.plots import save_png

job = jobs.start(snakemake)
with xr.open_dataset(snakemake.params.sample) as ds:
    ds = ds.load()
save_png(figures.sample_record(ds), snakemake.output.fig6, dpi=120)
save_png(figures.degrees_of_freedom(ds), snakemake.output.fig8, dpi=120)
kin = pd.read_csv(snakemake.input.kinematics)
kin = kin[kin.test_id.isin(valid_test_ids(snakemake.input.qc))]
peaks = kin[kin.series.str.startswith(f"{snakemake.params.specimen}-")].reset_index(drop=True)
peaks.attrs["specimen"] = snakemake.params.specimen
save_png(figures.eq8_and_peaks(ds, peaks), snakemake.output.fig9, dpi=120)
job.finish()
