"""The campaign level in one figure: each parameter against h/b and contact depth.

One row per parameter (:func:`rocklab.dissipation.covariates.series_fits`),
one column per (boundary condition, covariate): the values of the units the
covariate is a property of (specimens for h/b, series for contact depth)
with their parent's departure removed (a partial plot), the fitted line of
the model at that level and its 95 % confidence band.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.figure import Figure

from rocklab.inference.verdicts import ClaimVerdict
from rocklab.physics.boundary import Boundary

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.artist import Artist

    from rocklab.dissipation.covariates import LevelFit

#: The panels of each row: (boundary, covariate, axis label).
COLUMNS = (
    (Boundary.TWO_SIDED, "h_over_b", "h/b"),
    (Boundary.ONE_SIDED, "h_over_b", "h/b"),
    (Boundary.ONE_SIDED, "contact_depth_mm", "contact depth CD (mm)"),
)
#: Marker of each unit material (others get circles).
MARKERS = {"clay brick": "s", "tuff": "^"}


def covariate_figure(
    fits: Mapping[tuple[str, str], Mapping[str, LevelFit]], effects: pd.DataFrame | None = None
) -> Figure:
    """Parameters against h/b and contact depth, with the fitted line and band.

    Parameters
    ----------
    fits : dict
        (boundary, response) -> {covariate: LevelFit}
        (:func:`rocklab.dissipation.covariates.series_fits`).
    effects : pandas.DataFrame, optional
        campaign_effects.csv: each panel's title gives the effect's verdict and p.

    Returns
    -------
    matplotlib.figure.Figure
    """
    responses = sorted({r for (_, r), f in fits.items() if f})
    if not responses:
        fig, ax = plt.subplots(figsize=(6, 2))
        ax.axis("off")
        ax.text(0.5, 0.5, "no parameter has enough units for a fit at its level", ha="center", va="center")
        return fig
    height = 1.9 * len(responses) + 1.2
    fig, axes = plt.subplots(len(responses), len(COLUMNS), figsize=(11, height), squeeze=False, sharex="col")
    # fixed margins in inches: tight_layout costs a second on this many panels
    fig.subplots_adjust(left=0.1, right=0.98, bottom=0.7 / height, top=1 - 0.95 / height, hspace=0.45, wspace=0.3)
    for i, response in enumerate(responses):
        for j, (boundary, covariate, label) in enumerate(COLUMNS):
            ax = axes[i, j]
            fit = fits.get((boundary, response), {}).get(covariate)
            if fit is None:
                ax.text(
                    0.5, 0.5, ClaimVerdict.NOT_TESTABLE, ha="center", va="center", transform=ax.transAxes, color="0.5"
                )
                ax.set_yticks([])
            else:
                part = fit.partial()
                ax.fill_between(part["grid"], part["low"], part["high"], color="C0", alpha=0.2, lw=0)
                ax.plot(part["grid"], part["line"], color="C0")
                for unit, rows in fit.frame.groupby("unit"):
                    sel = rows.index.to_numpy()
                    ax.plot(part["x"][sel], part["y"][sel], MARKERS.get(unit, "o"), color="k", ms=4, mfc="none",
                            label=unit)  # fmt: skip
                if effects is not None:
                    key = (effects.boundary == boundary) & (effects.response == response)
                    e = effects[key & (effects.covariate == covariate)]
                    if len(e):
                        ax.set_title(f"{e.verdict.iloc[0]} (p = {e.p.iloc[0]:.2g})", fontsize=8)
            if i == 0:
                ax.annotate(boundary, (0.5, 1.22), xycoords="axes fraction", ha="center", fontsize=10)
            if i == len(responses) - 1:
                ax.set_xlabel(label)
            if j == 0:
                ax.set_ylabel(response.replace(".", ".\n"), fontsize=8)
    legend: dict[str, Artist] = {}  # label -> handle
    for ax in axes.flat:
        legend |= dict(zip(*reversed(ax.get_legend_handles_labels())))
    if legend:
        fig.legend(legend.values(), legend.keys(), loc="lower center", ncol=len(legend), fontsize=8)
    fig.suptitle(
        "Campaign level: unit values within their parent, fit at the covariate's level and 95 % band",
        y=1 - 0.15 / height,
        fontsize=10,
    )
    return fig
