"""From a rotation record (motion capture, inclinometer, video) to the wall's motion.

A rotation record gives theta as measured (``docs/raw-format.md``, "record:
rotation"), in the system's own zero with the wall vertical at rest, and
sometimes phi, v and w.  Optical systems lose markers: an empty field is a
lost sample.  Here:

* theta is kept as measured; a lost stretch is bridged by a cubic spline
  through the measured samples when the motion allows it: no longer than
  :data:`MAX_BRIDGE_S`, in which a flight of the wall is a smooth curve
  (a monotone cubic would flatten the peak of a flight that it bridges);
* a lost stretch during which the wall reached the vertical (theta changes
  sign across it, or the bridge comes within :data:`VERTICAL_NOISES` noise
  levels of zero) hides an impact: the bridge there is no measurement, so
  the impact's velocities are not taken from it (:func:`unseen_impacts`,
  applied by :func:`rocklab.lab.motion.stored_motion`) and the count is in
  ``qc.csv`` (``impacts_unseen``);
* the noise is estimated from the data (:func:`rocklab.lab.motion.noise_level`
  on the measured samples, by the reduction);
* the velocities of the impacts are fitted as a transducer record's
  (:mod:`rocklab.lab.flight_fit`), with the settings of :func:`flight_fits`:
  no guard against a ringing that a rotation record does not have, and
  windows over most of each flight, which its noise needs;
* a dead or clipped theta loses the instrument
  (:func:`rocklab.lab.instrument.health`); a lost stretch too long to bridge
  inside the motion does too.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypedDict

import numpy as np
from numpy.typing import ArrayLike

from rocklab.lab.instrument import InstrumentMotion, health
from rocklab.lab.records import RotationRecord

#: Longest lost stretch bridged [s]: occlusions of a few to a few tens of
#: frames at 100-500 Hz; within it a flight is a smooth curve (p * 0.25 s < 1).
MAX_BRIDGE_S = 0.25
#: A bridge within this many noise levels of theta = 0 reaches the vertical.
VERTICAL_NOISES = 5.0
#: Samples after an impact left out of the fit of the take-off [samples]: as many as
#: before a landing (:func:`rocklab.lab.motion.landing_window`), the impact's own.
IMPACT_SAMPLES = 2.5
#: Half-width of the fits of the flights [1/p]: the whole rise of a flight below 0.6 alpha.
WINDOW_P = 1.5


class FlightFits(TypedDict, total=False):
    """Settings of :func:`rocklab.lab.motion.extract_motion`'s fits of the flights (its parameters)."""

    ring_guard_s: float
    window_p: float


def flight_fits(fs: float) -> FlightFits:
    """The settings of :func:`rocklab.lab.motion.extract_motion` for a rotation record sampled at ``fs`` [Hz].

    The transducers' defaults leave out 0.06 s after each impact, their
    ringing, and fit 0.6/p each side of it.  A rotation record (markers, a
    film, an inclinometer) does not ring: the guard is the impact's own
    :data:`IMPACT_SAMPLES`.  Its noise is about ten times a transducer
    record's, and a film's error follows the wall's speed (the compression
    shifts a moving marker, by up to 1e-4 rad at the impact, where the wall
    is fastest): fits over :data:`WINDOW_P` / p, most of each flight,
    average both down.  On the two-sided walls of
    ``bench/native_accuracy.py`` the median |e error| of a film at 240
    frames per second went from 0.017 to 0.008, that of a C3D at 240 Hz
    from 0.010 to 0.003 (CHANGELOG); the exact motion's stays 0.

    Returns
    -------
    FlightFits
        ``ring_guard_s`` [s] and ``window_p`` [1/p].
    """
    return {"ring_guard_s": IMPACT_SAMPLES / fs, "window_p": WINDOW_P}


def lost_stretches(lost: ArrayLike) -> list[tuple[int, int]]:
    """(first, stop) sample indices of the runs of lost samples."""
    edges = np.diff(np.r_[0, np.asarray(lost, np.int8), 0])
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def bridge(time: np.ndarray, x: ArrayLike, lost: np.ndarray) -> np.ndarray:
    """``x`` with its lost samples bridged by a cubic spline through the measured ones;
    before the first and after the last measured sample, that sample (the
    record starts held and ends at rest)."""
    from scipy.interpolate import CubicSpline  # imported here: scipy costs 1 s at start-up

    x = np.array(x, float)
    good = ~lost
    if lost.any() and good.sum() >= 2:
        inner = lost & (time > time[good][0]) & (time < time[good][-1])
        x[inner] = CubicSpline(time[good], x[good])(time[inner])
        x[: np.argmax(good)] = x[good][0]
        x[len(x) - np.argmax(good[::-1]) :] = x[good][-1]
    return x


def at_vertical(theta: np.ndarray, lost: np.ndarray, noise: float) -> list[tuple[int, int]]:
    """The lost stretches (:func:`lost_stretches`) in which the bridged ``theta`` reached the vertical:
    a sign change across the stretch or a bridge within :data:`VERTICAL_NOISES` noise levels of 0."""
    out: list[tuple[int, int]] = []
    for i0, i1 in lost_stretches(lost):
        if i0 == 0 or i1 == len(theta):
            continue
        inside = np.abs(theta[i0:i1]).min()
        if np.sign(theta[i0 - 1]) != np.sign(theta[i1]) or inside < VERTICAL_NOISES * noise:
            out.append((i0, i1))
    return out


def rotation_motion(
    rec: RotationRecord, alpha: float, noise_of: Callable[[np.ndarray, float], float]
) -> InstrumentMotion:
    """The wall's motion from a rotation record, its gaps bridged and flagged (module docstring).

    Parameters
    ----------
    rec : RotationRecord
    alpha : float
        Slenderness angle of the wall [rad]: the span its release must give theta.
    noise_of : callable
        ``noise_of(theta, fs)``: the noise of a rotation record [rad]
        (:func:`rocklab.lab.motion.noise_level`).
    """
    t, fs = rec.time, rec.fs
    theta_raw = rec.dof["theta"]
    lost = np.isnan(theta_raw)
    faults, malfunction = health({"theta_rad": (theta_raw, alpha)}, fs)
    theta = bridge(t, theta_raw, lost)
    noise = noise_of(theta_raw[~lost], fs) if (~lost).sum() > 10 else np.nan
    flags: list[str] = []
    stretches = lost_stretches(lost)
    inner = [(i0, i1) for i0, i1 in stretches if i0 > 0 and i1 < len(t)]
    too_long = [(i0, i1) for i0, i1 in inner if (i1 - i0) / fs > MAX_BRIDGE_S]
    if too_long and malfunction is None:
        i0, i1 = max(too_long, key=lambda s: s[1] - s[0])
        malfunction = (
            f"theta_rad lost for {(i1 - i0) / fs:.2f} s from {t[i0]:.2f} s"
            f" (longer than the {MAX_BRIDGE_S:g} s that can be bridged)"
        )
    if lost.any():
        flags.append(f"theta_rad {int(lost.sum())} lost sample(s) in {len(stretches)} stretch(es) bridged")
    unseen = at_vertical(theta, lost, noise) if np.isfinite(noise) else []
    if unseen:
        flags.append(f"{len(unseen)} impact(s) on a lost stretch: not measured")
    dof: dict[str, np.ndarray] = {}
    for name in ("phi", "v", "w"):
        x = rec.dof.get(name)
        if x is None:
            flags.append(f"{name} not in the record: {name} = 0")
            dof[name] = np.zeros_like(t)
        else:
            dof[name] = bridge(t, x, np.isnan(x))
    unit = {"theta": "rad", "phi": "rad", "v": "mm", "w": "mm"}
    variables: dict[str, tuple[str, np.ndarray, dict[str, Any]]] = {
        f"{name}_measured": ("time", x, {"units": unit[name], "long_name": f"{name} as recorded (NaN: lost)"})
        for name, x in rec.dof.items()
    }
    variables["theta_lost"] = (
        "time",
        lost.astype(np.int8),
        {
            "long_name": "theta not measured here: bridged",
            "flag_values": np.array([0, 1], np.int8),
            "flag_meanings": "measured bridged",
        },
    )
    return InstrumentMotion(
        theta,
        dof["phi"],
        dof["v"],
        dof["w"],
        lost,
        malfunction,
        flags,
        faults,
        variables,
        {"samples_bridged": int(lost.sum()), "impacts_unseen": len(unseen), "theta_noise_rad": noise, **rec.attrs},
    )


def unseen_impacts(t_arrival: ArrayLike, t_departure: ArrayLike, time: np.ndarray, lost: np.ndarray) -> np.ndarray:
    """Which impacts fell on a lost stretch.

    An impact from its arrival at theta = 0 to its departure, widened by a
    sample each side, that overlaps a lost stretch (widened to the measured
    samples around it) was not measured: its velocities would be those of
    the bridge.

    Parameters
    ----------
    t_arrival, t_departure : ndarray
        Arrival at and departure from theta = 0 of each impact [s].
    time : ndarray
        Time of the record [s].
    lost : ndarray of bool
        Samples not measured (``theta_lost``).

    Returns
    -------
    ndarray of bool
        One per impact.
    """
    t_arrival, t_departure = np.asarray(t_arrival, float), np.asarray(t_departure, float)
    out = np.zeros(t_arrival.shape, bool)
    dt = time[1] - time[0] if len(time) > 1 else 0.0
    for i0, i1 in lost_stretches(lost):
        lo, hi = time[max(i0 - 1, 0)], time[min(i1, len(time) - 1)]
        out |= (t_departure + dt >= lo) & (t_arrival - dt <= hi)
    return out
