"""Snakemake shim: results/diagnosis.json and diagnosis.md from the series' diagnoses."""

import json
from pathlib import Path

from rocklab.diagnosis import with_boundaries, write_diagnosis
from rocklab.diagnosis.summary import diagnosis_summary
from rocklab.io import setup_logging
from rocklab.summaries import write_summary

setup_logging(snakemake.log[0])
entries = [e for path in snakemake.input for e in json.loads(Path(path).read_text())]
write_diagnosis(with_boundaries(entries, seed=snakemake.params.seed), snakemake.output.json, snakemake.output.md)
write_summary(diagnosis_summary(snakemake.output.json), snakemake.output.docs_summary)
