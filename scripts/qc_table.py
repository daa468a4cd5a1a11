"""Snakemake shim: results/qc.csv and results/kinematics.csv from the reduced tests."""

import pandas as pd

from rocklab.io import read_attrs, setup_logging, write_table
from rocklab.lab.campaign import open_campaign
from rocklab.lab.reduction import KINEMATICS_COLUMNS, kinematics_row, qc_table

setup_logging(snakemake.log[0])
reduced = read_attrs(snakemake.input.tests)
write_table(qc_table(reduced, open_campaign(snakemake.params.raw_dir)), snakemake.output.qc, snakemake.params.schema)
rows = [kinematics_row(r.attrs) for r in reduced if r.attrs.get("reject_reason") != "unreadable"]
write_table(pd.DataFrame(rows, columns=KINEMATICS_COLUMNS), snakemake.output.kinematics)
