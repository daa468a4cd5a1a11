"""Helpers shared by the text accelerogram readers (units, head peeking, traces).

Every reader returns float64 acceleration in m/s^2 and marks it with
``stats.units = "m/s2"``; the units found in (or assumed for) the file are kept
in the format dictionary as ``units_in_file``.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt
from obspy import Stream, Trace, UTCDateTime

from rocklab.disk import StrPath
from rocklab.physics.constants import G
from rocklab.physics.flight import FloatArray

#: Factor from each accepted acceleration unit to m/s^2.
UNIT_FACTORS = {"g": G, "m/s2": 1.0, "cm/s2": 0.01, "gal": 0.01, "mm/s2": 1e-3}

#: Units marker set on every trace the readers return.
SI_UNITS = "m/s2"

_FLOAT = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
FLOAT_RE = re.compile(rf"^{_FLOAT}$")


def to_si(values: npt.ArrayLike, units: str) -> FloatArray:
    """Acceleration in m/s^2 (float64) from ``values`` in ``units``.

    ``units`` is one of :data:`UNIT_FACTORS` (case-insensitive, ``m/s^2`` and
    ``m/s**2`` spellings accepted).
    """
    key = canonical_units(units)
    return np.asarray(values, dtype=np.float64) * UNIT_FACTORS[key]


def canonical_units(units: object) -> str:
    """Normalised spelling of an acceleration unit (key of :data:`UNIT_FACTORS`)."""
    key = str(units).lower().replace("^", "").replace("**", "")
    if key not in UNIT_FACTORS:
        raise ValueError(f"unknown acceleration units {units!r}; expected one of {sorted(UNIT_FACTORS)}")
    return key


def head_lines(filename: StrPath, nbytes: int = 8192) -> list[str] | None:
    """First complete lines of a text file, or ``None`` if it is not ASCII text.

    Cheap by construction: reads at most ``nbytes``.  A partial last line is
    dropped unless the whole file fits in the buffer.
    """
    try:
        with open(filename, "rb") as fh:
            raw = fh.read(nbytes + 1)
    except (OSError, TypeError):
        return None
    if b"\x00" in raw:
        return None
    try:
        text = raw[:nbytes].decode("ascii")
    except UnicodeDecodeError:
        return None
    lines = text.splitlines()
    if len(raw) > nbytes and lines and not text.endswith(("\n", "\r")):
        lines = lines[:-1]
    return lines


def is_float(token: str) -> bool:
    """True if ``token`` is a plain decimal/exponent number."""
    return bool(FLOAT_RE.match(token))


def all_floats(line: str, count: int | None = None) -> bool:
    """True if ``line`` holds only numbers (exactly ``count`` of them if given)."""
    tokens = line.split()
    if not tokens or (count is not None and len(tokens) != count):
        return False
    return all(is_float(t) for t in tokens)


def parse_values(lines: Iterable[str]) -> FloatArray:
    """All whitespace-separated numbers in ``lines`` as one float64 array."""
    return np.array(" ".join(lines).split(), dtype=np.float64)


def read_lines(filename: StrPath) -> list[str]:
    """All lines of an ASCII text file (the file is opened read-only)."""
    with open(filename, encoding="ascii", errors="strict") as fh:
        return fh.read().splitlines()


def make_trace(
    values: FloatArray | Sequence[float],
    units: str,
    delta: float,
    fmt_key: str,
    fmt_header: Mapping[str, Any],
    *,
    headonly: bool = False,
    npts: int | None = None,
    network: str = "",
    station: str = "",
    location: str = "",
    channel: str = "",
    starttime: float | str | UTCDateTime | None = None,
) -> Trace:
    """Trace in m/s^2 from ``values`` in ``units``, with the format header kept.

    ``fmt_header`` goes to ``stats[fmt_key]`` with ``units_in_file`` added;
    ``stats.units`` is set to ``"m/s2"``.
    """
    header: dict[str, Any] = {
        "delta": float(delta),
        "network": network,
        "station": station,
        "location": location,
        "channel": channel,
        "units": SI_UNITS,
        fmt_key: dict(fmt_header, units_in_file=canonical_units(units)),
    }
    if starttime is not None:
        header["starttime"] = UTCDateTime(starttime)
    if headonly:
        header["npts"] = int(npts if npts is not None else len(values))
        return Trace(data=np.array([], dtype=np.float64), header=header)
    return Trace(data=to_si(values, units), header=header)


def single(trace: Trace) -> Stream:
    """A one-trace :class:`obspy.Stream`."""
    return Stream(traces=[trace])
