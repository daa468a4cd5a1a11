"""Snakemake shim: the overturning maps (Sect. 5) of a batch of records.

Rules ``overturning_maps_<k>``: the paper's models, one file per record and
model.  Rules ``calibrated_maps_<k>``: the calibrated walls the campaign's
diagnosis names, one folder per record, one file per model in it.  Each
record logs to its own file.
"""

from pathlib import Path

import numba

from rocklab.diagnosis.result import CampaignDiagnosis
from rocklab.io import setup_logging, write_netcdf
from rocklab.seismic import calibrated
from rocklab.seismic.accelerograms import load_record
from rocklab.seismic.maps import overturning_map

numba.set_num_threads(min(snakemake.threads, numba.config.NUMBA_NUM_THREADS))
p = snakemake.params
# read once: every calibrated model of every record of the batch is built from it
diagnosis = CampaignDiagnosis.from_json(snakemake.input.diagnosis) if "diagnosis" in snakemake.input.keys() else None
names = calibrated.model_names(diagnosis) if diagnosis is not None else p.models
for k, record in enumerate(p.records):
    setup_logging(snakemake.log[k])
    if diagnosis is not None:
        folder = Path(snakemake.output[k])
        folder.mkdir(parents=True, exist_ok=True)
        paths = [folder / f"{record}__{name}.nc" for name in names]
    else:
        paths = snakemake.output[k * len(names) : (k + 1) * len(names)]
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
