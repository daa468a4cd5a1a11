"""PEER AT2 accelerograms (NGA-West2 and the legacy PEER-2000 database) as obspy plugins.

Both flavours have a four-line header and then the acceleration in g, five
values per line (Fortran ``5E15.7``)::

    PEER NGA STRONG MOTION DATABASE RECORD                    (NGA-West2)
    Imperial Valley-02, 5/19/1940, El Centro Array #9, 180    event, date, station, component
    ACCELERATION TIME SERIES IN UNITS OF G
    NPTS=   5372, DT=   .0100 SEC, [filter poles]

    PEER STRONG MOTION DATABASE RECORD. PROCESSING BY PACIFIC ENGINEERING.   (legacy)
    IMPERIAL VALLEY 5/19/40 0439, EL CENTRO ARRAY #9, 180 (USGS STATION 117)
    ACCELERATION TIME HISTORY IN UNITS OF G. FILTER POINTS: HP=0.2 Hz LP=15.0 Hz
    NPTS=  4000, DT= .01000 SEC

Format names ``PEER_NGA_AT2`` and ``PEER_LEGACY_AT2``; both keep their header
in ``stats.at2`` (``flavour``, ``event``, ``date``, ``station_name``,
``component``, ``npts``, ``dt``, the header lines and ``units_in_file='g'``).
``stats.station`` is the station name and ``stats.channel`` the component
label exactly as the header writes them (no codes are invented); the files
carry no trigger time, so ``starttime`` stays at the obspy default.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Any, cast

from obspy import Stream

from rocklab.disk import StrPath
from rocklab.physics.flight import FloatArray

from ._text import head_lines, make_trace, parse_values, read_lines, single

NGA_MAGIC = "PEER NGA STRONG MOTION DATABASE RECORD"
LEGACY_MAGIC = "PEER STRONG MOTION DATABASE RECORD"
LEGACY_MARK = "PACIFIC ENGINEERING"

_NPTS_DT = re.compile(r"^\s*NPTS\s*=\s*(\d+)\s*,\s*DT\s*=\s*([-+]?\d*\.?\d+(?:[eE][-+]?\d+)?)\s*SEC", re.I)
_ACC_IN_G = re.compile(r"^\s*ACCELERATION TIME (SERIES|HISTORY) IN UNITS OF G\b", re.I)


def _flavour(lines: Sequence[str] | None) -> str | None:
    """'nga', 'legacy' or None from the first four header lines."""
    if lines is None or len(lines) < 5:
        return None
    if not (_ACC_IN_G.match(lines[2]) and _NPTS_DT.match(lines[3])):
        return None
    first = lines[0].strip().upper()
    if first.startswith(NGA_MAGIC):
        return "nga"
    if first.startswith(LEGACY_MAGIC) and LEGACY_MARK in first:
        return "legacy"
    return None


def _is_peer_nga_at2(filename: StrPath) -> bool:
    """True for a PEER NGA-West2 AT2 acceleration file (header checked only)."""
    return _flavour(head_lines(filename, 1024)) == "nga"


def _is_peer_legacy_at2(filename: StrPath) -> bool:
    """True for a legacy PEER-2000 AT2 ("PROCESSING BY PACIFIC ENGINEERING") file."""
    return _flavour(head_lines(filename, 1024)) == "legacy"


def _parse_title(line: str, flavour: str) -> dict[str, str]:
    """Event, date, station name and component from header line 2."""
    parts = [p.strip() for p in line.split(",")]
    if flavour == "nga" and len(parts) >= 4:
        return {"event": parts[0], "date": parts[1], "station_name": ", ".join(parts[2:-1]), "component": parts[-1]}
    if flavour == "legacy" and len(parts) >= 3:
        m = re.match(r"^(.*?)\s+(\d{1,2}/\d{1,2}/\d{2,4})\s*(\d{3,4})?\s*$", parts[0])
        event, date = (m.group(1), (m.group(2) + " " + (m.group(3) or "")).strip()) if m else (parts[0], "")
        last = parts[-1]
        component, _, station_id = last.partition("(")
        return {
            "event": event,
            "date": date,
            "station_name": ", ".join(parts[1:-1]),
            "component": component.strip(),
            "station_id": station_id.rstrip(")").strip(),
        }
    return {"event": line.strip(), "date": "", "station_name": "", "component": ""}


def _read_at2(filename: StrPath, flavour: str, headonly: bool) -> Stream:
    lines = read_lines(filename)
    if _flavour(lines[:5]) != flavour:
        raise ValueError(f"{filename} is not a PEER {flavour} AT2 file")
    # a match: _flavour has checked this line
    m = cast(re.Match[str], _NPTS_DT.match(lines[3]))
    npts, dt = int(m.group(1)), float(m.group(2))
    info: dict[str, Any] = {
        "flavour": "NGA-West2" if flavour == "nga" else "legacy PEER-2000",
        **_parse_title(lines[1], flavour),
        "npts": npts,
        "dt": dt,
        "header": lines[:4],
    }
    values: FloatArray | list[float] = [] if headonly else parse_values(lines[4:])
    if not headonly and len(values) != npts:
        raise ValueError(f"{filename}: header says NPTS={npts}, found {len(values)} values")
    tr = make_trace(
        values,
        "g",
        dt,
        "at2",
        info,
        headonly=headonly,
        npts=npts,
        station=info["station_name"],
        channel=info["component"],
    )
    return single(tr)


def _read_peer_nga_at2(filename: StrPath, headonly: bool = False, **kwargs: Any) -> Stream:
    """Read a PEER NGA-West2 AT2 file: one trace, m/s^2 (from g)."""
    return _read_at2(filename, "nga", headonly)


def _read_peer_legacy_at2(filename: StrPath, headonly: bool = False, **kwargs: Any) -> Stream:
    """Read a legacy PEER-2000 AT2 file: one trace, m/s^2 (from g)."""
    return _read_at2(filename, "legacy", headonly)
