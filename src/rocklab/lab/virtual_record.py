"""A virtual record: the transducer readings of a wall motion, written in the lab's raw format.

Turns a wall motion (theta, and optionally phi, v, w, on a time grid) into
the record of one test (``docs/raw-format.md``), with the instrument
effects of the real campaign (noise, 50 Hz mains hum, ringing after
impacts, 3-decimal readings, :class:`Effects`), the test protocol (a hold
phase with the screw's slow creep, the release, free rocking, rest, a
residual out-of-plumb), and
the instrument faults that the lab's validity rules must catch (dead, stuck
and clipped channels, spikes, short gaps, an unreadable file,
:class:`Fault`).  Every effect is a knob that can be switched off, and
everything random is drawn from the generator given.

Layers, from the bottom:

* :func:`instrument_readings` / :func:`apply_faults`: readings from a motion;
* :func:`record_from_motion`: a whole record (hold, release, rocking, rest)
  from a free-rocking history theta(t) given as arrays;
* :func:`write_record`: the record as ``tests/<id>.csv.gz``.

The walls, their causes and the campaign around the records are
:mod:`rocklab.lab.virtual_lab`'s.  Lengths of the record in mm, dynamics in
SI (m, s, rad).
"""

from __future__ import annotations

import gzip
import io
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from rocklab.lab import kinematics

#: Faults that lose a channel, and those that are repaired.
LOSING_FAULTS = ("dead", "stuck", "clipped")
REPAIRABLE_FAULTS = ("spikes", "gaps")


@dataclass(frozen=True)
class Effects:
    """Instrument and protocol effects; a zero amplitude switches one off.

    Defaults match the real campaign: 0.002 mm noise and 50 Hz hum of
    ~0.002 mm on every channel, a 0.05-0.1 mm transient dying out in
    ~50 ms after impacts, a hold of 1.5-3 s with the screw pushing the wall
    back at ~3e-4 rad/s, 2-4 s of rest at the end, twist of ~5e-4 rad.

    Attributes
    ----------
    noise_mm : float
        Standard deviation of the white gaussian noise of each channel [mm].
    hum_mm, hum_hz : float
        Amplitude [mm] and frequency [Hz] of the mains hum (random phase per
        channel; aliased at 100 Hz sampling).
    ringing_mm, ringing_hz, ringing_tau_s : float
        Ringing after each impact: amplitude [mm] at the top of the wall for
        the first impact (scaled by the impact velocity and the transducer
        height), frequency [Hz], decay time [s].
    creep_rad_s : float
        Rate at which the screw pushes the held wall back [rad/s].
    hold_s, rest_s : (float, float)
        Ranges of the hold before the release and of the rest after the
        motion has died out [s].
    twist_ratio : float
        Twist phi as a fraction of theta (asymmetric wall) [-].
    slide_mm : float
        Standard deviation of the sliding w added at each impact [mm].
    decimals : int or None
        Decimals of the written readings (the lab writes 3); None keeps all.
    """

    noise_mm: float = 0.002
    hum_mm: float = 0.002
    hum_hz: float = 50.0
    ringing_mm: float = 0.08
    ringing_hz: float = 35.0
    ringing_tau_s: float = 0.012
    creep_rad_s: float = 3e-4
    hold_s: tuple[float, float] = (1.5, 3.0)
    rest_s: tuple[float, float] = (2.0, 4.0)
    twist_ratio: float = 0.005
    slide_mm: float = 0.005
    decimals: int | None = 3

    @classmethod
    def off(cls, **kw: Any) -> Effects:
        """Every effect switched off (exact readings), except those in kw."""
        base = cls(
            noise_mm=0.0, hum_mm=0.0, ringing_mm=0.0, creep_rad_s=0.0, twist_ratio=0.0, slide_mm=0.0, decimals=None
        )
        return replace(base, **kw)


@dataclass(frozen=True)
class Fault:
    """An instrument fault injected in one record.

    Attributes
    ----------
    kind : {'dead', 'stuck', 'clipped', 'spikes', 'gaps', 'gain', 'unreadable'}
        ``dead``: the channel reads ~0 (noise only) throughout; ``stuck``:
        frozen at its value from ``start_s`` on; ``clipped``: saturates at
        ``level`` times its largest |reading| (default 0.6); ``spikes``:
        ``count`` isolated samples off by 2-30 mm; ``gaps``: ``count`` runs of
        1 to ``max_len`` lost samples (empty fields); ``gain``: every reading
        times ``level`` (default 0.98, a transducer out of calibration); ``unreadable``: the file
        is truncated in the middle of the gzip stream (``channel`` ignored).
    channel : int
        Channel number (as in ``setups.csv``).
    """

    kind: str
    channel: int = 0
    start_s: float | None = None
    level: float | None = None
    count: int = 3
    max_len: int = 8

    def describe(self) -> str:
        """The fault in words, as a flag of the reduction names it."""
        if self.kind == "unreadable":
            return "unreadable file"
        extra = f" from {self.start_s:.2f} s" if self.start_s is not None and self.kind == "stuck" else ""
        n = f" x{self.count}" if self.kind in REPAIRABLE_FAULTS else ""
        g = f" {0.98 if self.level is None else self.level:g}" if self.kind == "gain" else ""
        return f"ch{self.channel} {self.kind}{extra}{n}{g}"


def usual_layout(setup: str, length_mm: float, height_mm: float, thickness_mm: float, one_sided: bool) -> pd.DataFrame:
    """Transducers in the usual layout of the spec, as ``setups.csv`` rows.

    Channels 0, 1 on x = -L/2 and 2, 3 on x = +L/2 at 0.35 h and 0.85 h,
    horizontal along y with the frame 180-210 mm on the -y side; channel 4 on
    x = +L/2 at 0.6 h along x (frame 150 mm beyond); channel 5 (one-sided
    only) at the centre of the outer face at 0.5 h, frame 160 mm outside.
    Heights and distances are those of the real campaign's setups.
    """
    L, h, b = float(length_mm), float(height_mm), float(thickness_mm)
    lo, hi, mid = round(0.35 * h), round(0.85 * h), round(0.6 * h)
    rows: list[tuple[float, ...]] = [
        (0, -L / 2, 0, lo, -L / 2, -180, lo),
        (1, -L / 2, 0, hi, -L / 2, -210, hi),
        (2, L / 2, 0, lo, L / 2, -185, lo),
        (3, L / 2, 0, hi, L / 2, -205, hi),
        (4, L / 2, 0, mid, L / 2 + 150, 0, mid),
    ]
    if one_sided:
        z5 = round(0.5 * h)
        rows.append((5, 0, b / 2, z5, 0, b / 2 + 160, z5))
    df = pd.DataFrame(
        rows, columns=["channel", "wall_x_mm", "wall_y_mm", "wall_z_mm", "frame_x_mm", "frame_y_mm", "frame_z_mm"]
    )
    df.insert(0, "setup", setup)
    return df


def transducer_geometry(layout: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """Wall and frame ends of the transducers of a layout, (nch, 3) arrays each [mm]."""
    X = layout[["wall_x_mm", "wall_y_mm", "wall_z_mm"]].to_numpy(float)
    F = layout[["frame_x_mm", "frame_y_mm", "frame_z_mm"]].to_numpy(float)
    return X, F


def top_offset_mm(
    theta: ArrayLike,
    phi: ArrayLike,
    v: ArrayLike,
    w: ArrayLike,
    length_mm: float,
    height_mm: float,
    thickness_mm: float,
) -> np.ndarray | float:
    """Largest |y displacement| of the two top corners of the wall [mm].

    The quantity of the out-of-plumb rule, exact from the rigid-body map of
    the spec (the y component of X' - X at (+-L/2, 0, h)).
    """
    th, ph = np.asarray(theta, float), np.asarray(phi, float)
    b, h = float(thickness_mm), float(height_mm)
    ey = np.where(th < 0, -b / 2, b / 2)
    qy = np.cos(th) * (0 - ey) + np.sin(th) * h + ey
    out = [np.sin(ph) * x + np.cos(ph) * qy + np.asarray(w, float) for x in (-length_mm / 2, length_mm / 2)]
    return np.max(np.abs(out), axis=0)


def instrument_readings(
    t: np.ndarray,
    theta: ArrayLike,
    phi: ArrayLike,
    v: ArrayLike,
    w: ArrayLike,
    layout: pd.DataFrame,
    thickness_mm: float,
    height_mm: float,
    effects: Effects = Effects(),
    impacts: Sequence[tuple[float, float]] | None = None,
    rng: np.random.Generator | int | None = None,
) -> np.ndarray:
    """Transducer readings of a motion with noise, hum and ringing [mm].

    Parameters
    ----------
    t : ndarray (N,)
        Time [s].
    theta, phi : ndarray (N,)
        Rotations [rad].
    v, w : ndarray (N,)
        Sliding [mm].
    layout : DataFrame
        ``setups.csv`` rows of the setup.
    thickness_mm, height_mm : float
        Wall thickness and height [mm].
    effects : Effects
    impacts : sequence of (t_impact [s], strength [-]), optional
        Impacts that make the readings ring; strength 1 for the reference
        (first) impact.
    rng : numpy.random.Generator

    Returns
    -------
    ndarray (N, nch)
        Elongations [mm] before faults and rounding.
    """
    rng = np.random.default_rng(rng)
    X, F = transducer_geometry(layout)
    E = kinematics.transducer_elongation(theta, phi, v, w, X, F, thickness_mm)
    n, nch = E.shape
    if effects.noise_mm > 0:
        E += rng.normal(0.0, effects.noise_mm, E.shape)
    if effects.hum_mm > 0:
        ph = rng.uniform(0, 2 * np.pi, nch)
        amp = effects.hum_mm * rng.uniform(0.5, 1.5, nch)
        E += amp * np.sin(2 * np.pi * effects.hum_hz * t[:, None] + ph)
    if effects.ringing_mm > 0 and impacts is not None and len(impacts):
        reach = np.clip(X[:, 2] / float(height_mm), 0.0, 1.0) * rng.uniform(0.6, 1.4, nch)
        ring = np.zeros(n)
        dt = t[1] - t[0]
        span = int(np.ceil(6 * effects.ringing_tau_s / dt)) + 1
        for ti, strength in impacts:
            i0 = int(np.searchsorted(t, ti))
            seg = slice(i0, min(i0 + span, n))
            tau = t[seg] - ti
            ring[seg] += strength * np.exp(-tau / effects.ringing_tau_s) * np.sin(2 * np.pi * effects.ringing_hz * tau)
        E += effects.ringing_mm * ring[:, None] * reach
    return E


def apply_faults(
    readings: np.ndarray,
    t: np.ndarray,
    faults: Iterable[Fault],
    channels: Sequence[int],
    rng: np.random.Generator | int | None = None,
    noise_mm: float = 0.002,
) -> np.ndarray:
    """Inject instrument faults in readings (in place) [mm].

    Parameters
    ----------
    readings : ndarray (N, nch)
    t : ndarray (N,)
    faults : sequence of Fault
    channels : sequence of int
        Channel number of each column.
    rng : numpy.random.Generator
    noise_mm : float
        Noise left on a dead channel.

    Returns
    -------
    ndarray
        The readings, with NaN for lost samples.
    """
    rng = np.random.default_rng(rng)
    col = {c: i for i, c in enumerate(channels)}
    n = len(t)
    for f in faults:
        if f.kind == "unreadable":
            continue
        x = readings[:, col[f.channel]]
        if f.kind == "dead":
            x[:] = (0.0 if f.level is None else f.level) + rng.normal(0, noise_mm, n)
        elif f.kind == "stuck":
            i0 = int(np.searchsorted(t, f.start_s if f.start_s is not None else t[n // 3]))
            x[i0:] = x[i0]
        elif f.kind == "clipped":
            k = int(np.nanargmax(np.abs(x)))
            lim = (0.6 if f.level is None else f.level) * abs(x[k])
            x[:] = np.minimum(x, lim) if x[k] > 0 else np.maximum(x, -lim)
        elif f.kind == "spikes":
            idx = rng.choice(np.arange(5, n - 5), size=f.count, replace=False)
            x[idx] += rng.choice([-1.0, 1.0], f.count) * rng.uniform(2.0, 30.0, f.count)
        elif f.kind == "gain":
            # a transducer out of calibration: every reading scaled (level: the gain, default 0.98)
            x *= 0.98 if f.level is None else f.level
        elif f.kind == "gaps":
            for i0 in rng.choice(np.arange(5, n - f.max_len - 5), size=f.count, replace=False):
                x[i0 : i0 + rng.integers(1, f.max_len + 1)] = np.nan
        else:
            raise ValueError(f"unknown fault kind {f.kind!r}")
    return readings


def _smoothstep(u: np.ndarray) -> np.ndarray:
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3 - 2 * u)


def record_from_motion(
    t_free: np.ndarray,
    theta_free: ArrayLike,
    fs: float,
    layout: pd.DataFrame,
    specimen: Mapping[str, Any],
    *,
    phi_free: np.ndarray | None = None,
    v_free: np.ndarray | None = None,
    w_free: np.ndarray | None = None,
    impacts: pd.DataFrame | None = None,
    t_rest: float | None = None,
    effects: Effects = Effects(),
    faults: Iterable[Fault] = (),
    residual_top_mm: float = 0.0,
    residual_kind: str = "rotation",
    rng: np.random.Generator | int | None = None,
) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """A whole record (hold, release, free rocking, rest) from a free motion.

    Parameters
    ----------
    t_free, theta_free : ndarray
        Free rocking from the release (t_free[0] = 0) on the grid 1/fs [s, rad];
        theta_free[0] is the release rotation theta0.
    fs : float
        Sampling rate [Hz] (400 or 100).
    layout : DataFrame
        ``setups.csv`` rows of the setup.
    specimen : Mapping
        ``length_mm``, ``height_mm``, ``thickness_mm``.
    phi_free, v_free, w_free : ndarray, optional
        Extra degrees of freedom of the free motion [rad, mm, mm]; default
        the twist and sliding of ``effects``.
    impacts : DataFrame, optional
        Impacts of the free motion (``t`` [s] from release, ``thetadot_before``):
        they make the readings ring and the wall slide.
    t_rest : float, optional
        Time from release at which the wall comes to rest [s]; default the
        end of ``t_free``.
    effects : Effects
    faults : sequence of Fault
    residual_top_mm : float
        Final offset of the wall top (signed, y) [mm], grown over the motion.
    residual_kind : {'rotation', 'sliding'}
        As a final rotation theta_res = offset / h or a sliding w.
    rng : numpy.random.Generator

    Returns
    -------
    t : ndarray (N,)
        Record time [s] from 0.
    readings : ndarray (N, nch)
        Readings [mm], NaN where lost, rounded to ``effects.decimals``.
    truth : dict
        ``t_release``, ``theta0``, ``theta`` / ``phi`` / ``v`` / ``w`` arrays
        (the motion written), ``residual_top_mm`` (true, from the final pose).
    """
    rng = np.random.default_rng(rng)
    L, h, b = (float(specimen[k]) for k in ("length_mm", "height_mm", "thickness_mm"))
    dt = 1.0 / fs
    theta_free = np.asarray(theta_free, float)
    n_free = len(theta_free)
    if t_rest is None:
        t_rest = float(t_free[-1])
    # Drop the part of the free history far beyond the rest.
    hold = rng.uniform(*effects.hold_s)
    rest = rng.uniform(*effects.rest_s)
    n_keep = min(n_free, int(np.ceil((t_rest + rest) / dt)) + 1)
    theta_free = theta_free[:n_keep]
    n_hold = int(round(hold * fs))
    n_tail = max(int(np.ceil((t_rest + rest) / dt)) + 1 - n_keep, 0)
    theta0 = theta_free[0]
    sgn = np.sign(theta0) or 1.0
    # The screw holds the wall past the release rotation and pushes it back
    # slowly: a linear creep ending at theta0 at the release.
    th_hold = theta0 + sgn * effects.creep_rad_s * (n_hold - np.arange(n_hold)) * dt
    theta = np.concatenate([th_hold, theta_free, np.full(n_tail, theta_free[-1])])
    n = len(theta)
    t = np.arange(n) * dt
    t_release = n_hold * dt
    tf = t - t_release  # time from release
    rel = tf >= 0

    imp_t = np.asarray([] if impacts is None or len(impacts) == 0 else impacts["t"], float)
    imp_v = np.asarray([] if impacts is None or len(impacts) == 0 else np.abs(impacts["thetadot_before"]), float)
    imp_t, imp_v = imp_t[imp_t <= t_rest + rest], imp_v[imp_t <= t_rest + rest]

    phi = (
        effects.twist_ratio * theta
        if phi_free is None
        else np.concatenate([np.full(n_hold, phi_free[0]), phi_free[:n_keep], np.full(n_tail, phi_free[n_keep - 1])])
    )
    v = (
        np.zeros(n)
        if v_free is None
        else np.concatenate([np.full(n_hold, v_free[0]), v_free[:n_keep], np.full(n_tail, v_free[n_keep - 1])])
    )
    w = (
        np.zeros(n)
        if w_free is None
        else np.concatenate([np.full(n_hold, w_free[0]), w_free[:n_keep], np.full(n_tail, w_free[n_keep - 1])])
    )
    if w_free is None and effects.slide_mm > 0 and imp_t.size:
        steps = rng.normal(0, effects.slide_mm, imp_t.size)
        for ti, s in zip(imp_t, steps):
            w += s * _smoothstep((tf - ti) / 0.01)

    if residual_top_mm:
        # Grows from the first impact to the rest (the wall settles askew or
        # walks on its base), then stays.
        t_a = imp_t[0] if imp_t.size else 0.0
        ramp = _smoothstep((tf - t_a) / max(t_rest - t_a, dt)) * rel
        if residual_kind == "rotation":
            theta = theta + np.arcsin(residual_top_mm / h) * ramp
        elif residual_kind == "sliding":
            w = w + residual_top_mm * ramp
        else:
            raise ValueError("residual_kind must be 'rotation' or 'sliding'")

    ring: list[tuple[float, float]] | None = None
    if imp_t.size:
        ring = list(zip(imp_t + t_release, imp_v / imp_v[0]))
    E = instrument_readings(t, theta, phi, v, w, layout, b, h, effects, ring, rng)
    apply_faults(E, t, faults, layout.channel.tolist(), rng, effects.noise_mm)
    if effects.decimals is not None:
        E = np.round(E, effects.decimals)
    top = top_offset_mm(theta[-1], phi[-1], v[-1], w[-1], L, h, b)
    truth = {
        "t_release": t_release,
        "theta0": float(theta0),
        "theta": theta,
        "phi": phi,
        "v": v,
        "w": w,
        "residual_top_mm": float(top),
        "t_rest": t_release + t_rest,
    }
    return t, E, truth


def write_record(
    path: str | Path,
    test_id: str,
    fs: float,
    t: np.ndarray,
    readings: np.ndarray,
    channels: Iterable[int],
    unreadable: bool = False,
) -> None:
    """Write one ``tests/<id>.csv.gz`` exactly in the lab's format.

    Time with 4 decimals, readings with 3, empty fields for NaN.  With
    ``unreadable`` the gzip stream is cut in the middle (a broken transfer).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    head = f"# test_id: {test_id}\n# sampling_rate_hz: {fs:g}\n# units: s, mm\n"
    head += "time_s," + ",".join(f"ch{c}" for c in channels) + "\n"
    buf = io.StringIO()
    np.savetxt(buf, np.column_stack([t, readings]), fmt=["%.4f"] + ["%.3f"] * readings.shape[1], delimiter=",")
    body = buf.getvalue().replace("nan", "")
    data = gzip.compress((head + body).encode(), compresslevel=6, mtime=0)
    if unreadable:
        data = data[: len(data) // 2]
    path.write_bytes(data)
