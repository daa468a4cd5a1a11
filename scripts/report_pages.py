"""Snakemake shim: the report's HTML page of each input table or text, under the same name."""

import os
from pathlib import Path

from rocklab.io import setup_logging
from rocklab.report.html import report_page

setup_logging(snakemake.log[0])
schemas = snakemake.params.get("schemas", {})
for name, path in snakemake.output.items():
    source = snakemake.input[name]
    page = report_page(source, schemas.get(name), os.path.relpath(source, snakemake.config["results_dir"]))
    Path(path).write_text(page)
