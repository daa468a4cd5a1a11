"""Snakemake shim: the energy-dissipation tables of the valid tests."""

import logging
from pathlib import Path

import pandas as pd
import xarray as xr

from rocklab.statistics import campaign_tables
from rocklab.workflow import setup_logging, write_table

setup_logging(snakemake.log[0])
qc = pd.read_csv(snakemake.input.qc, keep_default_na=False, na_values=[""])
valid = set(qc.test_id[qc.valid.astype(str) == "True"])


def reduced():
    for path in snakemake.input.tests:
        if Path(path).stem in valid:
            with xr.open_dataset(path) as ds:
                yield ds.load()


tables, failed = campaign_tables(reduced(), qc, snakemake.params.n_boot, snakemake.params.seed)
for test_id, why in failed:
    logging.warning("%s: motion not analysed: %s", test_id, why)
schemas = Path(snakemake.params.schemas)
for name in ("tests", "impacts", "e_by_n", "series", "laws", "effects"):
    schema = schemas / f"{name}.schema.yaml"
    write_table(tables[name], snakemake.output[name], schema if schema.exists() else None)
