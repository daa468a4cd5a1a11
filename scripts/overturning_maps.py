"""Snakemake shim: the overturning maps (Sect. 5) of a batch of records, in
the job's folder (its declared output), one file per record and model.

Rule ``overturning_maps``: the paper's models.  Rule ``calibrated_maps``:
the calibrated walls the campaign's diagnosis names.  Each record logs to
its own file.
"""

import logging
from pathlib import Path

import numba

from rocklab import jobs
from rocklab.diagnosis.result import CampaignDiagnosis
from rocklab.io import setup_logging, write_netcdf
from rocklab.seismic import calibrated
from rocklab.seismic.accelerograms import load_record
from rocklab.seismic.maps import overturning_map

numba.set_num_threads(min(snakemake.threads, numba.config.NUMBA_NUM_THREADS))
job = jobs.start(snakemake)
p = snakemake.params
# read once: every calibrated model of every record of the batch is built from it
diagnosis = CampaignDiagnosis.from_json(snakemake.input.diagnosis) if "diagnosis" in snakemake.input.keys() else None
names = calibrated.model_names(diagnosis) if diagnosis is not None else p.models
folder = Path(snakemake.output[0])
logging.info("records %s: %d maps each, logged in %s", ", ".join(p.records), len(names), ", ".join(p.logs))
for k, record in enumerate(p.records):
    setup_logging(p.logs[k])
    paths = [folder / f"{record}__{name}.nc" for name in names]
    trace = load_record(record)
    for name, path in zip(names, paths):
        ds = overturning_map(
            trace,
            model=name,
            n=p.n,
            lo=p.lo,
            hi=p.hi,
            alpha=p.alpha,
            R=p.R,
            form=p.form,
            eq17=(p.eq17["a"], p.eq17["b"]),
            diagnosis=diagnosis,
            polarity=p.polarity,
            chunks=p.chunks,
        )
        write_netcdf(ds, path)
job.finish()
