"""Input/output helpers shared by the workflow scripts (no Snakemake needed).

Tables are validated against the JSON schemas of ``workflow/schemas`` before
they are written, netCDF files are written compressed and atomically
(:func:`write_netcdf`) and read back as xarray reads them, only the
variables asked for (:func:`read_dataset`), both through netCDF4 directly,
and logging goes to the rule's log file.

Every file is written through a temporary file beside it, renamed into place
once complete (:func:`rocklab.disk.atomic_output`): a job killed or out of
disk space never leaves a half-written result under its final name.

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

import logging
import sys
import zlib
from collections.abc import Callable, Hashable, Iterable, Iterator, Mapping
from datetime import UTC, datetime
from numbers import Number
from pathlib import Path
from typing import TYPE_CHECKING, Any, overload

import numpy as np
import yaml

from rocklab import __version__
from rocklab._imports import lazy_module
from rocklab.disk import SPACE_ERRNOS, atomic_output, no_space, write_text

if TYPE_CHECKING:
    import jsonschema
    import pandas as pd
    import xarray as xr
else:
    # bound lazily: a job that writes report pages needs neither
    jsonschema = lazy_module("jsonschema")
    pd = lazy_module("pandas")

#: A variable as :func:`write_netcdf` stores it (:func:`_stored_variable`):
#: dimensions, data, attributes, fill value and compression.
Stored = tuple[tuple[Hashable, ...], np.ndarray, dict[str, Any], Any, dict[str, Any]]

#: The version of the CF conventions that rocklab's netCDF files follow.
CF_CONVENTIONS = "CF-1.8"
#: The paper whose equations, tables and figures the files refer to.
REFERENCES = (
    "Sorrentino L., Masiani R., Griffith M.C., The relevance of energy damping in unreinforced masonry "
    "rocking mechanisms. Experimental and analytic investigations, Bulletin of Earthquake Engineering"
)


class _JobLog(logging.FileHandler):
    """A job's log file, which a full disk silences rather than floods: the
    failed write that stops the job says what happened (:class:`NoSpace`)."""

    def handleError(self, record: logging.LogRecord) -> None:
        exc = sys.exc_info()[1]
        if isinstance(exc, OSError) and exc.errno in SPACE_ERRNOS:
            return
        super().handleError(record)

    def close(self) -> None:
        # a job that logs to several files in turn closes each before the next: the lines
        # a full disk kept in its buffer are lost, not a traceback under the one-line stop
        try:
            super().close()
        except OSError as exc:
            if exc.errno not in SPACE_ERRNOS:
                raise


def setup_logging(path: str | Path) -> None:
    """Send log records and warnings of this process to ``path``.

    Raises
    ------
    rocklab.disk.NoSpace
        The log file cannot be made for want of space.
    """
    try:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        handler = _JobLog(path, mode="w")
    except OSError as exc:
        if (full := no_space(exc, path)) is not None:
            raise full from exc
        raise
    handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(message)s"))
    logging.basicConfig(level=logging.INFO, handlers=[handler], force=True)
    logging.captureWarnings(True)


def cf_attrs(title: str, source: str) -> dict[str, str]:
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
#: A variable of which zlib cannot bring :data:`COMPRESSION_PROBE` bytes from
#: its middle below this share of their size is stored uncompressed: the rotations
#: solved at full precision keep 85-95 % of their size and took a quarter of
#: the time of writing a reduced test.
COMPRESSION_WORTH = 0.8
COMPRESSION_PROBE = 8192
#: At most this many bytes (a few numbers per channel or impact), a variable is stored
#: uncompressed: its chunk index outweighs what zlib saves (reduced tests 4 % smaller, 4 % faster).
COMPRESSION_MIN_BYTES = 1024


#: Attributes by which xarray encodes or decodes a variable (masking,
#: scaling, times, booleans, text, auxiliary coordinates): :func:`write_netcdf`
#: leaves a dataset with any of them to xarray, and :func:`read_dataset` a
#: file with any of them beyond those :func:`write_netcdf` writes itself.
XARRAY_CODED = frozenset(
    "_FillValue missing_value scale_factor add_offset _Unsigned dtype _Encoding calendar coordinates".split()
)
#: Units by which xarray may read a variable as times (with "since") or
#: durations (``xarray.coding.times.TIME_UNITS``).
TIME_UNITS = frozenset({"days", "hours", "minutes", "seconds", "milliseconds", "microseconds", "nanoseconds"})
#: Global attributes that CF-1.8 (section 2.7) keeps in the root group.
ROOT_ONLY = ("Conventions", "history")
#: What a netCDF attribute may hold (xarray's check before it writes one).
ATTRIBUTE_TYPES = (str, Number, np.ndarray, np.number, list, tuple, bytes)


def write_netcdf(ds: xr.Dataset, path: str | Path, groups: Mapping[str, xr.Dataset] | None = None) -> None:
    """Write a dataset compressed, through a temporary file (:func:`atomic_output`),
    so an interrupted run never leaves a truncated output that looks complete.

    ``groups`` maps a name to a dataset stored in the file as the netCDF-4
    group of that name (CF-1.8 section 2.7; read back with
    :func:`read_dataset`'s ``group``): its variables and attributes, less
    ``Conventions`` and ``history``, which CF keeps in the root group.

    Numbers are compressed (:data:`COMPRESSION`) where it pays (:data:`COMPRESSION_WORTH`,
    :data:`COMPRESSION_MIN_BYTES`), floats with ``_FillValue`` NaN; booleans are stored as
    int8 with ``dtype = "bool"``; text as character arrays, which every netCDF tool and
    CF-1.8 read (cfchecker rejects the netCDF-4 string type); ``xarray.open_dataset`` gives
    them back as bool and str.  A line with the time and the rocklab version is appended to
    the ``history`` attribute.  A variable's own ``encoding`` is not used.

    These kinds, the only ones rocklab writes, go through netCDF4 directly
    (:func:`_stored_variable`), encoded as xarray encodes them; a dataset with anything else
    (times, auxiliary coordinates, attributes of :data:`XARRAY_CODED`) is written by
    ``xarray.Dataset.to_netcdf``.  ``tests/test_io.py`` checks that both read back the same.
    """
    path = Path(path)
    attrs = dict(ds.attrs)
    attrs.setdefault("Conventions", CF_CONVENTIONS)
    line = f"{datetime.now(UTC):%Y-%m-%dT%H:%M:%SZ} rocklab {__version__}: wrote {path.name}"
    attrs["history"] = "\n".join(filter(None, [attrs.get("history", ""), line]))
    stored = {name: _stored_variable(var) for name, var in ds.variables.items()}
    grouped = {
        name: (
            {k: v for k, v in g.attrs.items() if k not in ROOT_ONLY},
            {n: _stored_variable(var) for n, var in g.variables.items()},
        )
        for name, g in (groups or {}).items()
    }
    # auxiliary coordinates: xarray names them in a `coordinates` attribute
    direct = all(
        all(v is not None for v in variables.values()) and set(d.coords) <= set(d.dims)
        for d, variables in [(ds, stored), *(((groups or {})[n], v) for n, (_, v) in grouped.items())]
    )
    # compressed as it is written: the uncompressed size bounds what it needs
    needed = ds.nbytes + sum(g.nbytes for g in (groups or {}).values())
    with atomic_output(path, needed) as tmp:
        if direct:
            _write_variables(stored, attrs, tmp, path, grouped)
        else:
            _write_with_xarray(ds.assign_attrs(attrs), tmp)
            for name, g in (groups or {}).items():
                g = g.copy(deep=False)
                g.attrs = grouped[name][0]
                _write_with_xarray(g, tmp, name)


def _stored_variable(var: xr.Variable) -> Stored | None:
    """A variable as :func:`write_netcdf` stores it, encoded as xarray would.

    Returns
    -------
    tuple or None
        Dimensions, data, attributes, fill value and compression
        (``netCDF4.Dataset.createVariable``'s arguments); None for a kind
        left to xarray.
    """
    attrs = dict(var.attrs)
    if XARRAY_CODED & attrs.keys():
        return None
    data = np.asarray(var.values)
    kind = data.dtype.kind
    if kind in "OU":
        # utf-8 bytes, one character each along a last dimension named after their count
        encoded = np.array([s.encode() for s in data.astype(str).ravel()], dtype=bytes).reshape(data.shape)
        chars = encoded.reshape(*data.shape, 1).view("S1")
        return (*var.dims, f"string{chars.shape[-1]}"), chars, {**attrs, "_Encoding": "utf-8"}, None, {}
    if kind == "b":
        return var.dims, data.astype(np.int8), {**attrs, "dtype": "bool"}, None, {}
    if kind in "iu" or data.dtype in (np.float32, np.float64):
        fill = data.dtype.type(np.nan) if kind == "f" else None
        return var.dims, data, attrs, fill, COMPRESSION if data.ndim and _compresses(data) else {}
    return None


def _compresses(data: np.ndarray) -> bool:
    """Whether zlib is worth its time on ``data`` (:data:`COMPRESSION_WORTH`, :data:`COMPRESSION_MIN_BYTES`)."""
    if data.nbytes <= COMPRESSION_MIN_BYTES:
        return False
    # from the middle: a record's first and last samples are often the wall at rest, which any coder packs
    flat = np.ascontiguousarray(data).reshape(-1)
    start = max(0, (flat.size - COMPRESSION_PROBE // data.itemsize) // 2)
    probe = flat[start : start + COMPRESSION_PROBE // data.itemsize].tobytes()
    return len(zlib.compress(probe, COMPRESSION["complevel"])) < COMPRESSION_WORTH * len(probe)


def _write_variables(
    stored: Mapping[Hashable, Stored | None],
    attrs: Mapping[str, Any],
    tmp: Path,
    path: Path,
    groups: Mapping[str, tuple[Mapping[str, Any], Mapping[Hashable, Stored | None]]] | None = None,
) -> None:
    """Write :func:`_stored_variable`'s variables and the global ``attrs`` to
    ``tmp`` (for ``path``), and each of ``groups`` (name: its attributes and
    stored variables) as a group."""
    import netCDF4

    with netCDF4.Dataset(tmp, "w", format="NETCDF4") as nc:
        # (netCDF4 dataset or group, its attributes, its variables, where in words);
        # the names are xarray's, any hashable (str in rocklab's datasets)
        parts: list[tuple[Any, Mapping[str, Any], Mapping[Hashable, Stored | None], str]] = [
            (nc, attrs, stored, str(path))
        ]
        for group, (group_attrs, group_stored) in (groups or {}).items():
            parts.append((nc.createGroup(group), group_attrs, group_stored, f"{path}, group {group}"))
        for where, where_attrs, variables, label in parts:
            _set_attributes(where, where_attrs, label)
            for name, entry in variables.items():
                assert entry is not None  # written directly: every variable stored
                dims, data, var_attrs, fill, compression = entry
                for dim, size in zip(dims, data.shape):
                    if dim not in where.dimensions:
                        where.createDimension(dim, size)
                var = where.createVariable(name, data.dtype, dims, fill_value=fill, **compression)
                _set_attributes(var, var_attrs, f"{label}, variable {name}")
        # every variable defined before any is written: a write after a
        # definition has netCDF-C write the metadata of the whole file again
        for where, _, variables, _ in parts:
            where.set_auto_maskandscale(False)
            where.set_auto_chartostring(False)
            for name, entry in variables.items():
                assert entry is not None
                where.variables[name][...] = entry[1]


def _set_attributes(obj: Any, attrs: Mapping[str, Any], where: str) -> None:
    """Set the attributes of a netCDF4 dataset or variable as xarray would."""
    for key, value in attrs.items():
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, ATTRIBUTE_TYPES):
            raise TypeError(
                f"{where}: attribute {key!r} = {value!r}: a netCDF attribute holds a number, text or an array"
            )
        array = np.asarray(value)
        if array.dtype.kind in "US" and array.size > 1:
            obj.setncattr_string(key, value)
        else:
            obj.setncattr(key, value)


def _write_with_xarray(ds: xr.Dataset, tmp: Path, group: str | None = None) -> None:
    """:func:`write_netcdf`'s encoding through ``xarray.Dataset.to_netcdf``
    (into ``group`` of the file ``tmp`` already holds, if given)."""
    encoding: dict[Hashable, dict[str, Any]] = {
        name: dict(COMPRESSION)
        for name, var in ds.variables.items()
        if var.dtype.kind in "fiu" and var.ndim and _compresses(var.values)
    }
    text = {name: var.astype(str) for name, var in ds.variables.items() if var.dtype.kind in "OU"}
    encoding.update({name: {"dtype": "S1"} for name in text})
    # one assign, a shallow copy: the caller's dataset is left as it is
    ds.assign(text).to_netcdf(tmp, engine="netcdf4", encoding=encoding, group=group, mode="a" if group else "w")


def _attributes(obj: Any) -> dict[str, Any]:
    """The attributes of a netCDF4 dataset or variable, as xarray gives them."""
    return {k: obj.getncattr(k) for k in obj.ncattrs()}


def read_dataset(path: str | Path, variables: Iterable[str] | None = None, group: str | None = None) -> xr.Dataset:
    """A netCDF file loaded into memory (closed), as
    ``xarray.open_dataset(path)[variables].load()`` gives it.

    Read with netCDF4 directly, without xarray's machinery per variable
    (the less so the fewer variables are asked for), decoded as xarray
    decodes what :func:`write_netcdf` writes:
    character arrays to str (or bytes without ``_Encoding``), int8 with
    ``dtype = "bool"`` to bool, ``_FillValue`` NaN dropped from the
    attributes; numbers as stored, attributes as netCDF4 gives them (numpy
    scalars and arrays, str).  A file with attributes that xarray decodes
    otherwise (:data:`XARRAY_CODED`, times) is read by xarray.  The
    variables carry no ``encoding``.

    Parameters
    ----------
    path : path-like
        The file.
    variables : sequence of str, optional
        The variables to load, with the coordinates of their dimensions
        (``time`` for a reduced test's ``theta``); all if None.
    group : str, optional
        The group of the file to read (:func:`write_netcdf`'s ``groups``),
        its attributes as the dataset's; the root group if None.

    Raises
    ------
    KeyError
        Naming the file and the variables it lacks.
    """
    ds = _read(path, variables, group=group)
    assert ds is not None and not isinstance(ds, tuple)  # no keep, no also: the dataset
    return ds


#: What :func:`load_datasets` keeps: a test of these global attributes or not.
Keep = Callable[[dict[str, Any]], Any]


def _read(
    path: str | Path,
    variables: Iterable[str] | None = None,
    keep: Keep | None = None,
    group: str | None = None,
    also: str | None = None,
) -> xr.Dataset | tuple[xr.Dataset, xr.Dataset] | None:
    """:func:`read_dataset`; None where ``keep(global attributes)`` is false.

    ``also``: a group read from the same open file (all its variables), the
    result then the pair (dataset, that group): opening a reduced test's
    file costs netCDF-C more than reading its motion.
    """
    import netCDF4

    with netCDF4.Dataset(path) as root:
        ds = _from_handle(root, path, variables, keep, group)
        if ds is None or also is None:
            return ds
        group_ds = _from_handle(root, path, None, None, also)
        assert group_ds is not None  # no keep
        return ds, group_ds


def _from_handle(
    root: Any, path: str | Path, variables: Iterable[str] | None, keep: Keep | None, group: str | None
) -> xr.Dataset | None:
    """:func:`_read` of one group (the root if None) of the open file ``root``."""
    import xarray as xr

    if group is not None and group not in root.groups:
        raise KeyError(f"{path}: no group {group}")
    nc = root if group is None else root.groups[group]
    attrs = _attributes(nc)
    if keep is not None and not keep(attrs):
        return None
    wanted = list(nc.variables) if variables is None else list(variables)
    missing = [name for name in wanted if name not in nc.variables]
    if missing:
        raise KeyError(f"{path}: no variable {', '.join(missing)}")
    dims = {dim for name in wanted for dim in nc.variables[name].dimensions}
    names = [n for n, v in nc.variables.items() if n in wanted or (n in dims and v.dimensions == (n,))]
    decoded = {name: _decoded_variable(nc.variables[name]) for name in names}
    complete = {name: var for name, var in decoded.items() if var is not None}
    if len(complete) < len(decoded) or "coordinates" in attrs:
        # from this handle: netCDF-C can crash on a file opened twice at once
        ds = xr.open_dataset(xr.backends.NetCDF4DataStore(root, group=group))
        return (ds if variables is None else ds[wanted]).load()
    # xarray's order: the data variables, then the coordinates
    coords = {name: var for name, var in complete.items() if var.dims == (name,)}
    return xr.Dataset({n: v for n, v in complete.items() if n not in coords}, coords, attrs)


def _decoded_variable(var: Any) -> xr.Variable | None:
    """A netCDF4 variable as an ``xarray.Variable`` decoded as xarray would
    (:func:`read_dataset`); None for one that xarray decodes otherwise."""
    import xarray as xr

    attrs = _attributes(var)
    if not isinstance(var.dtype, np.dtype):  # variable-length strings
        return None
    fill = attrs.pop("_FillValue", None)
    is_bool = attrs.get("dtype") == "bool"
    if is_bool:
        del attrs["dtype"]
    encoding = attrs.pop("_Encoding", None)
    units = attrs.get("units")
    if (
        (fill is not None and not (var.dtype.kind == "f" and np.isnan(fill)))
        or encoding not in (None, "utf-8")
        or XARRAY_CODED & attrs.keys()
        or (isinstance(units, str) and ("since" in units or units in TIME_UNITS))
    ):
        return None
    var.set_auto_maskandscale(False)
    var.set_auto_chartostring(False)
    data = var[...].astype(bool) if is_bool else var[...]
    dims = var.dimensions
    if data.dtype == "S1" and dims:
        # xarray's char_to_bytes: each row of characters one string
        n = data.shape[-1]
        data = data.view(f"S{n}").reshape(data.shape[:-1]) if n else np.zeros(data.shape[:-1], np.bytes_)
        dims = dims[:-1]
    if encoding is not None:
        if data.dtype.kind != "S":
            return None
        data = np.array([b.decode() for b in data.ravel()], dtype=object).reshape(data.shape)
    return xr.Variable(dims, data, attrs)


def load_schema(path: str | Path) -> dict[str, Any]:
    """The JSON schema at ``path`` (YAML, ``workflow/schemas``)."""
    with open(path) as fh:
        return yaml.safe_load(fh)


def validate_table(df: pd.DataFrame, schema: str | Path | Mapping[str, Any]) -> None:
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


def write_table(
    df: pd.DataFrame,
    path: str | Path,
    schema: str | Path | Mapping[str, Any] | None = None,
    float_format: str = "%.6g",
) -> None:
    """Validate (when a schema is given) and write a CSV table."""
    if schema is not None:
        validate_table(df, schema)
    write_text(path, df.to_csv(index=False, float_format=float_format))


def is_valid(attrs: Mapping[str, Any]) -> bool:
    """Whether a reduced test's attributes (its own verdict, of which ``qc.csv`` is made) say it is valid."""
    return bool(int(attrs.get("valid", 0)))


def valid_test_ids(qc_path: str | Path) -> list[str]:
    """Test ids that ``qc.csv`` marks valid, in its order."""
    qc = pd.read_csv(qc_path, keep_default_na=False)
    return qc.test_id[qc.valid.astype(str) == "True"].tolist()


@overload
def load_datasets(
    paths: Iterable[str | Path],
    keep: Keep | None = None,
    variables: Iterable[str] | None = None,
    group: str | None = None,
    also: None = None,
) -> Iterator[xr.Dataset]: ...
@overload
def load_datasets(
    paths: Iterable[str | Path],
    keep: Keep | None = None,
    variables: Iterable[str] | None = None,
    group: str | None = None,
    *,
    also: str,
) -> Iterator[tuple[xr.Dataset, xr.Dataset]]: ...
def load_datasets(
    paths: Iterable[str | Path],
    keep: Keep | None = None,
    variables: Iterable[str] | None = None,
    group: str | None = None,
    also: str | None = None,
) -> Iterator[xr.Dataset | tuple[xr.Dataset, xr.Dataset]]:
    """Yield the netCDF files at ``paths`` (their ``group`` if given) loaded
    into memory (files closed, :func:`read_dataset`), those for whose
    attributes ``keep(attrs)`` is true if given; with ``also``, each as the
    pair (dataset, its group ``also``), both from one open of the file."""
    for path in paths:
        ds = _read(path, variables, keep, group, also)
        if ds is not None:
            yield ds


@overload
def valid_tests(
    paths: Iterable[str | Path],
    qc_path: str | Path | None = None,
    variables: Iterable[str] | None = None,
    group: str | None = None,
    also: None = None,
) -> Iterator[xr.Dataset]: ...
@overload
def valid_tests(
    paths: Iterable[str | Path],
    qc_path: str | Path | None = None,
    variables: Iterable[str] | None = None,
    group: str | None = None,
    *,
    also: str,
) -> Iterator[tuple[xr.Dataset, xr.Dataset]]: ...
def valid_tests(
    paths: Iterable[str | Path],
    qc_path: str | Path | None = None,
    variables: Iterable[str] | None = None,
    group: str | None = None,
    also: str | None = None,
) -> Iterator[xr.Dataset | tuple[xr.Dataset, xr.Dataset]]:
    """Yield the reduced datasets of the valid tests, loaded.

    Valid: marked so in ``qc.csv``, or without it by the test's own verdict
    (its ``valid`` attribute, of which qc.csv is made), so that a job over
    a few tests need not depend on the QC of the whole campaign.
    ``variables``: those to load (:func:`read_dataset`), all if None;
    ``group``: the group of each file to read (its attributes carry ``valid``);
    ``also``: a group read with it, each test then a pair (:func:`load_datasets`).
    """
    if qc_path is None:
        return load_datasets(paths, is_valid, variables, group, also=also)
    valid = set(valid_test_ids(qc_path))
    return load_datasets((p for p in paths if Path(p).stem in valid), variables=variables, group=group, also=also)
