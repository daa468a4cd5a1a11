"""Checks of the workflow's configuration that its schema cannot express.

Every key, with its meaning and default, is in
``workflow/schemas/config.schema.yaml``; Snakemake validates the
configuration against it and fills in the defaults.  What a schema cannot
see is the file system: whether ``raw_dir`` is a campaign folder, whether
``results_dir`` would write into it, and whether it can be written at all.  Those checks live here, as do
the paths the workflow records with each output.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Collection, Mapping
from pathlib import Path
from typing import Any

import jsonschema

from rocklab.disk import StrPath

#: The schema of the workflow's configuration, relative to the checkout.
SCHEMA = "workflow/schemas/config.schema.yaml"


def schema_defaults(schema: Mapping[str, Any]) -> dict[str, Any]:
    """The configuration a parsed JSON schema's defaults make, nested objects included
    (what Snakemake fills in where a configuration is silent)."""
    return {
        k: schema_defaults(sub) if sub.get("type") == "object" and "properties" in sub else sub["default"]
        for k, sub in schema["properties"].items()
    }


class ConfigError(ValueError):
    """A configuration the workflow refuses; the message says why in one line."""


def schema_error(exc: BaseException) -> ConfigError:
    """The one-line :class:`ConfigError` of a configuration that fails its schema.

    Parameters
    ----------
    exc : Exception
        The ``jsonschema.ValidationError`` itself, or an exception that
        carries it among its ``args`` or as its context (Snakemake's
        ``validate`` raises a ``WorkflowError`` that prints the whole schema).

    Returns
    -------
    ConfigError
        Naming the key: an unknown key with the keys known at its level
        (a misspelt ``result_dir`` reads "unknown config key result_dir"),
        a bad value with what the schema asks of it.
    """
    errors = [exc, *exc.args, exc.__context__]
    err = next((e for e in errors if isinstance(e, jsonschema.ValidationError)), None)
    if err is None:
        return ConfigError(f"configuration refused by {SCHEMA}: {exc}")
    where = ".".join(str(k) for k in err.absolute_path)
    if err.validator == "additionalProperties":
        known = list(err.schema.get("properties", {}))
        unknown = sorted(set(err.instance) - set(known))
        keys = ", ".join(f"{where}.{k}" if where else k for k in unknown)
        return ConfigError(f"unknown config key {keys} (the keys here: {', '.join(known)}; see {SCHEMA})")
    hint = ""
    if err.validator == "type" and isinstance(err.instance, str) and len(err.absolute_path) > 1:
        hint = "; --config passes nested values as text, give them in a file with --configfile"
    return ConfigError(f"config key {where or '(top level)'}: {err.message} (see {SCHEMA}{hint})")


def check_paths(raw_dir: StrPath, results_dir: StrPath) -> None:
    """Refuse a ``raw_dir`` that is not a campaign or a ``results_dir`` inside it.

    Parameters
    ----------
    raw_dir : path-like
        Campaign folder in the lab's raw format (``docs/raw-format.md``).
    results_dir : path-like
        Output folder; it need not exist yet.

    Raises
    ------
    ConfigError
        ``raw_dir`` is not a folder or has no ``tests.csv``; ``results_dir``
        is ``raw_dir`` or lies inside it (the campaign folder is only read),
        holds it (a result could overwrite a record: ``results/tests/``),
        or is a file.  Both are compared resolved, symbolic links followed.
    """
    raw = Path(raw_dir)
    campaign = "a campaign in the lab's raw format, docs/raw-format.md"
    if not raw.is_dir():
        raise ConfigError(f"raw_dir {str(raw_dir)!r} is not a folder ({campaign})")
    if not (raw / "tests.csv").is_file():
        raise ConfigError(f"raw_dir {str(raw_dir)!r} has no tests.csv: not {campaign}")
    raw, results = raw.resolve(), Path(results_dir).resolve()
    if results == raw or raw in results.parents:
        raise ConfigError(
            f"results_dir {str(results_dir)!r} is inside raw_dir {str(raw)!r}: the campaign folder is only read, "
            "write the results elsewhere"
        )
    if results in raw.parents:
        raise ConfigError(
            f"raw_dir {str(raw_dir)!r} is inside results_dir {str(results_dir)!r}: the results could overwrite "
            "the campaign, write them elsewhere"
        )
    if results.exists() and not results.is_dir():
        raise ConfigError(f"results_dir {str(results_dir)!r} is a file, not a folder")


#: Bytes the write check of ``results_dir`` writes: a filesystem block.
WRITE_PROBE = 4096


def check_writable(results_dir: StrPath) -> None:
    """Refuse a ``results_dir`` that cannot be written, before any job starts.

    The folder is created if it does not exist, and a file of one block
    written and removed in it (file modes alone do not tell: a read-only
    mount, a folder of another user, or a disk without a free block all
    refuse a write; a disk that fills up later stops the job that finds it
    full, :class:`rocklab.disk.NoSpace`).

    Raises
    ------
    ConfigError
        Naming the folder and what the system said.
    """
    folder = Path(results_dir)
    probe = None
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(prefix=".rocklab-write-check-", dir=folder)
        with os.fdopen(fd, "wb") as fh:
            fh.write(b"\0" * WRITE_PROBE)
    except OSError as exc:
        why = exc.strerror or str(exc)
        raise ConfigError(
            f"results_dir {str(results_dir)!r} cannot be written ({why}): give a folder you can write "
            "with --config results_dir=..., or free its disk"
        ) from None
    finally:
        if probe is not None:
            with contextlib.suppress(OSError):
                os.remove(probe)


def check_names(config: Mapping[str, Any], test_ids: Collection[str], records: Collection[str]) -> None:
    """Refuse a test or accelerogram that the configuration names and the inputs lack.

    They become file names of the results (``tests/<job>/<id>.nc``,
    ``maps/records-<k>/<record>__<model>.nc``): a name that is not one of the campaign's
    tests or of the manifest's records could make the workflow read or write
    outside ``results_dir``, or fail late for want of an input.

    Parameters
    ----------
    config : dict
        The workflow configuration, its defaults filled in.
    test_ids : sequence of str
        The campaign's tests with a results file (``Campaign.test_ids``).
    records : sequence of str
        The records of the accelerogram manifest.

    Raises
    ------
    ConfigError
        Naming the key and the value.
    """
    for key in ("sample_test", "fig20_test"):
        value = config["figures"][key]
        if value and value not in test_ids:
            raise ConfigError(f"config key figures.{key}: {value!r} is not a test of raw_dir's tests.csv")
    maps = config["maps"]
    for where, value in [
        *(("maps.records", r) for r in maps["records"]),
        ("maps.figure_record", maps["figure_record"]),
    ]:
        if value not in records:
            raise ConfigError(f"config key {where}: {value!r} is not a record of the accelerogram manifest")


def calibrated_map_n(n: int, calibrated_n: int) -> int:
    """Values of A_S/A and of D_S/D of the calibrated walls' maps: ``maps.calibrated_n``, at most ``maps.n``.

    Raises
    ------
    ConfigError
        Naming ``maps.calibrated_n`` when its grid is not a subgrid of the
        paper's maps of ``n`` values (the e-alone maps are read on its cells).
    """
    # the maps import xarray and the causes of the diagnosis: only where maps are configured
    from rocklab.seismic.maps import subgrid_step

    n_cal = min(calibrated_n, n)
    try:
        subgrid_step(n, n_cal)
    except ValueError as err:
        raise ConfigError(f"config key maps.calibrated_n: {n_cal} with maps.n = {n}: {err}") from None
    return n_cal


def recorded_path(path: StrPath, workdir: StrPath | None = None) -> str:
    """``path`` as the workflow records it: relative to ``workdir`` when inside it, else absolute.

    Snakemake stores each job's params and list of inputs with its outputs,
    and reruns the job when they change.  A file of the checkout given
    relative to the working directory (the checkout) reads the same after
    the checkout moves, so moving it reruns nothing; a file outside keeps
    its absolute path, which the move does not change.

    Parameters
    ----------
    path : path-like
    workdir : path-like, optional
        Default: the current directory (Snakemake's working directory).

    Returns
    -------
    str
    """
    path = Path(path).resolve()
    workdir = Path(os.getcwd() if workdir is None else workdir).resolve()
    return str(path.relative_to(workdir)) if path.is_relative_to(workdir) else str(path)
