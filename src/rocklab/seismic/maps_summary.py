"""What the map stages publish for the docs (Sect. 5): the indices of every map and of the calibrated walls.

Written by the map-summary job (``results/summaries/maps.json``) and the
calibrated-map job (``results/summaries/calibrated.json``) from the tables
they have just written (:mod:`rocklab.summaries`); the page
``docs/seismic-maps.md`` quotes them.

A map index is not a number that two machines reproduce digit for digit.
The cells of a map next to the boundary between overturning and standing
lie on a chaotic boundary: the history of such a cell turns on the last
bits of its floating-point arithmetic, so the cell flips with the machine
(the calibrated walls' mean N_O read 0.596853 on one machine and 0.596816
on another, some four cells of a 101 x 101 map per record). :data:`TOLERANCES`
states how far apart two runs may take each index:
:data:`rocklab.seismic.indices.FLIPPED_FRACTION` of a map's cells, and what
that does to the quantities made of the indices. Measured between four
floating-point environments (``bench/environments.py``, docs/reproducibility.md):
one cell of a paper's map (N_O 2.5e-5, its scatter 2.7e-4, a record's scatter
reduction 2.9 points where nearly every cell overturns), some eight of the
calibrated walls' sixteen maps; every move within a fifth of its tolerance.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pandas as pd

from rocklab.disk import StrPath
from rocklab.physics.boundary import Boundary
from rocklab.seismic.indices import FLIPPED_FRACTION
from rocklab.summaries import Tolerance

#: Share of the cells that overturn on a typical map, and the typical scatter
#: (changes per overturned cell) and N_O of e alone, by which the tolerances
#: of the derived quantities are scaled.
_OVERTURNED, _SCATTER, _N_O = 0.5, 0.2, 0.3

#: Absolute tolerance of each map index (dotted paths within a summary,
#: :func:`rocklab.summaries.tolerance`): N_O by the flipped fraction; the
#: scatter by the changes a flipped cell can make (two: the count is the mean
#: of the two axes', on each of which a cell has two neighbours), over the
#: overturned cells; a shift of N_O between two maps by the
#: flips of both; a change or reduction (%) from one model to another, of a
#: record or of their mean, minimum or maximum over the records, by those of
#: its two indices (the scatter's under every normalisation: the reversals
#: alone, the smaller of overturned and standing, the raw count); the range
#: of the calibrated walls' N_O as N_O. The paper's own numbers (``paper_*``)
#: take the same tolerance; they never move.
#:
#: A change p = 100 (1 - r) of the ratio r of two indices moves by
#: (100 - p) dr/r, with dr/r the sum of the two indices' relative moves
#: (``k`` below, at a typical map): at most 100 k + k |p|. The relative part
#: matters where the baseline is small (a change of -700 %); below the typical
#: N_O of 0.3 the bound rests on the flipped fraction's margin over what was
#: measured (one cell of eighty allowed).
_K_N_O = 2 * FLIPPED_FRACTION / _N_O
_K_SCATTER = 2 * (2 * FLIPPED_FRACTION / _OVERTURNED) / _SCATTER
_N_O_PCT = Tolerance(abs=100 * _K_N_O, rel=_K_N_O)
_SCATTER_PCT = Tolerance(abs=100 * _K_SCATTER, rel=_K_SCATTER)
TOLERANCES = {
    "*.N_O": Tolerance(abs=FLIPPED_FRACTION),
    "*.N_O_baseline": Tolerance(abs=FLIPPED_FRACTION),
    "*.N_O_model": Tolerance(abs=FLIPPED_FRACTION),
    "*.N_O_low": Tolerance(abs=FLIPPED_FRACTION),
    "*.N_O_high": Tolerance(abs=FLIPPED_FRACTION),
    "*.scatter": Tolerance(abs=2 * FLIPPED_FRACTION / _OVERTURNED),
    "*.N_O_shift": Tolerance(abs=2 * FLIPPED_FRACTION),
    "*.N_O_shift_abs": Tolerance(abs=2 * FLIPPED_FRACTION),
    "*.N_O_change_pct": _N_O_PCT,
    "*.N_O_reduction_pct": _N_O_PCT,
    "reductions*.N_O.*": _N_O_PCT,
    "*.scatter_change_pct": _SCATTER_PCT,
    "*.scatter_reduction_pct": _SCATTER_PCT,
    "reductions*.scatter.*": _SCATTER_PCT,
    "scatter_2s.*": _SCATTER_PCT,
}


def _scatter_reductions(summary: pd.DataFrame, baseline: str, model: str) -> dict[str, Any]:
    """Reductions (%) of the map scatter from ``baseline`` to ``model`` under
    two other normalisations of the changes than the paper's (by the number
    of overturnings): the reversals only (overturning to standing as the
    scale grows), and by the smaller of the overturned and standing cells;
    and of the raw count of changes. Over the records where both maps
    overturn (where the scatter is defined)."""
    s = summary.set_index(["record", "model"])
    b, m = s.xs(baseline, level="model"), s.xs(model, level="model")
    both = (b["n_overturned"] > 0) & (m["n_overturned"] > 0)
    b, m = b[both], m[both]

    def changes(x: pd.DataFrame) -> pd.Series:
        return (x["changes_duration"] + x["changes_amplitude"]) / 2

    def reversals(x: pd.DataFrame) -> pd.Series:
        return (x["reversals_duration"] + x["reversals_amplitude"]) / 2 / x["n_overturned"]

    def bounded(x: pd.DataFrame) -> pd.Series:
        return changes(x) / np.minimum(x["n_overturned"], x["n_cells"] - x["n_overturned"])

    def reduction(f: Callable[[pd.DataFrame], pd.Series]) -> dict[str, float]:
        r = 100 * (1 - f(m) / f(b))
        return {"mean": r.mean(), "min": r.min(), "max": r.max()}

    return {
        "n_records": int(both.sum()),
        "reversals_only": reduction(reversals),
        "by_min_of_overturned_and_standing": reduction(bounded),
        "raw_changes": reduction(changes),
    }


def _record_comparison(comparison: pd.DataFrame) -> dict[str, Any]:
    """Record by record, each comparison of ``comparison.csv`` (the reductions
    against the paper's per-record range) and the Table 4 rows without a
    shipped record."""
    c = comparison.astype({"table4_differences": str, "reason": str}).replace({"nan": ""})
    missing = c[c["table4_match"].isna() & c["table4_row"].notna()].drop_duplicates("table4_row")
    out: dict[str, Any] = {
        "missing_rows": [f"{int(r.table4_row)} ({r.record})" for r in missing.itertuples()],
        "by_comparison": {},
    }
    for (baseline, model), rows in c.groupby(["baseline", "model"], sort=False):
        mapped = rows[rows["N_O_baseline"].notna()]
        defined = mapped[mapped["in_paper_range"].notna()]
        out["by_comparison"][f"{baseline}__{model}"] = {
            "records": [
                {
                    "row": None if pd.isna(r.table4_row) else int(r.table4_row),
                    "record": r.record,
                    "N_O_baseline": r.N_O_baseline,
                    "N_O_model": r.N_O_model,
                    "N_O_reduction_pct": r.N_O_reduction_pct,
                    "scatter_reduction_pct": r.scatter_reduction_pct,
                    "in_paper_range": None if pd.isna(r.in_paper_range) else bool(r.in_paper_range),
                    "table4_match": None if pd.isna(r.table4_match) else bool(r.table4_match),
                    "table4_differences": r.table4_differences,
                    "reason": r.reason,
                }
                for r in mapped.itertuples()
            ],
            "n_in_paper_range": int(defined["in_paper_range"].astype(bool).sum()),
            "n_with_paper_range": len(defined),
            "out_of_paper_range": [r.record for r in defined.itertuples() if not bool(r.in_paper_range)],
        }
    return out


def maps_summary(summary_csv: StrPath, reductions_csv: StrPath, comparison_csv: StrPath) -> dict[str, Any]:
    """Sect. 5: the overturning indices of every record and model, the reductions.

    Parameters
    ----------
    summary_csv, reductions_csv, comparison_csv : str or pathlib.Path
        ``maps/summary.csv``, ``maps/reductions.csv`` and ``maps/comparison.csv``
        as written by the rule ``map_summary``.
    """
    summary = pd.read_csv(summary_csv)
    reductions = pd.read_csv(reductions_csv)
    records = list(dict.fromkeys(summary["record"]))
    models = list(dict.fromkeys(summary["model"]))
    s = summary.set_index(["record", "model"])
    out: dict[str, Any] = {
        "models": models,
        "records": records,
        "n_cells": s["n_cells"].iloc[0] if len(s) else None,
        "by_record": {
            rec: {m: {"N_O": row.N_O, "scatter": row.scatter} for (_, m), row in s.loc[[rec]].iterrows()}
            for rec in records
        },
        "reductions": {},
    }
    # the statistics over every record under "reductions", over a subset under "reductions_<subset>"
    for r in reductions.itertuples():
        section = "reductions" if r.records == "all" else f"reductions_{r.records}"
        entry = out.setdefault(section, {}).setdefault(f"{r.baseline}__{r.model}", {})
        entry.setdefault(r.index, {"n_records": r.n_records})[r.statistic] = r.reduction_pct
        if not pd.isna(r.paper_pct):
            entry[r.index][f"paper_{r.statistic}"] = r.paper_pct
    out["comparison"] = _record_comparison(pd.read_csv(comparison_csv))
    if {"2s-housner", "2s-0.95"} <= set(models):
        out["scatter_2s"] = _scatter_reductions(summary, "2s-housner", "2s-0.95")
        n_o = s["N_O"].unstack("model")
        low = n_o["2s-housner"].idxmin()
        out["weakest_2s_record"] = {"record": low, "N_O": n_o.loc[low, "2s-housner"]}
    if {"1s-zero", "1s-1.05"} <= set(models):
        n_o = s["N_O"].unstack("model")
        out["one_sided"] = {
            "n_records": len(records),
            "n_zero_at_most_1.05": int((n_o["1s-zero"] <= n_o["1s-1.05"]).sum()),
            "only_with_1.05": [r for r in records if n_o.loc[r, "1s-zero"] == 0 < n_o.loc[r, "1s-1.05"]],
        }
    return out


def calibrated_summary(path: StrPath, grid_n: int) -> dict[str, Any] | None:
    """Issue 13, item 4: the calibrated wall on the maps, per boundary (``2s``, ``1s``).

    Parameters
    ----------
    path : str or pathlib.Path
        ``maps/calibrated.csv`` as written by the rule ``calibrated_map_changes``.
    grid_n : int
        Values of each axis of the calibrated walls' maps (``maps.calibrated_n``),
        on which the e-alone maps are read.

    Returns
    -------
    dict or None
        The e-alone model, the calibrated wall, each finding switched off and the
        finding that matters most; None when the diagnosis named no cause (an
        empty table).
    """
    table = pd.read_csv(path)
    if table.empty:
        return None
    out: dict[str, Any] = {}
    for boundary, rows in table.groupby("boundary", sort=False):
        e_alone = rows[rows["role"] == "e alone"].iloc[0]
        full = rows[rows["role"] == "calibrated"].iloc[0]
        sizes = rows[rows["role"] == "absolute sizes"]
        offs = rows[rows["role"] == "finding off"].sort_values("rank")
        out["2s" if boundary == Boundary.TWO_SIDED else "1s"] = {
            "e_alone": {"model": e_alone["model"], "N_O": e_alone["N_O_mean"], "scatter": e_alone["scatter_mean"]},
            "calibrated": {
                "model": full["model"],
                "n_records": full["n_records"],
                "N_O": full["N_O_mean"],
                "scatter": full["scatter_mean"],
                "N_O_change_pct": full["N_O_change_pct"],
                "scatter_change_pct": full["scatter_change_pct"],
                # the range of N_O over the two transfer assumptions (ratios, absolute sizes)
                "N_O_low": full["N_O_low"],
                "N_O_high": full["N_O_high"],
            },
            "sizes": (
                {
                    "model": sizes["model"].iloc[0],
                    "N_O": sizes["N_O_mean"].iloc[0],
                    "scatter": sizes["scatter_mean"].iloc[0],
                }
                if len(sizes)
                else None
            ),
            "findings": {
                r["finding_off"]: {
                    "model": r["model"],
                    "N_O": r["N_O_mean"],
                    "scatter": r["scatter_mean"],
                    "N_O_shift": r["N_O_shift"],
                    "N_O_shift_abs": r["N_O_shift_abs"],
                    "rank": int(r["rank"]),
                }
                for _, r in offs.iterrows()
            },
            # findings that share the first rank all matter most
            "matters_most": " and ".join(offs["finding_off"][offs["rank"] == 1]) if len(offs) else None,
        }
    out["grid_n"] = grid_n
    return out
