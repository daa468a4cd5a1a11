"""SAC Steel Project near-fault time histories (Somerville et al. 1997) with a ``%`` header (obspy plugin).

Two ``%`` header lines, then the acceleration six values per line::

    %rrs        n   Northridge,17 Jan 94,04:31PST; Rinaldi Receiving Station FF
    %   2990    5.00000E-03  0  0  0.  0.  0.  0.  0.
     -0.11237E+03 -0.40766E+02  0.89456E+01 ...

Line 1: station code, component code (``n``, ``fn`` = fault normal, ``fp``...)
and a free description; line 2: number of points, time step [s] and further
numbers of unknown meaning (kept as ``extra``).  The last line may be padded
with zeros beyond the declared number of points (dropped).  The units are not
written in the file: these records are distributed in cm/s^2, the reader's
default (``units=`` keyword to override).  Note that most of them are *rotated*
(fault-normal/-parallel) components, not as-recorded ones.

Format name ``SOMERVILLE``; header in ``stats.somerville`` (``code``,
``component``, ``description``, ``npts``, ``dt``, ``extra``, header lines).
``stats.station`` is the code, ``stats.channel`` the component code.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from obspy import Stream

from rocklab.disk import StrPath
from rocklab.physics.flight import FloatArray

from ._text import all_floats, head_lines, is_float, make_trace, parse_values, read_lines, single

#: Units assumed when the caller gives none (the distributed files are cm/s^2).
DEFAULT_UNITS = "cm/s2"


def _npts_dt(line: str) -> tuple[int, float, list[float]] | None:
    """(npts, dt, extra) from header line 2, or None if it is not of that form."""
    if not line.startswith("%"):
        return None
    tokens = line[1:].split()
    if len(tokens) < 2 or not tokens[0].isdigit() or not all(is_float(t) for t in tokens):
        return None
    dt = float(tokens[1])
    if not 0.0 < dt < 1.0:
        return None
    return int(tokens[0]), dt, [float(t) for t in tokens[2:]]


def _is_somerville(filename: StrPath) -> bool:
    """True for a two-``%``-line near-fault record followed by 6-value data lines."""
    lines = head_lines(filename, 2048)
    if not lines or len(lines) < 4 or not lines[0].startswith("%"):
        return False
    if _npts_dt(lines[1]) is None:
        return False
    return all_floats(lines[2], 6) and all_floats(lines[3], 6)


def _read_somerville(filename: StrPath, headonly: bool = False, units: str = DEFAULT_UNITS, **kwargs: Any) -> Stream:
    """Read a SAC/Somerville near-fault file: one trace, m/s^2 (from ``units``, default cm/s^2)."""
    lines = read_lines(filename)
    parsed = _npts_dt(lines[1]) if len(lines) > 1 and lines[0].startswith("%") else None
    if parsed is None:
        raise ValueError(f"{filename} is not a SAC/Somerville near-fault file")
    npts, dt, extra = parsed
    title = lines[0][1:].split(maxsplit=2)
    info: dict[str, Any] = {
        "code": title[0] if title else "",
        "component": title[1] if len(title) > 1 else "",
        "description": title[2].strip() if len(title) > 2 else "",
        "npts": npts,
        "dt": dt,
        "extra": extra,
        "header": lines[:2],
    }
    values: FloatArray | list[float] = []
    if not headonly:
        values = parse_values(lines[2:])
        if len(values) < npts:
            raise ValueError(f"{filename}: header says {npts} points, found {len(values)}")
        if np.any(values[npts:] != 0.0):
            raise ValueError(f"{filename}: values beyond the declared {npts} are not zero padding")
        info["padding_dropped"] = len(values) - npts
        values = values[:npts]
    tr = make_trace(
        values,
        units,
        dt,
        "somerville",
        info,
        headonly=headonly,
        npts=npts,
        station=info["code"],
        channel=info["component"],
    )
    return single(tr)
