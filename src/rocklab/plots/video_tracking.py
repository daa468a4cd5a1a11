"""The figure of a filmed test: the markers tracked, drawn on a frame (matplotlib, no display)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from rocklab.lab.video_tracking import MARKERS


def tracked_markers(frame: np.ndarray, centroids: np.ndarray, diameter_px: float, title: str = "") -> Figure:
    """A frame in grey with the four markers found in it circled and named.

    Parameters
    ----------
    frame : ndarray (H, W) of uint8
        The frame, in grey levels.
    centroids : ndarray (4, 2)
        Image position (x right, y down) of :data:`rocklab.lab.video_tracking.MARKERS` [pixels]; NaN: not found.
    diameter_px : float
        Diameter of the markers [pixels] (the circles are twice it).
    title : str
    """
    h, w = frame.shape
    fig, ax = plt.subplots(figsize=(4.5, 4.5 * h / w + 0.4), layout="tight")
    ax.imshow(frame, cmap="gray", vmin=0, vmax=255, interpolation="nearest")
    colours = {"wall": "tab:orange", "post": "tab:cyan"}
    for name, (x, y) in zip(MARKERS, centroids):
        if not np.isfinite(x):
            continue
        colour = colours[name.split("_")[0]]
        ax.add_patch(plt.Circle((x, y), diameter_px, fill=False, color=colour, lw=1.2))
        ax.annotate(name.replace("_", " "), (x, y), (x + 1.3 * diameter_px, y), color=colour, fontsize=8, va="center")
    for pair, colour in ((slice(0, 2), colours["wall"]), (slice(2, 4), colours["post"])):
        ax.plot(centroids[pair, 0], centroids[pair, 1], color=colour, lw=0.8, ls="--")
    ax.set_title(title, fontsize=9)
    ax.set_axis_off()
    return fig
