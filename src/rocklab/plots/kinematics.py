"""Figures of Sect. 2 regenerated from one reduced test (matplotlib, no display).

Each function takes a reduced dataset (:mod:`rocklab.lab.reduction`) and
returns a ``matplotlib.figure.Figure``; the workflow saves them: Fig. 6 (a
transducer record), Fig. 8 (the four degrees of freedom), Fig. 9 (Eq. 8
against the full kinematics, and the normalised peaks).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from numpy.typing import ArrayLike
from scipy.signal import savgol_filter

if TYPE_CHECKING:
    import pandas as pd
    import xarray as xr


def transducer_velocity(x: ArrayLike, fs: float, window_s: float = 0.025) -> np.ndarray:
    """Velocity of a transducer reading [mm/s] by a Savitzky-Golay derivative.

    A cubic over ``window_s`` (11 samples at 400 Hz) passes the rocking
    motion (a few Hz) and suppresses the 50 Hz mains hum and white noise that
    a plain finite difference would amplify.
    """
    n = max(int(round(window_s * fs)) | 1, 5)
    return savgol_filter(x, n, 3, deriv=1, delta=1.0 / fs)


def sample_record(ds: xr.Dataset, channel: int = 3) -> Figure:
    """Fig. 6: a transducer's record and its numerically derived velocity (a test that no transducer
    recorded: its rotation theta, as its rotation or inertial record gave it)."""
    if "elongation" in ds:
        ch = int(channel) if channel in ds.channel.values else int(ds.channel.values[0])
        x = ds.elongation.sel(channel=ch).values
        what, unit = f"Δl, transducer {ch}", "mm"
    else:
        x = ds.theta.values
        what, unit = f"θ, {ds.attrs.get('instrument', '')} record", "rad"
    t = ds.time.values
    fs = float(ds.attrs["sampling_rate_hz"])
    ok = np.isfinite(x)
    v = np.full_like(x, np.nan)
    v[ok] = transducer_velocity(x[ok], fs)
    fig, axes = plt.subplots(2, 1, figsize=(8, 6))
    t_rel = float(ds.attrs.get("t_release", t[0]))
    for ax, window in zip(axes, [(t[0], t[-1]), (t_rel - 0.5, t_rel + 2.5)]):
        ax.plot(t, x, "--", color="k", lw=0.8, label=f"{what} [{unit}]")
        ax2 = ax.twinx()
        ax2.plot(t, v, color="C0", lw=0.8, label=f"velocity [{unit}/s]")
        ax.set_xlim(*window)
        ax.set_xlabel("t [s]")
        ax.set_ylabel(f"{what.split(',')[0]} [{unit}]")
        ax2.set_ylabel(f"d{what.split(',')[0]}/dt [{unit}/s]")
    axes[0].set_title(f"Fig. 6 - test {ds.attrs['test_id']} ({ds.attrs['series']}); b: zoom on the motion")
    fig.set_layout_engine("tight")
    return fig


def degrees_of_freedom(ds: xr.Dataset) -> Figure:
    """Fig. 8: the four degrees of freedom, normalised (v, w by b; theta, phi by alpha_ind)."""
    a_ind = abs(float(ds.attrs.get("theta0_release", np.nan))) or float(ds.attrs["alpha"])
    b = float(ds.attrs["thickness_mm"])
    t = ds.time.values
    fig, axes = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
    for ax, (name, scale, label) in zip(
        axes, [("v", b, "v / b"), ("w", b, "w / b"), ("theta", a_ind, "θ / α_ind"), ("phi", a_ind, "φ / α_ind")]
    ):
        ax.plot(t, ds[name].values / scale, lw=0.8)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("t [s]")
    axes[0].set_title(f"Fig. 8 - test {ds.attrs['test_id']} ({ds.attrs['series']})")
    fig.set_layout_engine("tight")
    return fig


def eq8_and_peaks(ds: xr.Dataset, peaks: pd.DataFrame) -> Figure:
    """Fig. 9: (a) theta of Eqs. 3-7 against Eq. 8; (b) normalised DOF peaks per test.

    Parameters
    ----------
    ds : xarray.Dataset
        A reduced test (panel a).
    peaks : DataFrame
        Columns ``test_id``, ``peak_theta``, ``peak_phi``, ``peak_v``, ``peak_w``
        for the tests of one specimen (panel b).
    """
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 7))
    t = ds.time.values
    ax1.plot(t, ds.theta.values, lw=1.0, label="θ, Eqs. 3-7")
    if "theta_eq8" in ds:
        ax1.plot(t, ds.theta_eq8.values, "--", lw=1.0, label="θ, Eq. 8")
        ax1.set_title(
            f"Fig. 9a - test {ds.attrs['test_id']}: max |Δθ| = {ds.attrs.get('theta_eq8_max_abs_diff', np.nan):.2e} rad"
        )
    ax1.set_xlabel("t [s]")
    ax1.set_ylabel("θ [rad]")
    ax1.legend()
    x = np.arange(len(peaks))
    for _k, (col, label) in enumerate(
        [("peak_v", "max|v|/b"), ("peak_w", "max|w|/b"), ("peak_theta", "max|θ|/α"), ("peak_phi", "max|φ|/α")]
    ):
        ax2.plot(x, peaks[col].to_numpy(), "o-", ms=3, label=label)
    ax2.set_yscale("log")
    ax2.set_xticks(x, peaks.test_id, rotation=90, fontsize=6)
    ax2.set_ylabel("normalised peak")
    ax2.legend(fontsize=7)
    ax2.set_title(f"Fig. 9b - specimen {peaks.attrs.get('specimen', '')}")
    fig.set_layout_engine("tight")
    return fig
