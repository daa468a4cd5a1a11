"""Input/output helpers shared by the workflow scripts (no Snakemake needed).

Tables are validated against the JSON schemas of ``workflow/schemas`` before
they are written, netCDF files are written compressed and atomically, and
logging goes to the rule's log file.

netCDF files follow the CF conventions (:data:`CF_CONVENTIONS`, checked by
``cfchecker`` in ``tests/test_cf.py``): the datasets carry :func:`cf_attrs`
and a ``long_name`` and ``units`` on each variable, and :func:`write_netcdf`
stores text as character arrays and appends to ``history``.  The ``time``
of a test or a simulation is in seconds from the start of the record or of
the simulation, ``units = "s"`` and no ``standard_name``: no date is
known, so it is not a CF time axis (which needs ``units = "seconds since
<date>"``; a made-up date would tell CF tools when the test was done, and
``xarray.open_dataset`` would read datetimes), and every reader gets plain
seconds back.
"""

from __future__ import annotations

import glob
import logging
import os
import tempfile
from datetime import UTC, datetime
from pathlib import Path
from types import SimpleNamespace

import jsonschema
import numpy as np
import pandas as pd
import yaml

from rocklab import __version__

#: The version of the CF conventions that rocklab's netCDF files follow.
CF_CONVENTIONS = "CF-1.8"
#: The paper whose equations, tables and figures the files refer to.
REFERENCES = (
    "Sorrentino L., Masiani R., Griffith M.C., The relevance of energy damping in unreinforced masonry "
    "rocking mechanisms. Experimental and analytic investigations, Bulletin of Earthquake Engineering"
)


def setup_logging(path):
    """Send log records and warnings of this process to ``path``."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    logging.basicConfig(
        filename=path, filemode="w", level=logging.INFO, format="%(asctime)s %(levelname)s %(message)s", force=True
    )
    logging.captureWarnings(True)


def cf_attrs(title, source) -> dict:
    """Global attributes of a rocklab netCDF file (CF section 2.6.2).

    Parameters
    ----------
    title : str
        What the file holds.
    source : str
        How its data were made (a laboratory test, a simulation); the
        rocklab version is appended.
    """
    return {
        "Conventions": CF_CONVENTIONS,
        "title": title,
        "source": f"{source}, rocklab {__version__}",
        "references": REFERENCES,
    }


#: Compression of the numeric variables of :func:`write_netcdf`: zlib without
#: the shuffle filter, which splits the bytes of each float and so breaks up
#: the patterns zlib finds in readings of a few decimals (transducer
#: elongations: a third of their size without it, two thirds with it).
COMPRESSION = {"zlib": True, "complevel": 1, "shuffle": False}


def write_netcdf(ds, path):
    """Write a dataset compressed, through a temporary file, so an interrupted
    run never leaves a truncated output that looks complete.

    Text variables are written as character arrays, which every netCDF
    tool and CF-1.8 read (cfchecker rejects the netCDF-4 string type);
    ``xarray.open_dataset`` gives them back as str.  A line with the time
    and the rocklab version is appended to the ``history`` attribute.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    encoding = {name: dict(COMPRESSION) for name, var in ds.variables.items() if var.dtype.kind in "fiu" and var.ndim}
    text = {name: var.astype(str) for name, var in ds.variables.items() if var.dtype.kind in "OU"}
    encoding.update({name: {"dtype": "S1"} for name in text})
    # one assign, a shallow copy: the caller's dataset is left as it is
    ds = ds.assign(text)
    ds.attrs.setdefault("Conventions", CF_CONVENTIONS)
    line = f"{datetime.now(UTC):%Y-%m-%dT%H:%M:%SZ} rocklab {__version__}: wrote {path.name}"
    ds.attrs["history"] = "\n".join(filter(None, [ds.attrs.get("history", ""), line]))
    # a writer killed outright (SIGKILL) leaves its temporary file: the next
    # write of the same file, the rerun, removes it
    for stale in path.parent.glob(f".{glob.escape(path.name)}.*.tmp"):
        stale.unlink(missing_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        ds.to_netcdf(tmp, engine="netcdf4", encoding=encoding)
        # mkstemp makes the file private (0600): give it the mode of any new file
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def benchmark_times(results) -> pd.DataFrame:
    """The jobs of a workflow run from Snakemake's benchmark files.

    Parameters
    ----------
    results : path-like
        A results folder; its ``benchmarks/`` holds one ``<rule>.tsv`` per
        single-job rule and ``<folder>/<job>.tsv`` per job of a stage of
        many jobs (the reduction, the diagnosis, the maps).

    Returns
    -------
    pandas.DataFrame
        One row per job: ``stage`` (the rule or the folder), ``job`` (the
        file's path under ``benchmarks/`` without ``.tsv``), ``s`` (wall time
        of the job [s]) and ``cpu_s`` (its CPU time [s], NaN where the file
        has none: Snakemake samples it once a second for the first 30 s of a
        job and every 30 s after, so it is a lower bound for a long job).
    """
    root = Path(results) / "benchmarks"
    rows = []
    for tsv in sorted(root.rglob("*.tsv")) if root.is_dir() else []:
        job = tsv.relative_to(root).with_suffix("")
        last = pd.read_csv(tsv, sep="\t").iloc[-1]
        rows.append(
            {
                "stage": job.parts[0],
                "job": job.as_posix(),
                "s": float(last["s"]),
                "cpu_s": float(last.get("cpu_time", np.nan)),
            }
        )
    return pd.DataFrame(rows, columns=["stage", "job", "s", "cpu_s"])


def read_attrs(paths):
    """The global attributes of netCDF files, without loading their data."""
    import netCDF4

    out = []
    for p in paths:
        with netCDF4.Dataset(p) as nc:
            out.append(SimpleNamespace(attrs={k: nc.getncattr(k) for k in nc.ncattrs()}, path=str(p)))
    return out


def load_schema(path):
    with open(path) as fh:
        return yaml.safe_load(fh)


def validate_table(df: pd.DataFrame, schema) -> None:
    """Check every row of a table against a JSON schema (``workflow/schemas``).

    Raises
    ------
    jsonschema.ValidationError
        Naming the first offending row and column.
    """
    schema = load_schema(schema) if isinstance(schema, (str, Path)) else schema
    required = schema.get("required", [])
    missing = [c for c in required if c not in df.columns]
    if missing:
        raise jsonschema.ValidationError(f"missing column(s) {', '.join(missing)}")
    validator = jsonschema.Draft202012Validator(schema)
    records = df.replace({np.nan: None}).to_dict("records")
    for i, rec in enumerate(records):
        err = jsonschema.exceptions.best_match(validator.iter_errors(rec))
        if err is not None:
            col = "/".join(str(x) for x in err.path) or "row"
            raise jsonschema.ValidationError(f"row {i + 1}, {col}: {err.message}")


def write_table(df: pd.DataFrame, path, schema=None, float_format="%.6g") -> None:
    """Validate (when a schema is given) and write a CSV table."""
    if schema is not None:
        validate_table(df, schema)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(path, index=False, float_format=float_format)


def valid_test_ids(qc_path) -> list:
    """Test ids that ``qc.csv`` marks valid, in its order."""
    qc = pd.read_csv(qc_path, keep_default_na=False)
    return qc.test_id[qc.valid.astype(str) == "True"].tolist()


def load_datasets(paths, keep=None):
    """Yield the netCDF files at ``paths`` loaded into memory (files closed),
    those for which ``keep(dataset)`` is true if given."""
    import xarray as xr

    for path in paths:
        with xr.open_dataset(path) as ds:
            if keep is None or keep(ds):
                yield ds.load()


def valid_tests(paths, qc_path=None):
    """Yield the reduced datasets of the valid tests, loaded.

    Valid: marked so in ``qc.csv``, or without it by the test's own verdict
    (its ``valid`` attribute, of which qc.csv is made), so that a job over
    a few tests need not depend on the QC of the whole campaign.
    """
    if qc_path is None:
        return load_datasets(paths, lambda ds: int(ds.attrs.get("valid", 0)))
    valid = set(valid_test_ids(qc_path))
    return load_datasets(p for p in paths if Path(p).stem in valid)
