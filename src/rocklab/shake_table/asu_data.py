"""The ASU shake-table data: test table, specimen geometry and table motions.

Layout of ``shake_table_dir`` (its SOURCE.md describes every column):
``tests.csv`` (one row per test), ``geometry.json`` (both specimens) and
``motions/TestNNN.csv.gz`` (200 Hz: ``time_s``, ``table_acc_g``,
``table_disp_mm``).

Sign convention
---------------
The displacement channel is the one the source's simulator drives along the
mesh's +x axis, so +x here is the positive displacement.  The accelerometer
has the opposite sign (SOURCE.md, QC: the second derivative of the
displacement is -0.996 times the acceleration), so the reader multiplies the
acceleration by :data:`ACCELERATION_SIGN` and checks every record: where the
displacement's second derivative correlates well with the acceleration
(``|r| >= SIGN_CHECK_MIN_CORR``) their regression gain must have the sign the
convention implies, or the record is refused.
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import obspy
import pandas as pd
from numpy.typing import ArrayLike

from rocklab.physics.wall import G
from rocklab.seismic.accelerograms import baseline_correct_array, peak_ground_acceleration

#: Specimens of the campaign, as in the column names of tests.csv.
SPECIMENS = ("SP1", "SP2")

#: Accelerometer sign relative to the displacement channel (+x, SOURCE.md QC).
ACCELERATION_SIGN = -1.0

#: Length [s] of the record before shaking whose mean is the offset (SOURCE.md).
PRE_EVENT = 0.5

#: Band [Hz] of the sign check (the QC band of SOURCE.md).
SIGN_CHECK_BAND = (0.2, 5.0)

#: Correlation above which a disagreeing sign refuses the record.
SIGN_CHECK_MIN_CORR = 0.5

#: Band-pass [Hz] and Butterworth order of the acceleration the block feels and
#: PGA/PGV are read from: the filter of the source's data loader (SOURCE.md).
BAND = (0.1, 25.0)
BAND_ORDER = 3

#: Columns of tests.csv the library reads.
REQUIRED = ("test", "ground_motion", "overturned_sp1", "overturned_sp2", "motion_file")


#: A ground-motion name that starts with a PEER NGA record sequence number (RSN).
_RSN = re.compile(r"^RSN(\d+)(?:_|$)", re.IGNORECASE)


def record_of(ground_motion: object) -> str:
    """The earthquake record of a ground motion: ``RSN<n>`` where its name carries the RSN, else the name.

    Both horizontal components of a record (``RSN137_TABAS_BAJ-L1.AT2`` and
    ``..._BAJ-T1.AT2``) are one record: the unit of folds and resamples.
    """
    name = str(ground_motion)
    m = _RSN.match(name)
    return f"RSN{int(m.group(1))}" if m else name


def check_dir(folder: str | Path, key: str = "shake_table_dir") -> Path:
    """The data folder, or a clear error naming the config ``key`` that points to it."""
    path = Path(folder)
    missing = [n for n in ("tests.csv", "geometry.json", "motions") if not (path / n).exists()]
    if missing:
        raise FileNotFoundError(
            f"config key {key!r} = {str(folder)!r}: {path.resolve()} lacks {', '.join(missing)}; "
            "point it to the shake-table data folder (see its SOURCE.md)"
        )
    return path


def dem_columns(tests: pd.DataFrame, specimen: str) -> list[str]:
    """The DEM prediction columns of one specimen (one per contact-stiffness setting)."""
    return [c for c in tests.columns if c.startswith(f"dem_{specimen.lower()}_")]


def read_tests(folder: str | Path) -> pd.DataFrame:
    """tests.csv, checked: one row per test, 0/1 outcomes and DEM flags.

    Raises
    ------
    ValueError
        Naming the file, the row (test) and the problem.
    """
    path = check_dir(folder) / "tests.csv"
    df = pd.read_csv(path, keep_default_na=False, na_values=[""])
    missing = [c for c in REQUIRED if c not in df.columns]
    if missing:
        raise ValueError(f"{path}: missing column(s) {', '.join(missing)}")
    if df.test.duplicated().any():
        raise ValueError(f"{path}: test {int(df.test[df.test.duplicated()].iloc[0])} appears twice")
    flags = [f"overturned_{s.lower()}" for s in SPECIMENS] + [c for s in SPECIMENS for c in dem_columns(df, s)]
    for col in flags:
        bad = ~df[col].isin([0, 1])
        if bad.any():
            row = df[bad].iloc[0]
            raise ValueError(f"{path}: test {row.test}, {col} = {row[col]!r}, not 0 or 1")
    df["motion_file"] = df.motion_file.fillna("").astype(str)
    return df


def read_geometry(folder: str | Path) -> dict[str, Any]:
    """geometry.json: per specimen the mass, and ``rocking_2d`` of each footprint edge (b, h, R, I_O: the block's)."""
    path = check_dir(folder) / "geometry.json"
    geo = json.loads(path.read_text())
    for s in SPECIMENS:
        try:
            float(geo[s]["mass_kg"])
            for edge in ("plus_x_edge", "minus_x_edge"):
                for key in ("b_m", "h_m", "R_m", "I_o_kgm2"):
                    float(geo[s]["footprint"]["rocking_2d"][edge][key])
        except (KeyError, TypeError) as exc:
            raise ValueError(f"{path}: {s} lacks mass_kg or rocking_2d.<edge>.b_m/h_m/R_m/I_o_kgm2 ({exc})") from None
    return geo


def displacement_gain(
    acc_g: np.ndarray | Sequence[float], disp_mm: ArrayLike, dt: float, band: tuple[float, float] = SIGN_CHECK_BAND
) -> tuple[float, float]:
    """Regression gain and correlation of the displacement's second derivative on the acceleration.

    Both signals are band-passed (``band`` [Hz], 4th-order zero-phase
    Butterworth) so that the double differentiation does not amplify noise.

    Parameters
    ----------
    acc_g : array_like
        Acceleration [g] as recorded.
    disp_mm : array_like
        Displacement [mm] as recorded.
    dt : float
        Sample interval [s].

    Returns
    -------
    gain, corr : float
        d''/g = gain * acc (least squares) and their correlation; a gain
        near -1 means the channels have opposite signs.
    """
    # imported here and in table_velocity: the Snakefile imports this module
    # for SPECIMENS and check_dir, and scipy.signal would cost it 1 s
    from scipy import signal

    sos = signal.butter(4, band, btype="bandpass", fs=1.0 / dt, output="sos")
    a = signal.sosfiltfilt(sos, np.asarray(acc_g, float) - np.mean(acc_g))
    d = signal.sosfiltfilt(sos, np.asarray(disp_mm, float) * 1e-3)
    dd = np.gradient(np.gradient(d, dt), dt) / G
    gain = float(np.dot(a, dd) / np.dot(a, a)) if np.dot(a, a) > 0 else 0.0
    corr = float(np.corrcoef(a, dd)[0, 1]) if np.std(a) > 0 and np.std(dd) > 0 else 0.0
    return gain, corr


def check_sign(gain: float, corr: float, where: str = "record", sign: float = ACCELERATION_SIGN) -> None:
    """Raise ValueError when a well-correlated gain contradicts the sign convention."""
    if abs(corr) >= SIGN_CHECK_MIN_CORR and np.sign(gain) != np.sign(sign):
        raise ValueError(
            f"{where}: the displacement's second derivative is {gain:+.3f} x the acceleration "
            f"(correlation {corr:+.2f}); the sign convention expects a gain of sign {sign:+.0f}"
        )


def read_motion(folder: str | Path, row: Mapping[str, Any]) -> obspy.Stream:
    """The table motion of one test as an obspy Stream, +x along the displacement.

    Parameters
    ----------
    folder : path
        ``shake_table_dir``.
    row : mapping
        The test's row of :func:`read_tests` (``test``, ``ground_motion``,
        ``motion_file``).

    Returns
    -------
    obspy.Stream
        Trace ``ACC``: table acceleration [m/s^2], the mean of its first
        :data:`PRE_EVENT` s removed, times :data:`ACCELERATION_SIGN`; trace
        ``DSP``: table displacement [m], its first :data:`PRE_EVENT` s mean
        removed.  ``stats``: ``units``, ``record`` (ground motion), ``test``,
        ``offset_g`` and the sign check (``sign_gain``, ``sign_corr``).

    Raises
    ------
    FileNotFoundError, ValueError
        Naming the file and the problem (no file for the test, a time step
        other than uniform, a sign that contradicts the convention).
    """
    if not row["motion_file"]:
        raise FileNotFoundError(f"test {row['test']}: no motion file in tests.csv (raw file missing at the source)")
    path = check_dir(folder) / row["motion_file"]
    df = pd.read_csv(path)
    for col in ("time_s", "table_acc_g", "table_disp_mm"):
        if col not in df.columns:
            raise ValueError(f"{path}: missing column {col}")
    t = df.time_s.to_numpy(float)
    dt = float(np.median(np.diff(t)))
    if np.max(np.abs(np.diff(t) - dt)) > 1e-6:
        raise ValueError(f"{path}: time step not uniform (row {int(np.argmax(np.abs(np.diff(t) - dt))) + 2})")
    acc, disp = df.table_acc_g.to_numpy(float), df.table_disp_mm.to_numpy(float)
    n0 = max(1, int(round(PRE_EVENT / dt)))
    offset = float(np.mean(acc[:n0]))
    gain, corr = displacement_gain(acc, disp, dt)
    check_sign(gain, corr, str(path))
    common = {"network": "AS", "station": f"T{int(row['test']):03d}", "delta": dt, "starttime": obspy.UTCDateTime(0)}
    extra = {"record": str(row["ground_motion"]), "test": int(row["test"])}
    acc_tr = obspy.Trace(ACCELERATION_SIGN * (acc - offset) * G, header={**common, "channel": "ACC"})
    acc_tr.stats.update({**extra, "units": "m/s2", "offset_g": offset, "sign_gain": gain, "sign_corr": corr})
    dsp_tr = obspy.Trace((disp - np.mean(disp[:n0])) * 1e-3, header={**common, "channel": "DSP"})
    dsp_tr.stats.update({**extra, "units": "m"})
    return obspy.Stream([acc_tr, dsp_tr])


def block_input(trace: obspy.Trace) -> np.ndarray:
    """The acceleration the block feels [m/s^2]: the record band-passed as the source's loader does (:data:`BAND`)."""
    return baseline_correct_array(
        trace.data, trace.stats.delta, pre_event=PRE_EVENT, freqmin=BAND[0], freqmax=BAND[1], corners=BAND_ORDER
    )


def table_velocity(displacement: obspy.Trace) -> np.ndarray:
    """Table velocity [m/s] from the displacement trace [m], band-passed as :func:`block_input`.

    The table is displacement-controlled: its velocity is the derivative of
    the displacement, free of the drift that integrating the noisy
    accelerometer (offset, spikes) leaves.
    """
    from scipy import signal  # imported here: see displacement_gain

    dt = displacement.stats.delta
    sos = signal.butter(BAND_ORDER, BAND, btype="bandpass", fs=1.0 / dt, output="sos")
    return np.gradient(signal.sosfiltfilt(sos, displacement.data), dt)


def motion_measures(stream: obspy.Stream) -> dict[str, float]:
    """PGA [g] and peak acceleration towards +x and -x [g] of the block input, PGV [m/s], duration [s].

    Parameters
    ----------
    stream : obspy.Stream
        As :func:`read_motion` returns it (traces ``ACC`` and ``DSP``).
    """
    acc, dsp = stream.select(channel="ACC")[0], stream.select(channel="DSP")[0]
    a = block_input(acc)
    return {
        "pga_g": float(peak_ground_acceleration(a)) / G,
        "pgv_m_s": float(np.max(np.abs(table_velocity(dsp)))),
        "peak_plus_g": float(np.max(a)) / G,
        "peak_minus_g": float(-np.min(a)) / G,
        "duration_s": float((acc.stats.npts - 1) * acc.stats.delta),
    }
