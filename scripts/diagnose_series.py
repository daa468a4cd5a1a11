"""Snakemake shim: results/diagnosis/<series>.json, the diagnosis of one series ([] if there is none)."""

import json
from pathlib import Path

from rocklab.diagnosis import diagnose_records, jsonable, records_by_series
from rocklab.io import setup_logging, valid_tests
from rocklab.lab.motion import read_motion

setup_logging(snakemake.log[0])
series = snakemake.wildcards.series
# a list: the tests are read twice (their motions, their records)
tests = list(valid_tests(snakemake.input.tests))
motions = {Path(p).stem: p for p in snakemake.input.motions}
stored = {t.attrs["test_id"]: read_motion(motions[t.attrs["test_id"]]) for t in tests}
records = records_by_series(tests, stored).get(series, [])
entry = diagnose_records(
    records, series, n_boot=snakemake.params.n_boot, n_history=snakemake.params.n_history, seed=snakemake.params.seed
)
Path(snakemake.output[0]).write_text(json.dumps(jsonable([entry] if entry else []), indent=1))
