"""Snakemake shim: restitution of the UMinho limestone blocks (results/limestone_diagnosis.json, .md)."""

import json
from pathlib import Path

from rocklab.diagnosis import jsonable
from rocklab.diagnosis.block_tests import blocks_markdown, diagnose_blocks, read_events
from rocklab.io import setup_logging

setup_logging(snakemake.log[0])
result = diagnose_blocks(
    read_events(snakemake.input.events), n_boot=snakemake.params.n_boot, seed=snakemake.params.seed
)
Path(snakemake.output.json).write_text(json.dumps(jsonable(result), indent=1))
Path(snakemake.output.md).write_text(blocks_markdown(result))
