"""Snakemake shim: results/diagnosis.json and diagnosis.md from the series' diagnoses."""

from rocklab import jobs
from rocklab.diagnosis import CampaignDiagnosis, with_boundaries, write_diagnosis
from rocklab.diagnosis.diagnosis_summary import diagnosis_summary
from rocklab.summaries import write_summary

job = jobs.start(snakemake)
series = CampaignDiagnosis.of_series_files(snakemake.input)
diagnosis = with_boundaries(series, walls=snakemake.params.walls, thickness=snakemake.params.thickness)
write_diagnosis(diagnosis, snakemake.output.json, snakemake.output.md)
write_summary(diagnosis_summary(diagnosis), snakemake.output.docs_summary)
job.finish()
