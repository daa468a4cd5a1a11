"""Snakemake shim: results/summaries/instruments.json, the accuracy of each instrument (rocklab.lab.accuracy)."""

from rocklab import jobs
from rocklab.lab.accuracy import accuracy_summary
from rocklab.summaries import write_summary

job = jobs.start(snakemake)
write_summary(accuracy_summary(n_tests=snakemake.params.n_tests), snakemake.output.docs_summary)
job.finish()
