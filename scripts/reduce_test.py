"""Snakemake shim: reduce one test to results/tests/<test_id>.nc."""

import logging
import sys

from rocklab.campaign import open_campaign
from rocklab.reduction import reduce_test
from rocklab.workflow import setup_logging, write_netcdf

setup_logging(snakemake.log[0])
test_id = snakemake.wildcards.test_id
ds = reduce_test(open_campaign(snakemake.params.raw_dir), test_id, snakemake.params.options)
logging.info("%s: valid=%s %s %s", test_id, ds.attrs["valid"], ds.attrs["reject_reason"], ds.attrs["reject_detail"])
if ds.attrs.get("flags"):
    logging.info("%s: %s", test_id, ds.attrs["flags"])
write_netcdf(ds, snakemake.output[0])
