"""Header-less numeric column text: time plus one (two-column) or several acceleration columns (obspy plugins).

Examples: ``elcentro_NS_full.dat`` (t, a in g, whitespace-separated),
``sct190985.txt`` (t, N-S, E-W, V in g), ``RSN1086_NORTHR_SYL360.AT2``
(``t,a`` comma-separated in g: an NGA-West2 record converted to two columns,
despite its name).  The file says nothing about units or components, so the
caller must:

* ``units=`` -- acceleration units of every column, default ``"g"``
  (``"m/s2"``, ``"cm/s2"``/``"gal"``, ``"mm/s2"`` also accepted);
* ``components=`` -- channel names, one per acceleration column (default
  ``COL2``, ``COL3``... after the 1-based column of the file);
* ``station=`` -- optional station name.

``obspy.read(path, units="m/s2", components=["NS"])`` passes them through.
The time step is the mean spacing of the time column, which must be uniform
(within 1 % of dt); a non-zero first time becomes ``starttime`` (seconds after
the obspy epoch 1970-01-01), since the true trigger time is unknown.

Format names ``TWO_COLUMN`` (exactly t + 1 column, whitespace-separated),
``MULTI_COLUMN`` (t + 2 or more columns, one trace each) and
``CSV_TWO_COLUMN`` (exactly ``t,a``, comma-separated, e.g. the NGA-West2
conversions of the shuang2099/Ground-motion-truncation-method repository).
Header in ``stats.text_columns``: ``column`` (1-based column of the file),
``ncolumns``, ``delimiter``, ``t0``, ``dt``, ``units_in_file``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from obspy import Stream

from rocklab.disk import StrPath

from ._text import all_floats, head_lines, make_trace

#: Units assumed when the caller gives none.
DEFAULT_UNITS = "g"

_PROBE_LINES = 50


def _ncolumns(filename: StrPath, delimiter: str | None = None) -> int | None:
    """Number of columns if the head is uniform numeric columns with a time axis, else None.

    ``delimiter`` None: columns separated by whitespace; else by that character.
    """
    lines = head_lines(filename, 4096)
    if not lines:
        return None
    lines = [line for line in lines[:_PROBE_LINES] if line.strip()]
    if len(lines) < 3:
        return None
    if delimiter is not None:
        # the same check as for whitespace columns, on the fields between delimiters; a field
        # holding blanks inside (whitespace columns) is no number
        lines = [" ".join(field.strip().replace(" ", "-") or "-" for field in line.split(delimiter)) for line in lines]
    ncol = len(lines[0].split())
    if ncol < 2 or not all(all_floats(line, ncol) for line in lines):
        return None
    t = np.array([float(line.split()[0]) for line in lines])
    step = np.diff(t)
    if step[0] <= 0 or np.any(np.abs(step - step.mean()) > 0.01 * step.mean()):
        return None
    return ncol


def _is_two_column(filename: StrPath) -> bool:
    """True for header-less ``t a`` text with a uniform time column."""
    return _ncolumns(filename) == 2


def _is_multi_column(filename: StrPath) -> bool:
    """True for header-less ``t a1 a2 ...`` text (3+ columns) with a uniform time column."""
    ncol = _ncolumns(filename)
    return ncol is not None and ncol >= 3


def _is_csv_two_column(filename: StrPath) -> bool:
    """True for header-less ``t,a`` comma-separated text with a uniform time column."""
    return _ncolumns(filename, ",") == 2


def _read_columns(
    filename: StrPath,
    headonly: bool,
    units: str,
    components: str | Sequence[str] | None,
    station: str,
    delimiter: str | None = None,
) -> Stream:
    table = np.loadtxt(filename, dtype=np.float64, ndmin=2, delimiter=delimiter)
    t = table[:, 0]
    n, ncol = table.shape
    if n < 2:
        raise ValueError(f"{filename}: fewer than two samples")
    # the time column is printed with a few decimals: 9 significant digits are all dt can claim
    dt = float(f"{(t[-1] - t[0]) / (n - 1):.9g}")
    if dt <= 0 or np.max(np.abs(np.diff(t) - dt)) > 0.01 * dt:
        raise ValueError(f"{filename}: the time column is not uniformly sampled")
    if components is None:
        components = [f"COL{k}" for k in range(2, ncol + 1)]
    elif isinstance(components, str):
        components = [components]
    if len(components) != ncol - 1:
        raise ValueError(f"{filename}: {ncol - 1} acceleration columns but {len(components)} component names")
    traces = []
    for k, name in enumerate(components, start=2):
        info = {"column": k, "ncolumns": ncol, "delimiter": delimiter or "whitespace", "t0": float(t[0]), "dt": dt}
        traces.append(
            make_trace(
                table[:, k - 1],
                units,
                dt,
                "text_columns",
                info,
                headonly=headonly,
                npts=n,
                station=station,
                channel=str(name),
                starttime=float(t[0]),
            )
        )
    return Stream(traces=traces)


def _read_two_column(
    filename: StrPath,
    headonly: bool = False,
    units: str = DEFAULT_UNITS,
    components: str | Sequence[str] | None = None,
    station: str = "",
    **kwargs: Any,
) -> Stream:
    """Read ``t a`` text: one trace in m/s^2 (``units`` default g, see module doc)."""
    return _read_columns(filename, headonly, units, components, station)


def _read_multi_column(
    filename: StrPath,
    headonly: bool = False,
    units: str = DEFAULT_UNITS,
    components: str | Sequence[str] | None = None,
    station: str = "",
    **kwargs: Any,
) -> Stream:
    """Read ``t a1 a2 ...`` text: one trace per column in m/s^2 (see module doc)."""
    return _read_columns(filename, headonly, units, components, station)


def _read_csv_two_column(
    filename: StrPath,
    headonly: bool = False,
    units: str = DEFAULT_UNITS,
    components: str | Sequence[str] | None = None,
    station: str = "",
    **kwargs: Any,
) -> Stream:
    """Read ``t,a`` comma-separated text: one trace in m/s^2 (``units`` default g, see module doc)."""
    if _ncolumns(filename, ",") != 2:
        raise ValueError(f"{filename}: not two comma-separated columns t,a")
    return _read_columns(filename, headonly, units, components, station, delimiter=",")
