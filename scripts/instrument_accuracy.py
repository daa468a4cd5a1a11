"""Snakemake shim: results/summaries/instruments.json, the accuracy of each instrument (rocklab.lab.accuracy)."""

from rocklab.io import setup_logging
from rocklab.lab.accuracy import accuracy_summary
from rocklab.summaries import write_summary

setup_logging(snakemake.log[0])
write_summary(accuracy_summary(), snakemake.output.docs_summary)
