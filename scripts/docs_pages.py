"""Snakemake shim: results/docs/numbers.json (the stages' summaries, the job times) and the docs pages."""

import logging
from pathlib import Path

from rocklab import jobs
from rocklab.report.pages import write_docs

job = jobs.start(snakemake)
templates = Path(snakemake.input.templates[0]).parent
out = Path(snakemake.output.numbers).parent
for path in write_docs(snakemake.params.results_dir, templates, out, checkout=snakemake.params.checkout):
    logging.info("wrote %s", path)
job.finish()
