"""Figures of the shake-table outcomes: fragility curves and maps of the calibrated blocks.

Each function returns a ``matplotlib.figure.Figure``; the workflow saves them.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from rocklab.plots.maps import _MAP_COLOURS, _edges
from rocklab.shake_table.evaluation import fragility_table

if TYPE_CHECKING:
    import pandas as pd
    import xarray as xr

_STYLE = {
    "block-calibrated": dict(color="C3", ls="-"),
    "pgv-threshold": dict(color="C0", ls="--"),
}


def fragility_curves(predictions: pd.DataFrame) -> Figure:
    """P(overturning) against PGV and PGA per specimen: measured, the calibrated block and the PGV threshold.

    Measured: the overturning rate of each bin, with its 95 % interval over
    resampled records (:func:`rocklab.shake_table.evaluation.fragility_table`);
    models: their mean held-out probability in the same bins, and the
    calibrated block's held-out probability of each test.

    Parameters
    ----------
    predictions : pandas.DataFrame
        predictions.csv (:func:`rocklab.shake_table.evaluation.cross_validate`).
    """
    table = fragility_table(predictions)
    specimens = sorted(predictions.specimen.unique())
    fig, axes = plt.subplots(len(specimens), 2, figsize=(11, 3.8 * len(specimens)), squeeze=False)
    for row, s in zip(axes, specimens):
        g = predictions[predictions.specimen == s]
        for ax, measure, col, unit in zip(row, ("pgv", "pga"), ("pgv_m_s", "pga_g"), ("m/s", "g")):
            x = g[col].to_numpy()
            ax.scatter(x, g.p_block_calibrated, s=5, c="C3", alpha=0.25, label="calibrated block, per test")
            t = table[(table.specimen == s) & (table.measure == measure)]
            mid = np.where(np.isfinite(t.upper), 0.5 * (t.lower + t.upper.fillna(0)), 1.3 * t.lower)
            mid = np.maximum(mid, 0.5 * x.min())
            err = np.vstack([t.observed - t.observed_lo, t.observed_hi - t.observed])
            ax.errorbar(mid, t.observed, yerr=err, fmt="ks", ms=5, capsize=3, label="measured rate, 95 % CI (records)")
            for m in ("block-calibrated", "pgv-threshold"):
                ax.plot(mid, t[m.replace("-", "_")], marker=".", label=f"{m}, held out", **_STYLE[m])
            ax.set_xscale("log")
            ax.set_xlabel(f"{measure.upper()} ({unit})")
            ax.set_ylabel("P(overturning)")
            ax.set_ylim(-0.05, 1.05)
            ax.set_title(f"{s}: against {measure.upper()}")
        row[0].legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    return fig


def calibrated_maps(maps: Sequence[xr.Dataset]) -> Figure:
    """Overturning maps of the calibrated blocks: one panel per specimen and record (overturned gray).

    Parameters
    ----------
    maps : sequence of xarray.Dataset
        :func:`rocklab.shake_table.evaluation.calibrated_maps` of each specimen.
    """
    panels = [(ds, r) for ds in maps for r in ds.record.values]
    fig, axes = plt.subplots(1, len(panels), figsize=(4.2 * len(panels), 4.2), squeeze=False)
    for ax, (ds, r) in zip(axes[0], panels):
        m = ds.sel(record=r)
        ax.pcolormesh(
            _edges(m.duration_scale.values),
            _edges(m.amplitude_scale.values),
            m.overturned.values,
            cmap=_MAP_COLOURS,
            vmin=0,
            vmax=1,
        )
        ax.set_xlabel("D_S/D")
        ax.set_ylabel("A_S/A")
        ax.set_title(f"{ds.attrs.get('specimen', '')} calibrated\n{r}  N_O = {float(m.N_O):.2f}", fontsize=9)
    fig.tight_layout()
    return fig
