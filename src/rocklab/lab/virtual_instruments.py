"""Virtual records of the other instruments: a rotation record and an inertial record of a wall motion.

From the same true motion as the transducers of :mod:`rocklab.lab.virtual_record`
(the hold, the release, the free rocking and the rest of
:func:`rocklab.lab.virtual_record.record_from_motion`), the readings of

* a motion-capture system (``# record: rotation``): theta as measured, with
  white noise and markers lost for a few to a few tens of frames
  (:class:`RotationEffects`, :func:`rotation_readings`);
* a gyroscope and an accelerometer glued on the wall (``# record:
  inertial``): the rate of theta and the specific force at the sensor, with
  the bias left after the zeroing, white noise and, where asked, a gain
  error of either sensor
  (:class:`InertialEffects`, :func:`inertial_readings`);

and :func:`write_instrument_record` writes either in the lab's format
(``docs/raw-format.md``).  Everything random comes from the generator given.
"""

from __future__ import annotations

import gzip
import io
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from rocklab.lab.records import INERTIAL_COLUMNS, INERTIAL_UNITS, ROTATION_UNITS
from rocklab.physics.constants import G

#: The instruments of a virtual test (``# record:`` of its file; transducers have none).
INSTRUMENTS = ("transducers", "rotation", "inertial")
#: Faults of a rotation or inertial record: the instrument dead (noise only) or clipped at
#: ``level`` of its largest |reading|.
INSTRUMENT_FAULTS = ("dead", "clipped", "unreadable")


@dataclass(frozen=True)
class RotationEffects:
    """What a motion-capture system does to theta.

    Attributes
    ----------
    noise_rad : float
        Standard deviation of the white noise of theta [rad] (markers 1.5 m
        up tracked to 0.03 mm: 2e-5 rad).
    occlusions : int
        Number of stretches of lost samples.
    max_occlusion_s : float
        Longest stretch lost [s] (each lasts from one frame to this).
    sliding : bool
        Whether the record has the phi, v, w columns too.
    """

    noise_rad: float = 2e-5
    occlusions: int = 4
    max_occlusion_s: float = 0.08
    sliding: bool = False


@dataclass(frozen=True)
class InertialEffects:
    """What a MEMS gyroscope and accelerometer do to the rate and the specific force.

    Attributes
    ----------
    gyro_density : float
        White-noise density of the rate [rad/s/sqrt(Hz)] (its standard
        deviation is this times sqrt(fs / 2)).
    gyro_bias_rad_s : (float, float)
        Range of the magnitude of the gyroscope's bias [rad/s] (random sign).
    acc_density : float
        White-noise density of the specific force [m/s^2/sqrt(Hz)].
    acc_bias_m_s2 : float
        Largest magnitude of the accelerometer's bias on each axis [m/s^2].
    sensor : (float, float, float)
        Where the sensor is glued, as fractions (x / (L/2), y / (b/2), z / h).
    gyro_gain, acc_gain : float
        Scale of the gyroscope's rate and of the accelerometer's specific force
        (reading = gain x true value + bias + noise) [-]: 1 for a calibrated sensor
        (:mod:`rocklab.lab.sensor_gain` finds them).
    """

    gyro_density: float = 7e-5
    gyro_bias_rad_s: tuple[float, float] = (1e-4, 5e-4)
    acc_density: float = 1e-3
    acc_bias_m_s2: float = 3e-3
    sensor: tuple[float, float, float] = (1.0, 0.0, 0.8)
    gyro_gain: float = 1.0
    acc_gain: float = 1.0


def occluded(n: int, fs: float, count: int, max_s: float, rng: np.random.Generator) -> np.ndarray:
    """Samples an optical instrument lost: ``count`` stretches of one sample to ``max_s`` [s], away from the ends.

    Parameters
    ----------
    n : int
        Samples of the record.
    fs : float
        Sampling rate [Hz].
    count : int
        Stretches lost.
    max_s : float
        Longest stretch [s].
    rng : numpy.random.Generator

    Returns
    -------
    ndarray (n,) of bool
    """
    lost = np.zeros(n, bool)
    longest = max(int(max_s * fs), 1)
    if count and n > longest + 10:
        for i0 in rng.integers(5, n - longest - 5, count):
            lost[i0 : i0 + rng.integers(1, longest + 1)] = True
    return lost


def rotation_readings(
    t: np.ndarray,
    theta: ArrayLike,
    phi: ArrayLike,
    v: ArrayLike,
    w: ArrayLike,
    effects: RotationEffects = RotationEffects(),
    rng: np.random.Generator | int | None = None,
) -> dict[str, np.ndarray]:
    """The columns of a rotation record of a motion (lost samples NaN).

    Returns
    -------
    dict
        ``theta_rad`` and, with ``effects.sliding``, ``phi_rad``, ``v_mm``, ``w_mm``.
    """
    rng = np.random.default_rng(rng)
    n = len(t)
    cols = {"theta_rad": np.asarray(theta, float) + rng.normal(0.0, effects.noise_rad, n)}
    if effects.sliding:
        cols["phi_rad"] = np.asarray(phi, float) + rng.normal(0.0, effects.noise_rad, n)
        cols["v_mm"] = np.asarray(v, float) + rng.normal(0.0, 0.03, n)
        cols["w_mm"] = np.asarray(w, float) + rng.normal(0.0, 0.03, n)
    lost = occluded(n, 1.0 / (t[1] - t[0]), effects.occlusions, effects.max_occlusion_s, rng)
    for x in cols.values():
        x[lost] = np.nan
    return cols


def sensor_point(specimen: Mapping[str, Any], effects: InertialEffects = InertialEffects()) -> np.ndarray:
    """Where the sensor is glued (body frame) [mm]."""
    fx, fy, fz = effects.sensor
    return np.array([fx * specimen["length_mm"] / 2, fy * specimen["thickness_mm"] / 2, fz * specimen["height_mm"]])


def inertial_readings(
    t: ArrayLike,
    theta: ArrayLike,
    sensor_mm: np.ndarray,
    thickness_mm: float,
    effects: InertialEffects = InertialEffects(),
    rng: np.random.Generator | int | None = None,
) -> tuple[dict[str, np.ndarray], float]:
    """The columns of an inertial record of a rocking motion theta(t), and the gyroscope's bias.

    The rate is the derivative of theta; the specific force at the sensor
    r = (y - e_y, z) from the active base edge e_y = +-b/2 is
    (-g sin theta, g cos theta) plus the acceleration of the point,
    theta'' (r_z, -r_y) - theta'^2 (r_y, r_z) in the body frame, whose
    theta'' makes the spike of each impact.

    Returns
    -------
    (dict, float)
        ``gyro_x_rad_s``, ``acc_y_m_s2``, ``acc_z_m_s2``; the bias [rad/s].
    """
    rng = np.random.default_rng(rng)
    t, theta = np.asarray(t, float), np.asarray(theta, float)
    fs = 1.0 / (t[1] - t[0])
    rate = np.gradient(theta, t)
    acc = np.gradient(rate, t)
    ry = (sensor_mm[1] - np.where(theta >= 0, 1.0, -1.0) * thickness_mm / 2) / 1e3
    rz = sensor_mm[2] / 1e3
    f_y = -G * np.sin(theta) + acc * rz - rate**2 * ry
    f_z = G * np.cos(theta) - acc * ry - rate**2 * rz
    bias = float(rng.choice([-1.0, 1.0]) * rng.uniform(*effects.gyro_bias_rad_s))
    sg, sa = effects.gyro_density * np.sqrt(fs / 2), effects.acc_density * np.sqrt(fs / 2)
    n = len(t)
    cols = {
        "gyro_x_rad_s": effects.gyro_gain * rate + bias + rng.normal(0.0, sg, n),
        # zeroed on the vertical wall at rest: the offsets of f_z's g too
        "acc_y_m_s2": effects.acc_gain * f_y + rng.uniform(-1, 1) * effects.acc_bias_m_s2 + rng.normal(0.0, sa, n),
        "acc_z_m_s2": effects.acc_gain * f_z + rng.uniform(-1, 1) * effects.acc_bias_m_s2 + rng.normal(0.0, sa, n),
    }
    return cols, bias


def instrument_fault(
    cols: dict[str, np.ndarray], kind: str, rng: np.random.Generator | int | None = None, level: float | None = None
) -> dict[str, np.ndarray]:
    """An instrument fault (:data:`INSTRUMENT_FAULTS`) on the first column of a record's readings (in place).

    ``dead``: the column reads noise around zero; ``clipped``: it saturates at
    ``level`` (default 0.5) of its largest |reading|.
    """
    rng = np.random.default_rng(rng)
    name = next(iter(cols))
    x = cols[name]
    if kind == "dead":
        x[:] = rng.normal(0.0, 1e-3 * np.nanstd(x), x.size)
    elif kind == "clipped":
        lim = (0.5 if level is None else level) * np.nanmax(np.abs(x))
        x[:] = np.clip(x, -lim, lim)
    elif kind != "unreadable":
        raise ValueError(f"unknown instrument fault {kind!r}")
    return cols


def write_instrument_record(
    path: str | Path,
    test_id: str,
    instrument: str,
    fs: float,
    t: np.ndarray,
    cols: Mapping[str, np.ndarray],
    sensor_mm: Iterable[float] | None = None,
    unreadable: bool = False,
    source: str = "rocklab virtual lab, motion capture",
) -> None:
    """Write a ``# record: rotation`` or ``# record: inertial`` file in the lab's format.

    Time with 5 decimals, rotations with 7, rates with 6, forces and lengths
    with 5; empty fields for NaN.  Gzip-compressed unless ``path`` ends in
    ``.csv`` (the plain text the format accepts too).  With ``unreadable``
    the gzip stream is cut in the middle (a broken transfer).  ``source``:
    the rotation record's ``# source:`` line.
    """
    units = {"rotation": ROTATION_UNITS, "inertial": INERTIAL_UNITS}[instrument]
    head = f"# test_id: {test_id}\n# record: {instrument}\n# sampling_rate_hz: {fs:g}\n# units: {', '.join(units)}\n"
    if instrument == "inertial":
        assert sensor_mm is not None  # an inertial record says where its sensor is
        head += "# sensor_mm: " + ", ".join(f"{x:g}" for x in sensor_mm) + "\n"
        names = list(INERTIAL_COLUMNS)
    else:
        head += f"# source: {source}\n"
        names = list(cols)
    decimals = {"theta_rad": 7, "phi_rad": 7, "gyro_x_rad_s": 6}
    head += "time_s," + ",".join(names) + "\n"
    buf = io.StringIO()
    fmt = ["%.5f"] + [f"%.{decimals.get(c, 5)}f" for c in names]
    np.savetxt(buf, np.column_stack([t, *(cols[c] for c in names)]), fmt=fmt, delimiter=",")
    body = buf.getvalue().replace("nan", "")
    text = (head + body).encode()
    data = text if Path(path).suffix == ".csv" else gzip.compress(text, compresslevel=6, mtime=0)
    if unreadable:
        data = data[: len(data) // 2]
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_bytes(data)
