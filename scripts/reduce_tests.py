"""Snakemake shim: reduce the tests of one job to results/tests/<test_id>.nc,
store the motion of each in results/motion/<test_id>.nc, and the attributes
their QC rows are made of in results/reduction/<job>.json, last: the job's
declared output, which a job cut short does not leave."""

import logging
from pathlib import Path

from rocklab.io import setup_logging, write_netcdf
from rocklab.lab.campaign import open_campaign
from rocklab.lab.motion import stored_motion
from rocklab.lab.reduction import reduce_tests, row_attrs, write_row_attrs

setup_logging(snakemake.log[0])
outputs = {Path(out).stem: out for out in snakemake.params.netcdf}
motions = {Path(out).stem: out for out in snakemake.params.motion}
rows = []
for test_id, ds in reduce_tests(open_campaign(snakemake.params.raw_dir), outputs, snakemake.params.options):
    logging.info("%s: valid=%s %s %s", test_id, ds.attrs["valid"], ds.attrs["reject_reason"], ds.attrs["reject_detail"])
    if ds.attrs.get("flags"):
        logging.info("%s: %s", test_id, ds.attrs["flags"])
    write_netcdf(ds, outputs[test_id])
    rows.append(row_attrs(ds))
    motion = stored_motion(ds)
    if "motion_error" in motion.attrs:
        logging.info("%s: no motion: %s", test_id, motion.attrs["motion_error"])
    write_netcdf(motion, motions[test_id])
write_row_attrs(rows, snakemake.output.rows)
