"""Snakemake shim: the report's HTML page of each input table or text, under the same name."""

import os

from rocklab import jobs
from rocklab.disk import write_text
from rocklab.report.html import report_page

job = jobs.start(snakemake)
schemas = snakemake.params.get("schemas", {})
for name, path in snakemake.output.items():
    source = snakemake.input[name]
    page = report_page(source, schemas.get(name), os.path.relpath(source, snakemake.config["results_dir"]))
    write_text(path, page)
job.finish()
