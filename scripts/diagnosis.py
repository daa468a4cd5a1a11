"""Snakemake shim: results/diagnosis.json and diagnosis.md."""

from rocklab.diagnosis import diagnose_campaign, records_by_series, write_diagnosis
from rocklab.workflow import setup_logging, valid_tests

setup_logging(snakemake.log[0])
entries = diagnose_campaign(records_by_series(valid_tests(snakemake.input.tests, snakemake.input.qc)),
                            n_boot=snakemake.params.n_boot, n_history=snakemake.params.n_history,
                            seed=snakemake.params.seed)
write_diagnosis(entries, snakemake.output.json, snakemake.output.md)
