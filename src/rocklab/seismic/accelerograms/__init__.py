"""Recorded accelerograms (Table 4 of the paper) as obspy Streams in m/s^2.

Readers (obspy waveform plugins, registered in ``pyproject.toml`` so that
``obspy.read(path)`` detects them; one module per format family):

========================  ===================  ==================  ===============
format name               module               units in the file   header in stats
========================  ===================  ==================  ===============
``PEER_NGA_AT2``          :mod:`.peer`         g                   ``at2``
``PEER_LEGACY_AT2``       :mod:`.peer`         g                   ``at2``
``CALTECH_VOL2``          :mod:`.caltech`      cm/s^2              ``caltech``
``SOMERVILLE``            :mod:`.somerville`   cm/s^2 (``units=``) ``somerville``
``TWO_COLUMN``            :mod:`.columns`      g (``units=``)      ``text_columns``
``MULTI_COLUMN``          :mod:`.columns`      g (``units=``)      ``text_columns``
``CSV_TWO_COLUMN``        :mod:`.columns`      g (``units=``)      ``text_columns``
``SLAMMER``               :mod:`.slammer`      g (``units=``)      ``slammer``
``KNET``, ``KINEMETRICS_EVT``  obspy itself    counts x ``calib``  obspy's
========================  ===================  ==================  ===============

Every rocklab reader returns float64 data in m/s^2 and sets
``stats.units = "m/s2"``; the units of the file are in the format dictionary
(``units_in_file``).  :func:`read_accelerogram` also converts obspy's own
K-NET and Kinemetrics EVT traces (counts) with ``stats.calib``.  A SLAMMER
record takes its dt from the ``EQdata.txt`` table beside it (or ``dt=``).

Processing (:mod:`.processing`): baseline correction, PGA, PGV, record length
and significant duration.  Shipped records (:mod:`.manifest`):
:func:`read_manifest`, :func:`load_record`, :func:`read_table4`,
:func:`table4_agreement`.
"""

from ._text import to_si
from .manifest import (
    accelerogram_dir,
    build_manifest,
    load_record,
    read_manifest,
    read_table4,
    table4_agreement,
    write_manifest,
)
from .native import read_accelerogram, to_si_stream
from .processing import (
    arias_intensity,
    baseline_correct,
    baseline_correct_array,
    ground_motion_parameters,
    peak_ground_acceleration,
    peak_ground_velocity,
    record_duration,
    significant_duration,
    velocity,
)

__all__ = [
    "accelerogram_dir",
    "arias_intensity",
    "baseline_correct",
    "baseline_correct_array",
    "build_manifest",
    "ground_motion_parameters",
    "load_record",
    "peak_ground_acceleration",
    "peak_ground_velocity",
    "read_accelerogram",
    "read_manifest",
    "read_table4",
    "record_duration",
    "significant_duration",
    "table4_agreement",
    "to_si",
    "to_si_stream",
    "velocity",
    "write_manifest",
]
