"""Caltech/USGS Volume II corrected accelerograms with a ``%`` comment header (obspy plugin).

These are the classic EERL "Vol. II" files (e.g. Pacoima Dam S16E 1971,
El Centro Array #7 S50W 1979) with every header line turned into a MATLAB
comment.  The text header (first 25 lines) is followed by the integer and real
header blocks and by the line::

    %  1845 POINTS OF ACC DATA EQUALLY SPACED AT   .020 SEC.

after which come the corrected accelerations, eight per line (``8F10.3``), in
cm/s^2 (the header's peak is quoted in ``CMS/SEC/SEC`` and equals the data
maximum).  The last line may be padded with zeros beyond the declared number
of points; the padding is dropped.

Format name ``CALTECH_VOL2``; the header is in ``stats.caltech``: record id,
event, date, station id and name, component, declared npts/dt, the uncorrected
record's npts and duration, band-pass corners (Hz), the header peaks
(``pga_cm_s2``, ``pgv_cm_s``, ``pgd_cm`` and their times) and all ``%`` lines.
``stats.station`` is the station name, ``stats.channel`` the component.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Any

import numpy as np
from obspy import Stream

from rocklab.disk import StrPath
from rocklab.physics.flight import FloatArray

from ._text import head_lines, make_trace, parse_values, read_lines, single

MAGIC = "%CORRECTED ACCELEROGRAM"

_N = r"([-+]?\d*\.?\d+(?:[eE][-+]?\d+)?)"
_POINTS = re.compile(rf"^%\s*(\d+)\s+POINTS OF ACC DATA EQUALLY SPACED AT\s+{_N}\s*SEC", re.I)
_PEAK = re.compile(rf"^%\s*PEAK\s+(ACCELERATION|VELOCITY|DISPLACEMENT)\s*=\s*{_N}\s+(\S+)\s+AT\s+{_N}", re.I)
_UNCORR = re.compile(rf"^%\s*NO\. OF POINTS\s*=\s*(\d+)\s+DURATION\s*=\s*{_N}\s*SEC", re.I)
_FILTER = re.compile(rf"BAND-PASS FILTERED BETWEEN\s+{_N}\s*-\s*{_N}\s+AND\s+{_N}\s*-\s*{_N}\s*HZ", re.I)
_COMP = re.compile(r"^%COMP\s+(\S+)")
_STATION = re.compile(r"^%STATION\s+(.*?)\s{2,}")


def _is_caltech_vol2(filename: StrPath) -> bool:
    """True for a ``%``-commented Caltech Vol. II corrected accelerogram."""
    lines = head_lines(filename, 8192)
    if not lines or not lines[0].upper().startswith(MAGIC):
        return False
    return any(_POINTS.match(line) for line in lines if line.startswith("%"))


def _parse_header(comments: Sequence[str]) -> dict[str, Any]:
    info: dict[str, Any] = {
        "record_id": comments[0][len(MAGIC) :].split()[0] if len(comments[0]) > len(MAGIC) else "",
        "event": comments[2][1:].strip() if len(comments) > 2 else "",
        "date": comments[3][1:].strip() if len(comments) > 3 else "",
        "station_id": "",
        "station_name": "",
        "component": "",
    }
    peak_keys = {
        "ACCELERATION": ("pga_cm_s2", "t_pga_s"),
        "VELOCITY": ("pgv_cm_s", "t_pgv_s"),
        "DISPLACEMENT": ("pgd_cm", "t_pgd_s"),
    }
    for i, line in enumerate(comments):
        if m := _POINTS.match(line):
            info["npts"], info["dt"] = int(m.group(1)), float(m.group(2))
        elif m := _PEAK.match(line):
            value_key, time_key = peak_keys[m.group(1).upper()]
            info[value_key], info[time_key] = float(m.group(2)), float(m.group(4))
            info[value_key.rsplit("_", 1)[0] + "_units"] = m.group(3)
        elif m := _UNCORR.match(line):
            info["uncorrected_npts"], info["uncorrected_duration_s"] = int(m.group(1)), float(m.group(2))
        elif m := _FILTER.search(line):
            info["bandpass_hz"] = tuple(float(m.group(k)) for k in range(1, 5))
        elif not info["component"] and (m := _COMP.match(line)):
            info["component"] = m.group(1)
        elif not info["station_id"] and (m := _STATION.match(line)):
            info["station_id"] = m.group(1)
            if i + 1 < len(comments):
                info["station_name"] = re.split(r"\s{2,}", comments[i + 1][1:].strip())[0]
    return info


def _read_caltech_vol2(filename: StrPath, headonly: bool = False, **kwargs: Any) -> Stream:
    """Read a Caltech Vol. II ``%``-header file: one trace, m/s^2 (from cm/s^2)."""
    lines = read_lines(filename)
    if not lines or not lines[0].upper().startswith(MAGIC):
        raise ValueError(f"{filename} is not a Caltech Vol. II accelerogram")
    comments = [line for line in lines if line.startswith("%")]
    info = _parse_header(comments)
    if "npts" not in info:
        raise ValueError(f"{filename}: no 'POINTS OF ACC DATA' line in the header")
    if info.get("acceleration_units", "CMS/SEC/SEC").upper() not in ("CMS/SEC/SEC", "CM/SEC/SEC"):
        raise ValueError(f"{filename}: unexpected acceleration units {info['acceleration_units']}")
    info["header"] = comments
    npts = info["npts"]
    values: FloatArray | list[float] = []
    if not headonly:
        values = parse_values([line for line in lines if line.strip() and not line.startswith("%")])
        if len(values) < npts:
            raise ValueError(f"{filename}: header says {npts} points, found {len(values)}")
        pad = values[npts:]
        if np.any(pad != 0.0):
            raise ValueError(f"{filename}: {len(pad)} values beyond the declared {npts} are not zero padding")
        info["padding_dropped"] = len(pad)
        values = values[:npts]
    tr = make_trace(
        values,
        "cm/s2",
        info["dt"],
        "caltech",
        info,
        headonly=headonly,
        npts=npts,
        station=info["station_name"],
        channel=info["component"],
    )
    return single(tr)
