"""rocklab.plots: the Sect. 3-4 figures build from the dissipation tables."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rocklab.dissipation.statistics import SERIES_COLUMNS, series_stats
from rocklab.plots import dissipation as figures


def tables(one_sided=True):
    """tests.csv, e_by_n.csv and series.csv of a small made-up campaign."""
    rng = np.random.default_rng(0)
    rows, e_rows = [], []
    specs = [("5a-2s", "two-sided", 14.6, np.nan), ("5c-2s", "two-sided", 6.5, np.nan)]
    if one_sided:
        specs += [("2a-1s-cd60", "one-sided", 14.4, 60.0), ("2a-1s-cd260", "one-sided", 14.4, 260.0)]
    for series, boundary, hb, cd in specs:
        for k in range(6):
            tid = f"{series}-{k}"
            two = boundary == "two-sided"
            e = (0.95 if two else 1.2) + 0.01 * rng.standard_normal()
            rows.append(
                dict(
                    test_id=tid,
                    series=series,
                    boundary=boundary,
                    h_over_b=hb,
                    contact_depth_mm=cd,
                    e_ratio=e,
                    theta0_over_alpha=0.9 if two else 0.73,
                    T_quarter_p=6.8,
                    T_quarter_p_housner=7.5,
                    T_quarter_p_linear=6.8,
                    n_cycles=20.0 if two else 1.5,
                    duration_p=40.0 if two else 9.0,
                    centre_amplification=np.nan if two else 1.0 + 1e-4 * k,
                    t_first_impact=2.0,
                )
            )
            n = np.arange(1, 30 if two else 4)
            e_rows.append(
                pd.DataFrame(
                    dict(
                        n=n,
                        e_ratio_eq10=0.95 + 0.001 * n,
                        e_ratio_eq11=0.95 + 0.001 * n,
                        test_id=tid,
                        series=series,
                        boundary=boundary,
                    )
                )
            )
    tests = pd.DataFrame(rows)
    series = series_stats(tests, SERIES_COLUMNS).merge(
        tests.groupby("series")[["boundary", "h_over_b", "contact_depth_mm"]].first().reset_index()
    )
    return tests, pd.concat(e_rows, ignore_index=True), series.assign(stands_apart=False)


@pytest.mark.parametrize("one_sided", [True, False])
def test_every_dissipation_figure_builds_with_both_panels(one_sided):
    tests, e_n, series = tables(one_sided)
    figs = figures.dissipation_figures(tests, e_n, series)
    assert sorted(figs) == ["fig10", "fig11", "fig13", "fig16", "fig17", "fig18", "fig19", "fig20"]
    for name, fig in figs.items():
        assert len(fig.axes) >= 2, name
    # Fig. 13: one series mean per series, on the panel of its boundary condition
    a, b = figs["fig13"].axes[:2]
    assert len(a.get_xticks()) == 2 and len(b.get_xticks()) == (2 if one_sided else 0)
    assert figures.fig20_sample(tests) == ("2a-1s-cd60-0" if one_sided else None)
    figures.plt.close("all")


def test_save_png_writes_what_savefig_lays_out_at_that_dpi(tmp_path):
    """One layout at the file's dpi, the same pixels as savefig's own two draws; the figure closed."""
    from PIL import Image

    from rocklab.plots import save_png

    tests, e_n, series = tables()
    fig = figures.dissipation_figures(tests, e_n, series)["fig16"]
    assert fig.get_layout_engine() is not None  # laid out at every draw
    fig.savefig(tmp_path / "savefig.png", dpi=120)
    fig = figures.dissipation_figures(tests, e_n, series)["fig16"]
    save_png(fig, tmp_path / "save_png.png", dpi=120)
    assert fig.get_layout_engine() is None and not figures.plt.fignum_exists(fig.number)
    a, b = (np.asarray(Image.open(tmp_path / f"{n}.png")) for n in ("savefig", "save_png"))
    assert a.shape == b.shape == (int(fig.get_figheight() * 120), int(fig.get_figwidth() * 120), 4)
    assert np.array_equal(a, b)
    figures.plt.close("all")
