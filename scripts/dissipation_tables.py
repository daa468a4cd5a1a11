"""Snakemake shim: the energy-dissipation tables of the valid tests, from the per-test tables of the reduction jobs."""

import logging
from pathlib import Path

import pandas as pd

from rocklab import jobs
from rocklab.disk import write_text
from rocklab.dissipation.analysis import AnalysedTests
from rocklab.dissipation.dissipation_summary import dissipation_summary
from rocklab.dissipation.statistics import campaign_tables, table3_markdown
from rocklab.io import valid_test_ids, write_table
from rocklab.summaries import write_summary

job = jobs.start(snakemake)
qc = pd.read_csv(snakemake.input.qc, keep_default_na=False, na_values=[""])
valid = set(valid_test_ids(snakemake.input.qc))
tables, failed = campaign_tables(
    AnalysedTests.joined(
        map(AnalysedTests.read, snakemake.input.analysed), [t for t in snakemake.params.test_ids if t in valid]
    ),
    qc,
    snakemake.params.walls,
    snakemake.params.n_boot,
    snakemake.params.seed,
)
for test_id, why in failed:
    logging.warning("%s: motion not analysed: %s", test_id, why)
schemas = Path(snakemake.params.schemas)
for name in ("tests", "impacts", "e_by_n", "series", "laws", "effects", "table3", "summary"):
    schema = schemas / f"{name}.schema.yaml"
    write_table(tables[name], snakemake.output[name], schema if schema.exists() else None)
write_text(snakemake.output.table3_md, table3_markdown(tables["table3"]) + "\n")
write_summary(dissipation_summary(snakemake.output), snakemake.output.docs_summary)
job.finish()
