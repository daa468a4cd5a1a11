"""Snakemake shim: results/qc.csv and results/kinematics.csv from the reduction jobs' rows."""

from rocklab.io import setup_logging, write_table
from rocklab.lab.campaign import open_campaign
from rocklab.lab.reduction import kinematics_table, qc_table, read_row_attrs

setup_logging(snakemake.log[0])
reduced = read_row_attrs(snakemake.input.rows)
campaign = open_campaign(snakemake.params.raw_dir)
write_table(qc_table(reduced, campaign), snakemake.output.qc, snakemake.params.schema)
write_table(kinematics_table(reduced, campaign), snakemake.output.kinematics)
