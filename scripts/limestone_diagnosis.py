"""Snakemake shim: restitution of the UMinho limestone blocks (results/limestone_diagnosis.json, .md, figure)."""

from pathlib import Path

from rocklab.diagnosis import LimestoneDiagnosis
from rocklab.diagnosis.block_tests import blocks_markdown, diagnose_blocks, read_events
from rocklab.diagnosis.summary import limestone_summary
from rocklab.io import setup_logging
from rocklab.plots import save_png
from rocklab.plots.diagnosis import family_figure
from rocklab.summaries import write_summary

setup_logging(snakemake.log[0])
events = read_events(snakemake.input.events)
result = diagnose_blocks(events, n_boot=snakemake.params.n_boot, seed=snakemake.params.seed)
limestone = LimestoneDiagnosis.from_dict(result)
save_png(family_figure(limestone, events), snakemake.output.figure, dpi=120)
limestone.to_json(snakemake.output.json)
Path(snakemake.output.md).write_text(blocks_markdown(result))
write_summary(limestone_summary(snakemake.output.json), snakemake.output.docs_summary)
