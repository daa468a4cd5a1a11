"""Snakemake shim: restitution of the UMinho limestone blocks (results/limestone_diagnosis.json, .md, figure)."""

from rocklab import jobs
from rocklab.diagnosis.block_tests import blocks_markdown, diagnose_blocks, read_events
from rocklab.diagnosis.diagnosis_summary import limestone_summary
from rocklab.disk import write_text
from rocklab.plots import save_png
from rocklab.plots.diagnosis import family_figure
from rocklab.summaries import write_summary

job = jobs.start(snakemake)
events = read_events(snakemake.input.events)
limestone = diagnose_blocks(events, n_boot=snakemake.params.n_boot, seed=snakemake.params.seed)
save_png(family_figure(limestone, events), snakemake.output.figure, dpi=120)
limestone.to_json(snakemake.output.json)
write_text(snakemake.output.md, blocks_markdown(limestone))
write_summary(limestone_summary(limestone), snakemake.output.docs_summary)
job.finish()
