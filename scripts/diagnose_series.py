"""Snakemake shim: results/diagnosis/<job>.json, the entries of the series of a diagnosis job.

The series are read and diagnosed one at a time, so that the job's memory is
that of its largest series, not of all the job's tests.
"""

from rocklab import jobs
from rocklab.diagnosis import CampaignDiagnosis, diagnose_records, stored_records

job = jobs.start(snakemake)
entries = []
for series in snakemake.params.series:
    entry = diagnose_records(
        stored_records(snakemake.params.tests[series]).get(series, []),
        series,
        n_boot=snakemake.params.n_boot,
        n_history=snakemake.params.n_history,
        seed=snakemake.params.seed,
    )
    if entry:
        entries.append(entry)
CampaignDiagnosis.from_dict(entries).to_json(snakemake.output[0])
job.finish()
