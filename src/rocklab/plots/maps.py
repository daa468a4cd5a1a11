"""Figures of the overturning maps (Sect. 5): Figs. 21 and 23 (maps), Fig. 22 (indices).

Each function returns a ``matplotlib.figure.Figure``; the workflow saves them.
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure

from rocklab.seismic.walls import MODELS

if TYPE_CHECKING:
    import pandas as pd
    import xarray as xr

#: White: standing; gray: overturned, as the paper's dots.
_MAP_COLOURS = ListedColormap(["white", "0.45"])


def _edges(x: np.ndarray) -> np.ndarray:
    mid = 0.5 * (x[1:] + x[:-1])
    step = x[1] - x[0] if x.size > 1 else 1.0
    return np.concatenate([[x[0] - 0.5 * step], mid, [x[-1] + 0.5 * step]])


def overturning_maps(maps: Sequence[xr.Dataset], title: str | None = None) -> Figure:
    """Figs. 21 and 23: maps side by side, overturned cells gray.

    Parameters
    ----------
    maps : sequence of xarray.Dataset
        Results of :func:`rocklab.seismic.maps.overturning_map`; each panel is
        labelled with its model's description.
    title : str, optional
    """
    fig, axes = plt.subplots(1, len(maps), figsize=(5.2 * len(maps), 5.0), squeeze=False)
    for k, (ax, ds) in enumerate(zip(axes[0], maps)):
        o = ds["overturned"].transpose("amplitude_scale", "duration_scale")
        d, a = ds["duration_scale"].values, ds["amplitude_scale"].values
        ax.pcolormesh(_edges(d), _edges(a), o.values.astype(int), cmap=_MAP_COLOURS, vmin=0, vmax=1, rasterized=True)
        ax.set_aspect("equal")
        ax.set_xlabel("D_S / D")
        ax.set_ylabel("A_S / A")
        n_o = float(o.values.mean())
        desc = MODELS.get(ds.attrs["model"], ("", ds.attrs["model"]))[1].split(";")[0]
        ax.set_title(textwrap.fill(f"{chr(ord('a') + k)}  {desc}", 48) + f"\nN_O = {n_o:.3f}", fontsize=9)
    a0 = maps[0].attrs
    fig.suptitle(
        title
        or f"record {a0['record']}, alpha = {a0['alpha']:g} rad, R = {a0['R']:g} m, "
        f"{a0['form']} form (overturned: gray)",
        fontsize=10,
    )
    fig.set_layout_engine("tight")
    return fig


def map_indices_figure(
    summary: pd.DataFrame, models: Sequence[str] = ("2s-housner", "2s-0.95"), order: Sequence[str] | None = None
) -> Figure:
    """Fig. 22: (a) N_O and (b) (N_D + N_A)/2 record by record for two or more models.

    Parameters
    ----------
    summary : pandas.DataFrame
        :func:`rocklab.seismic.indices.summary_table`.
    models : sequence of str
        Models drawn side by side for every record.
    order : sequence of str, optional
        Records in drawing order (e.g. by Table 4 row); default as in ``summary``.
    """
    records = list(order) if order is not None else list(dict.fromkeys(summary["record"]))
    wide = summary.set_index(["record", "model"])
    fig, axes = plt.subplots(2, 1, figsize=(max(6.0, 0.7 * len(records) + 2), 7), sharex=True)
    x = np.arange(len(records))
    width = 0.8 / len(models)
    greys = np.linspace(0.2, 0.85, len(models))
    for k, model in enumerate(models):
        sub = wide.xs(model, level="model").reindex(records)
        label = MODELS.get(model, ("", model))[1].split(";")[0]
        xk = x + (k - (len(models) - 1) / 2) * width
        style = {"width": width, "label": label, "color": str(greys[k]), "edgecolor": "k"}
        axes[0].bar(xk, sub["N_O"], **style)
        axes[1].bar(xk, sub["scatter"], **style)
    axes[0].set_ylabel("N_O")
    axes[0].set_title("a  normalised number of overturnings", fontsize=10, loc="left")
    axes[1].set_ylabel("(N_D + N_A) / 2")
    axes[1].set_title("b  average normalised number of changes overturning - no overturning", fontsize=10, loc="left")
    axes[1].set_xticks(x, records, rotation=45, ha="right")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", ncol=len(models), fontsize=8)
    fig.set_layout_engine("tight", rect=(0, 0, 1, 0.95))
    return fig
