"""Snakemake shim: results/diagnosis/<series>.json of each series of a boundary condition ([] if there is none).

The series are read and diagnosed one at a time, so that the job's memory is
that of its largest series, not of the boundary condition's whole campaign.
"""

from pathlib import Path

from rocklab.diagnosis import CampaignDiagnosis, diagnose_records, records_by_series
from rocklab.io import setup_logging, valid_tests
from rocklab.lab.motion import read_motion

setup_logging(snakemake.log[0])
motions = {Path(p).stem: p for p in snakemake.params.motions}
for series, out in zip(snakemake.params.series, snakemake.output):
    # a list: the tests are read twice (their motions, their records); of
    # their records the diagnosis needs the rotation, its time and the attributes
    tests = list(valid_tests(snakemake.params.tests[series], variables=("theta",)))
    stored = {t.attrs["test_id"]: read_motion(motions[t.attrs["test_id"]]) for t in tests}
    entry = diagnose_records(
        records_by_series(tests, stored).get(series, []),
        series,
        n_boot=snakemake.params.n_boot,
        n_history=snakemake.params.n_history,
        seed=snakemake.params.seed,
    )
    CampaignDiagnosis.from_dict([entry] if entry else []).to_json(out)
