"""Snakemake shim: results/qc.csv, results/kinematics.csv and the QC summary from the reduction jobs' rows."""

import pandas as pd

from rocklab import jobs
from rocklab.io import write_table
from rocklab.lab.campaign import open_campaign
from rocklab.lab.qc_summary import quality_control_summary
from rocklab.lab.reduction import kinematics_table, qc_table, read_row_attrs
from rocklab.summaries import write_summary

job = jobs.start(snakemake)
reduced = read_row_attrs(snakemake.input.rows)
campaign = open_campaign(snakemake.params.raw_dir)
write_table(qc_table(reduced, campaign), snakemake.output.qc, snakemake.params.schema)
write_table(kinematics_table(reduced, campaign), snakemake.output.kinematics)
write_summary(quality_control_summary(pd.read_csv(snakemake.output.qc)), snakemake.output.docs_summary)
job.finish()
