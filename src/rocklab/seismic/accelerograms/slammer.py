"""SLAMMER record library: one acceleration value per line in g, dt in ``EQdata.txt`` (obspy plugin).

SLAMMER (USGS rigid-block/Newmark displacement program, Jibson, Rathje,
Jibson & Lee 2013) ships its strong-motion records as
``records/<event>/<record id>`` files holding nothing but the acceleration
in g, one value per line, no header (e.g. ``records/Kern County 1952/TAF-111``)::

    -0.00104012
    -9.82012E-4

The sampling interval is not in the file but in the record table
``records/EQdata.txt``: tab-separated, no header, one row per record with the
columns event, moment magnitude, focal mechanism, record id (the file name),
station, owner, latitude, longitude, site class, Vs30 [m/s], dt [s] and
three distances (kept unnamed as ``extra``).  A record id can appear under
two events (``BCR-230``: Imperial Valley 1979 at 0.005 s and Superstition
Hills 1987 at 0.010 s); the event is then the name of the file's folder, as in
SLAMMER's own layout.

The reader looks for ``EQdata.txt`` beside the file, then in the parent
folder (SLAMMER's layout), and takes dt from the row of the file's record id;
``dt=`` (seconds) given by the caller is used instead, and is required where
no table lists the file.  ``units=`` overrides the library's g.

Format name ``SLAMMER``; header in ``stats.slammer``: ``record``, ``dt``,
``dt_source`` (the table's path or ``"dt argument"``) and, from the table,
``event``, ``magnitude``, ``mechanism``, ``station_name``, ``owner``,
``latitude``, ``longitude``, ``site_class``, ``vs30_m_s``, ``extra``.
``stats.station`` is the station name and ``stats.channel`` the component
(the record id's suffix after its last ``-``, e.g. ``111``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from obspy import Stream

from rocklab.disk import StrPath
from rocklab.physics.flight import FloatArray

from ._text import head_lines, is_float, make_trace, parse_values, read_lines, single

#: Units of the SLAMMER library (the caller's ``units=`` overrides them).
DEFAULT_UNITS = "g"

#: Name of SLAMMER's record table.
TABLE = "EQdata.txt"

#: Named columns of ``EQdata.txt`` (the remaining ones are kept as ``extra``).
TABLE_COLUMNS = (
    "event",
    "magnitude",
    "mechanism",
    "record",
    "station_name",
    "owner",
    "latitude",
    "longitude",
    "site_class",
    "vs30_m_s",
    "dt",
)

_PROBE_LINES = 50


def _is_slammer(filename: StrPath) -> bool:
    """True for header-less text holding one number per line (at least three lines)."""
    lines = head_lines(filename, 2048)
    if not lines:
        return False
    lines = [line for line in lines[:_PROBE_LINES] if line.strip()]
    return len(lines) >= 3 and all(len(line.split()) == 1 and is_float(line.strip()) for line in lines)


def _table_rows(table: StrPath) -> list[dict[str, Any]]:
    """Rows of an ``EQdata.txt`` as dictionaries (:data:`TABLE_COLUMNS` plus ``extra``)."""
    rows = []
    # the full table has a few Latin-1 bytes (non-breaking spaces in station names)
    with open(table, encoding="latin-1") as fh:
        lines = fh.read().splitlines()
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        fields = line.split("\t")
        if len(fields) < len(TABLE_COLUMNS) or not is_float(fields[10].strip()):
            raise ValueError(f"{table}, line {number}: not a SLAMMER record row (event, ..., dt in column 11)")
        row: dict[str, Any] = dict(zip(TABLE_COLUMNS, (f.strip() for f in fields)))
        row["extra"] = [f.strip() for f in fields[len(TABLE_COLUMNS) :]]
        rows.append(row)
    return rows


def record_metadata(filename: StrPath) -> dict[str, Any] | None:
    """The ``EQdata.txt`` row of a SLAMMER record file, or ``None`` if no table lists it.

    Parameters
    ----------
    filename : str or Path
        A SLAMMER record (its name is the record id).

    Returns
    -------
    dict or None
        The row (:data:`TABLE_COLUMNS`, ``extra``, dt as float [s]) and
        ``table``, the path of the table it comes from.

    Raises
    ------
    ValueError
        The table lists the record id under several events with different
        dt and the file's folder names none of them.
    """
    path = Path(filename)
    for table in (path.parent / TABLE, path.parent.parent / TABLE):
        if not table.is_file():
            continue
        hits = [row for row in _table_rows(table) if row["record"] == path.name]
        if len(hits) > 1:
            hits = [row for row in hits if row["event"] == path.parent.name] or hits
        if not hits:
            continue
        if len({float(row["dt"]) for row in hits}) > 1:
            events = "; ".join(f"{row['event']} (dt {row['dt']} s)" for row in hits)
            raise ValueError(
                f"{filename}: {table} lists record {path.name} under several events, {events}; "
                "put the file in a folder named after its event or pass dt="
            )
        return {**hits[0], "dt": float(hits[0]["dt"]), "table": str(table)}
    return None


def _read_slammer(
    filename: StrPath, headonly: bool = False, dt: float | None = None, units: str = DEFAULT_UNITS, **kwargs: Any
) -> Stream:
    """Read a SLAMMER record: one trace in m/s^2 (from g), dt from ``EQdata.txt`` or ``dt=``."""
    meta = record_metadata(filename)
    if dt is not None:
        if float(dt) <= 0:
            raise ValueError(f"{filename}: dt must be positive, not {dt!r}")
        info = {**(meta or {}), "dt": float(dt), "dt_source": "dt argument"}
    elif meta is not None:
        info = {**meta, "dt_source": meta["table"]}
    else:
        raise ValueError(
            f"{filename}: no {TABLE} beside the file or in its parent folder lists record {Path(filename).name}; "
            "pass dt= (seconds)"
        )
    info.pop("table", None)
    info["record"] = Path(filename).name
    lines = read_lines(filename)
    values: FloatArray | list[float] = parse_values(lines) if not headonly else []
    if not headonly and len(values) != sum(1 for line in lines if line.strip()):
        raise ValueError(f"{filename}: a line holds more than one value; SLAMMER records hold one per line")
    tr = make_trace(
        values,
        units,
        info["dt"],
        "slammer",
        info,
        headonly=headonly,
        npts=sum(1 for line in lines if line.strip()),
        station=info.get("station_name", ""),
        channel=info["record"].rsplit("-", 1)[-1],
    )
    return single(tr)
