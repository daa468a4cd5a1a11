"""Formats obspy reads itself (K-NET ASCII, Kinemetrics EVT), brought to m/s^2.

obspy returns these in counts with ``stats.calib`` converting to m/s^2
(K-NET: scale factor in gal/count times 0.01; EVT: full scale and sensor
sensitivity with g = 9.81 m/s^2, obspy's choice).  :func:`read_accelerogram`
multiplies by ``calib``, sets ``calib = 1`` and ``stats.units = "m/s2"`` so the
rest of rocklab sees one convention whatever the source.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
import obspy

from ._text import SI_UNITS

#: obspy formats whose data are counts to be scaled by ``stats.calib`` into m/s^2.
CALIBRATED_FORMATS = ("KNET", "KINEMETRICS_EVT")


def to_si_stream(stream: obspy.Stream) -> obspy.Stream:
    """Apply ``calib`` to traces of :data:`CALIBRATED_FORMATS` (in place); return the stream.

    Traces of other formats must already be in m/s^2 (rocklab's plugins are).
    """
    for tr in stream:
        fmt = tr.stats.get("_format")
        if fmt in CALIBRATED_FORMATS:
            tr.data = np.asarray(tr.data, dtype=np.float64) * tr.stats.calib
            tr.stats.calib = 1.0
            tr.stats.units = SI_UNITS
        elif tr.stats.get("units") != SI_UNITS:
            raise ValueError(f"trace {tr.id} of format {fmt} has no known acceleration units")
    return stream


def read_accelerogram(path: str | os.PathLike[str], format: str | None = None, **kwargs: Any) -> obspy.Stream:
    """Any supported accelerogram file as an obspy Stream in m/s^2 (float64).

    Parameters
    ----------
    path : str or Path
        File to read; the format is autodetected unless ``format`` is given.
    format : str, optional
        obspy format name (``"PEER_NGA_AT2"``, ``"KNET"``...).
    **kwargs
        Passed to the reader (e.g. ``units=``, ``components=`` for column text).
    """
    if format is None:
        stream = obspy.read(str(path), **kwargs)
    else:
        stream = obspy.read(str(path), format=format, **kwargs)
    return to_si_stream(stream)
