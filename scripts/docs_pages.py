"""Snakemake shim: results/docs/numbers.json (the stages' summaries, the job times) and the docs pages."""

import logging
from pathlib import Path

from rocklab.io import setup_logging
from rocklab.report.pages import write_docs

setup_logging(snakemake.log[0])
templates = Path(snakemake.input.templates[0]).parent
for path in write_docs(snakemake.params.results_dir, templates, Path(snakemake.output.numbers).parent):
    logging.info("wrote %s", path)
