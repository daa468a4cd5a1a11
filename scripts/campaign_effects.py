"""Snakemake shim: the campaign-level effects (campaign_effects.csv) and their figure."""

import pandas as pd

from rocklab import jobs
from rocklab.diagnosis import CampaignDiagnosis
from rocklab.dissipation.covariates import campaign_effects, series_fits
from rocklab.dissipation.dissipation_summary import campaign_level_summary
from rocklab.io import write_table
from rocklab.plots import save_png
from rocklab.plots.covariates import covariate_figure
from rocklab.summaries import write_summary

job = jobs.start(snakemake)
tests = pd.read_csv(snakemake.input.tests)
qc = pd.read_csv(snakemake.input.qc)
diagnosis = CampaignDiagnosis.from_json(snakemake.input.diagnosis)
walls = snakemake.params.walls
effects = campaign_effects(tests, diagnosis, qc, walls=walls)
write_table(effects, snakemake.output.table, snakemake.params.schema)
write_summary(campaign_level_summary(snakemake.output.table), snakemake.output.docs_summary)
save_png(covariate_figure(series_fits(tests, diagnosis, qc, walls), effects), snakemake.output.figure, dpi=90)
job.finish()
