"""Snakemake shim: reduce the tests of one job to results/tests/<job>/<test_id>.nc,
each with its motion inside (rocklab.lab.motion.write_test_with_motion), and
the attributes their QC rows are made of in results/reduction/<job>.json, and
the dissipation tables of its valid tests in results/reduction/<job>.dissipation.json
(rocklab.dissipation.analysis.AnalysedTests)."""

import logging
from pathlib import Path

from rocklab import jobs
from rocklab.dissipation.analysis import AnalysedTests
from rocklab.io import is_valid
from rocklab.lab.campaign import open_campaign
from rocklab.lab.motion import write_test_with_motion
from rocklab.lab.reduction import reduce_tests, row_attrs, write_row_attrs

job = jobs.start(snakemake)
folder = Path(snakemake.output.tests)
outputs = {t: folder / f"{t}.nc" for t in snakemake.params.tests}
rows, valid = [], []
for test_id, ds in reduce_tests(open_campaign(snakemake.params.raw_dir), outputs, snakemake.params.options):
    logging.info("%s: valid=%s %s %s", test_id, ds.attrs["valid"], ds.attrs["reject_reason"], ds.attrs["reject_detail"])
    if ds.attrs.get("flags"):
        logging.info("%s: %s", test_id, ds.attrs["flags"])
    motion = write_test_with_motion(ds, outputs[test_id])
    rows.append(row_attrs(ds))
    if is_valid(ds.attrs):
        valid.append(motion)
    if "motion_error" in motion.attrs:
        logging.info("%s: no motion: %s", test_id, motion.attrs["motion_error"])
write_row_attrs(rows, snakemake.output.rows)
AnalysedTests.of(valid).write(snakemake.output.dissipation)
job.finish()
