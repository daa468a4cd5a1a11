"""Snakemake shim: PGA, PGV and the sign check of every shake-table record."""

from rocklab import jobs
from rocklab.io import write_table
from rocklab.shake_table.asu_data import read_tests
from rocklab.shake_table.evaluation import motion_table

job = jobs.start(snakemake)
p = snakemake.params
tests = read_tests(p.folder)
if p.ground_motions:
    tests = tests[tests.ground_motion.isin(p.ground_motions)]
write_table(motion_table(p.folder, tests), snakemake.output[0], p.schema)
job.finish()
