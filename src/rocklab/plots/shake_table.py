"""Figures of the shake-table outcomes: fragility curves and maps of the calibrated blocks.

Each function returns a ``matplotlib.figure.Figure``; the workflow saves them.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rocklab.plots.maps import _MAP_COLOURS, _edges
from rocklab.shake_table.evaluation import MODELS, fragility_table

_STYLE = {
    "block-nominal": dict(color="0.5", ls=":"),
    "block-calibrated": dict(color="C3", ls="-"),
    "pgv-threshold": dict(color="C0", ls="--"),
    "dem": dict(color="C2", ls="-."),
}


def fragility_curves(predictions):
    """Held-out probability of overturning against PGA and PGV, with the measured outcomes.

    Parameters
    ----------
    predictions : pandas.DataFrame
        predictions.csv (:func:`rocklab.shake_table.evaluation.cross_validate`).
    """
    table = fragility_table(predictions)
    specimens = sorted(predictions.specimen.unique())
    fig, axes = plt.subplots(len(specimens), 2, figsize=(11, 3.8 * len(specimens)), squeeze=False)
    rng = np.random.default_rng(0)
    for row, s in zip(axes, specimens):
        g = predictions[predictions.specimen == s]
        for ax, measure, col, unit in zip(row, ("pga", "pgv"), ("pga_g", "pgv_m_s"), ("g", "m/s")):
            x = g[col].to_numpy()
            y = g.observed.to_numpy(float)
            ax.scatter(x, y + rng.uniform(-0.03, 0.03, y.size), s=6, c="k", alpha=0.3, label="measured outcome")
            ax.scatter(x, g.p_block_calibrated, s=6, c="C3", alpha=0.4, label="calibrated block, per test")
            t = table[(table.specimen == s) & (table.measure == measure)]
            mid = np.where(np.isfinite(t.upper), 0.5 * (t.lower + t.upper.fillna(0)), 1.3 * t.lower)
            mid = np.maximum(mid, 0.5 * x.min())
            ax.plot(mid, t.observed, "ks", ms=6, label="measured rate per bin")
            for m in MODELS:
                ax.plot(mid, t[m.replace("-", "_")], marker=".", label=m, **_STYLE[m])
            ax.set_xscale("log")
            ax.set_xlabel(f"{measure.upper()} ({unit})")
            ax.set_ylabel("P(overturning), held out")
            ax.set_ylim(-0.08, 1.08)
            ax.set_title(f"{s}: against {measure.upper()}")
        row[0].legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    return fig


def calibrated_maps(maps):
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
