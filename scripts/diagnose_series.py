"""Snakemake shim: results/diagnosis/<job>.json, the entries of the series of a diagnosis job.

The series are read and diagnosed one at a time, so that the job's memory is
that of its largest series, not of all the job's tests.
"""

from pathlib import Path

from rocklab.diagnosis import CampaignDiagnosis, diagnose_records, records_by_series
from rocklab.io import setup_logging, valid_tests
from rocklab.lab.motion import read_motion

setup_logging(snakemake.log[0])
entries = []
for series in snakemake.params.series:
    # a list: the tests are read twice (their motions, their records); of
    # their records the diagnosis needs the rotation, its time and the attributes
    paths = {Path(p).stem: p for p in snakemake.params.tests[series]}
    tests = list(valid_tests(paths.values(), variables=("theta",)))
    # the motion each test's file holds (its group, read apart from its records)
    stored = {t.attrs["test_id"]: read_motion(paths[t.attrs["test_id"]]) for t in tests}
    entry = diagnose_records(
        records_by_series(tests, stored).get(series, []),
        series,
        n_boot=snakemake.params.n_boot,
        n_history=snakemake.params.n_history,
        seed=snakemake.params.seed,
    )
    if entry:
        entries.append(entry)
CampaignDiagnosis.from_dict(entries).to_json(snakemake.output[0])
