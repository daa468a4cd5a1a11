"""Figures of Sects. 3-4 regenerated from the dissipation tables (matplotlib, no display).

Figs. 10, 11, 13, 16-20 from ``tests.csv``, ``e_by_n.csv`` and
``series.csv`` (:mod:`rocklab.dissipation.analysis`); as in the paper, panel a is
two-sided and panel b one-sided rocking, with their own y scales, and the
test series are ordered by h/b.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from rocklab.physics.boundary import Boundary

if TYPE_CHECKING:
    import xarray as xr
    from matplotlib.axes import Axes

#: Panels of the Sect. 3-4 figures, in the paper's order.
PANELS = ((Boundary.TWO_SIDED, "a", "2s"), (Boundary.ONE_SIDED, "b", "1s"))
#: Marker colour of each contact depth (Fig. 13b).
CD_COLORS = {60.0: "C0", 120.0: "C1", 260.0: "C2"}


def _series_order(series: pd.DataFrame) -> pd.DataFrame:
    """Series of a table sorted by h/b, then contact depth."""
    cols = [c for c in ("h_over_b", "contact_depth_mm", "series") if c in series]
    return series.sort_values(cols, na_position="first").reset_index(drop=True)


def _two_panels(figsize: tuple[float, float] = (9, 7), sharex: bool = False) -> tuple[Figure, dict[str, Axes]]:
    fig, axes = plt.subplots(2, 1, figsize=figsize, sharex=sharex)
    return fig, dict(zip((b for b, _, _ in PANELS), axes))


def _series_ticks(ax: Axes, s: pd.DataFrame) -> None:
    labels = [f"{r.series}\n{r.h_over_b:.1f}" for r in s.itertuples()]
    ax.set_xticks(np.arange(len(s)), labels, rotation=90, fontsize=7)
    ax.set_xlabel("test series, h/b")


def initial_rotation_by_test(tests: pd.DataFrame) -> Figure:
    """Fig. 10: theta0 / alpha (nominal alpha) test after test, per series.

    Parameters
    ----------
    tests : pandas.DataFrame
        ``results/tests.csv`` in test order.
    """
    fig, axes = _two_panels(figsize=(11, 7))
    for boundary, letter, short in PANELS:
        ax = axes[boundary]
        d = tests[tests.boundary == boundary]
        for name, g in d.groupby("series", sort=True):
            ax.plot(np.arange(1, len(g) + 1), g.theta0_over_alpha, "o-", ms=3, lw=0.8, label=name)
        ax.set_ylabel("θ0 / α")
        ax.set_title(f"Fig. 10{letter} - {short}")
        if len(d):
            ax.legend(fontsize=6, ncol=2, loc="center left", bbox_to_anchor=(1.01, 0.5))
        ax.grid(alpha=0.3)
    axes[Boundary.ONE_SIDED].set_xlabel("time history, TH (test order within its series)")
    fig.set_layout_engine("tight")
    return fig


def ratio_vs_impacts(e_by_n: pd.DataFrame, min_tests: int = 5) -> Figure:
    """Fig. 11: e_exp / e_an after n impacts, Eqs. 10 and 11.

    Every test by Eq. 11 (thin lines) and the median over the tests that
    reach n impacts, by Eq. 10 and Eq. 11; 1 is e_exp = e_an (Eq. 2 for
    two-sided, Eq. 14 for one-sided rocking, nominal alpha).

    Parameters
    ----------
    e_by_n : pandas.DataFrame
        ``results/e_by_n.csv``.
    min_tests : int
        The medians are drawn while at least this many tests reach n.
    """
    fig, axes = _two_panels()
    for boundary, letter, short in PANELS:
        ax = axes[boundary]
        d = e_by_n[e_by_n.boundary == boundary]
        for _, g in d.groupby("test_id", sort=False):
            ax.plot(g.n, g.e_ratio_eq11, color="0.75", lw=0.4)
        med = d.groupby("n").agg(
            count=("test_id", "size"), eq10=("e_ratio_eq10", "median"), eq11=("e_ratio_eq11", "median")
        )
        med = med[med["count"] >= min_tests]
        ax.plot(med.index, med.eq11, "k-", lw=1.6, label="median, Eq. 11")
        ax.plot(med.index, med.eq10, "C3--", lw=1.2, label="median, Eq. 10")
        ax.axhline(1.0, color="C0", lw=1, label=f"e_an,{short}")
        ax.set_ylabel(f"e_exp / e_an,{short}")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_title(f"Fig. 11{letter} - {short}, {d.test_id.nunique()} tests")
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    axes[Boundary.ONE_SIDED].set_xlabel("number of impacts, n")
    fig.set_layout_engine("tight")
    return fig


def ratio_by_series(tests: pd.DataFrame, series: pd.DataFrame) -> Figure:
    """Fig. 13: e_exp / e_an per test series, identified by h/b.

    Tests as dots, series means with their bootstrap 95 % interval; the
    series flagged as standing apart (``series.stands_apart``) in red.  In
    panel b the colour is the contact depth CD.
    """
    fig, axes = _two_panels(figsize=(9, 8))
    for boundary, letter, short in PANELS:
        ax = axes[boundary]
        s = _series_order(series[series.boundary == boundary])
        x = dict(zip(s.series, range(len(s))))
        d = tests[tests.boundary == boundary]
        for r in s.itertuples():
            if boundary == Boundary.ONE_SIDED:
                color = CD_COLORS.get(r.contact_depth_mm, "k")
            else:
                color = "C3" if getattr(r, "stands_apart", False) in (True, "True") else "k"
            y = d.loc[d.series == r.series, "e_ratio"].to_numpy()
            ax.plot(
                np.full(y.size, x[r.series]) + np.linspace(-0.15, 0.15, y.size), y, ".", color=color, alpha=0.35, ms=4
            )
            err = [[r.e_ratio_mean - r.e_ratio_ci_low], [r.e_ratio_ci_high - r.e_ratio_mean]]
            ax.errorbar(x[r.series], r.e_ratio_mean, yerr=err, fmt="s", color=color, ms=5, capsize=3)
        ax.axhline(1.0, color="0.5", lw=0.8)
        ax.axhline(d.e_ratio.mean(), color="k", ls="--", lw=0.8, label=f"mean of the tests, {d.e_ratio.mean():.3f}")
        if boundary == Boundary.ONE_SIDED:
            for cd, c in CD_COLORS.items():
                ax.plot([], [], "s", color=c, label=f"CD = {cd:g} mm")
        elif s.get("stands_apart", pd.Series(dtype=bool)).eq(True).any():
            ax.plot([], [], "s", color="C3", label="series standing apart (modified z > 3.5)")
        _series_ticks(ax, s)
        ax.set_ylabel(f"e_exp / e_an,{short}")
        ax.set_title(f"Fig. 13{letter} - {short}")
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    fig.set_layout_engine("tight")
    return fig


def series_means(
    series: pd.DataFrame,
    quantity: str,
    ylabel: str,
    fig_label: str,
    references: Sequence[tuple[str, str]] = (),
    lines: Mapping[str, Sequence[tuple[float, str]]] | None = None,
) -> Figure:
    """Figs. 16-19: series means of a per-test quantity with bootstrap 95 % CI.

    Parameters
    ----------
    series : pandas.DataFrame
        ``results/series.csv`` (``<quantity>_mean``, ``_ci_low``, ``_ci_high``).
    quantity : str
        Per-test quantity, e.g. ``"theta0_over_alpha"``.
    ylabel, fig_label : str
        Axis label and figure number ("Fig. 16").
    references : sequence of (str, str)
        Further series-mean quantities drawn as open markers, with labels
        (Fig. 17: Housner's closed forms).
    lines : dict, optional
        Boundary -> sequence of (value, label): horizontal reference lines
        (the paper's values).
    """
    fig, axes = _two_panels(figsize=(9, 8))
    for boundary, letter, short in PANELS:
        ax = axes[boundary]
        s = _series_order(series[series.boundary == boundary])
        x = np.arange(len(s))
        m = s[f"{quantity}_mean"].to_numpy(float)
        err = [m - s[f"{quantity}_ci_low"].to_numpy(float), s[f"{quantity}_ci_high"].to_numpy(float) - m]
        ax.errorbar(x, m, yerr=err, fmt="o", color="k", capsize=3, label="measured, series mean")
        for k, (ref, label) in enumerate(references):
            ax.plot(x, s[f"{ref}_mean"], ["D", "^", "v"][k % 3], mfc="none", color=f"C{k}", label=label)
        for value, label in (lines or {}).get(boundary, ()):
            ax.axhline(value, color="0.4", ls=":", lw=1, label=label)
        _series_ticks(ax, s)
        ax.set_ylabel(ylabel)
        ax.set_title(f"{fig_label}{letter} - {short}")
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    fig.set_layout_engine("tight")
    return fig


def centre_amplification(
    tests: pd.DataFrame,
    ds: xr.Dataset | None = None,
    monitor: tuple[int, np.ndarray, np.ndarray] | None = None,
    t_first_impact: float | None = None,
) -> Figure:
    """Fig. 20: amplification at the centre of the facade (channel 5).

    (a) a one-sided test: the monitor's reading and the one its point would
    have on the rigid-body motion of the test; (b) their ratio of maxima
    after the first impact, test after test, for every one-sided series,
    coloured by contact depth.

    Parameters
    ----------
    tests : pandas.DataFrame
        ``results/tests.csv`` (``centre_amplification``).
    ds : xarray.Dataset, optional
        The sample test (reduced); panel a is left empty without one (a
        campaign without a monitor channel).
    monitor : (int, ndarray, ndarray)
        :func:`rocklab.lab.motion.monitor_readings` of ``ds``.
    t_first_impact : float
        First impact of the sample test [s].
    """
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(9, 7))
    if ds is not None:
        assert monitor is not None and t_first_impact is not None  # they come with the sample test
        ch, measured, rigid = monitor
        t = ds.time.values
        ax1.plot(t, measured, color="k", lw=0.9, label=f"channel {ch}, measured (centre)")
        ax1.plot(t, rigid, "C3--", lw=0.9, label=f"channel {ch} from the rigid-body motion (θ, φ, v, w)")
        ax1.axvline(t_first_impact, color="0.5", lw=0.8, ls=":", label="first impact")
        ax1.set_xlim(t_first_impact - 2.0, min(t[-1], t_first_impact + 4.0))
        ax1.set_title(f"Fig. 20a - test {ds.attrs['test_id']} ({ds.attrs['series']})")
        ax1.legend(fontsize=7)
    else:
        ax1.set_title("Fig. 20a - no one-sided test with a monitor channel")
    ax1.set_xlabel("t [s]")
    ax1.set_ylabel("Δl [mm]")
    d = tests[tests.boundary == Boundary.ONE_SIDED].dropna(subset=["centre_amplification"])
    x0 = 0
    for (cd, _name), g in d.groupby(["contact_depth_mm", "series"], sort=True):
        ax2.plot(x0 + np.arange(len(g)), g.centre_amplification, ".", ms=4, color=CD_COLORS.get(cd, "k"))
        x0 += len(g) + 3
    for cd, g in d.groupby("contact_depth_mm"):
        ax2.plot(
            [],
            [],
            "s",
            color=CD_COLORS.get(cd, "k"),
            label=f"CD = {cd:g} mm: mean {g.centre_amplification.mean():.4f} ({len(g)} tests)",
        )
    ax2.axhline(1.0, color="0.5", lw=0.8)
    ax2.set_xticks([])
    ax2.set_xlabel("one-sided tests, grouped by contact depth and series")
    ax2.set_ylabel("max |Δl| centre / rigid, after the first impact")
    ax2.set_title("Fig. 20b")
    if len(d):
        ax2.legend(fontsize=7)
    fig.set_layout_engine("tight")
    return fig


def fig20_sample(tests: pd.DataFrame) -> str | None:
    """Test of Fig. 20a: the first one-sided test with a monitor reading, or None."""
    d = tests[(tests.boundary == Boundary.ONE_SIDED) & tests.centre_amplification.notna()]
    return next(iter(d.test_id), None)


def dissipation_figures(
    tests: pd.DataFrame, e_by_n: pd.DataFrame, series: pd.DataFrame, sample: xr.Dataset | None = None
) -> dict[str, Figure]:
    """Figs. 10, 11, 13 and 16-20 with the paper's reference values.

    Parameters
    ----------
    tests, e_by_n, series : pandas.DataFrame
        ``results/tests.csv``, ``e_by_n.csv``, ``series.csv``.
    sample : xarray.Dataset, optional
        Reduced test of Fig. 20a (:func:`fig20_sample`).

    Returns
    -------
    dict
        ``"fig10"`` ... ``"fig20"`` -> Figure.
    """
    from rocklab.lab.motion import monitor_readings

    both = tuple(Boundary)
    figs = {
        "fig10": initial_rotation_by_test(tests),
        "fig11": ratio_vs_impacts(e_by_n),
        "fig13": ratio_by_series(tests, series),
        "fig16": series_means(
            series,
            "theta0_over_alpha",
            "θ0 / α",
            "Fig. 16",
            lines={Boundary.TWO_SIDED: [(0.91, "paper, mean 0.91")], Boundary.ONE_SIDED: [(0.73, "paper, mean 0.73")]},
        ),
        "fig17": series_means(
            series,
            "T_quarter_p",
            "p T_1/4",
            "Fig. 17",
            references=[
                ("T_quarter_p_housner", "Housner from rest at θ0/α_fall"),
                ("T_quarter_p_linear", "linearised, with the release speed"),
            ],
            lines={b: [(4.0, "paper: close to or larger than 4")] for b in both},
        ),
        "fig18": series_means(series, "n_cycles", "number of cycles, n", "Fig. 18"),
        "fig19": series_means(series, "duration_p", "p D", "Fig. 19"),
    }
    kw: dict[str, Any] = {}
    if sample is not None:
        t1 = tests.set_index("test_id").t_first_impact[sample.attrs["test_id"]]
        kw = dict(ds=sample, monitor=monitor_readings(sample), t_first_impact=float(t1))
    figs["fig20"] = centre_amplification(tests, **kw)
    return figs
