"""Snakemake shim: results/diagnosis.json and diagnosis.md from the series' diagnoses."""

import json
from pathlib import Path

from rocklab.diagnosis import with_boundaries, write_diagnosis
from rocklab.io import setup_logging

setup_logging(snakemake.log[0])
# by series, as the boundary conditions' files interleave them
entries = sorted((e for path in snakemake.input for e in json.loads(Path(path).read_text())), key=lambda e: e["key"])
write_diagnosis(with_boundaries(entries, seed=snakemake.params.seed), snakemake.output.json, snakemake.output.md)
