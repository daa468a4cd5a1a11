"""Snakemake shim: results/diagnosis/<series>.json of each series of a boundary condition ([] if there is none)."""

import json
from pathlib import Path

from rocklab.diagnosis import diagnose_records, jsonable, records_by_series
from rocklab.io import setup_logging, valid_tests
from rocklab.lab.motion import read_motion

setup_logging(snakemake.log[0])
# a list: the tests are read twice (their motions, their records)
tests = list(valid_tests(snakemake.input.tests))
motions = {Path(p).stem: p for p in snakemake.input.motions}
stored = {t.attrs["test_id"]: read_motion(motions[t.attrs["test_id"]]) for t in tests}
records = records_by_series(tests, stored)
for series, out in zip(snakemake.params.series, snakemake.output):
    entry = diagnose_records(
        records.get(series, []),
        series,
        n_boot=snakemake.params.n_boot,
        n_history=snakemake.params.n_history,
        seed=snakemake.params.seed,
    )
    Path(out).write_text(json.dumps(jsonable([entry] if entry else []), indent=1))
