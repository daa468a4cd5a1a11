"""The overturning maps against the paper (Sect. 5): the reductions it reports, record by record and over records.

The paper compares maps of one record under two walls (:data:`COMPARISONS`)
through the per-record reductions of their indices
(:func:`rocklab.seismic.reductions.record_reductions` of the
:func:`rocklab.seismic.indices.summary_table`); it reports their statistics
over its records (:data:`PAPER_REDUCTIONS`).  :func:`reductions` computes
those statistics (``results/maps/reductions.csv``), :func:`record_comparison`
sets each record's reduction against the paper's range and its Table 4 row
(``results/maps/comparison.csv``).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np
import pandas as pd

from rocklab.seismic.reductions import record_reductions

#: Pairs (baseline, model) compared record by record (Sect. 5).
COMPARISONS = (("2s-housner", "2s-0.95"), ("1s-zero", "1s-1.05"), ("1s-1.05", "1s-eq17"))

#: What the paper reports for a comparison: (baseline, model, index) -> {statistic: %}.
PAPER_REDUCTIONS = {
    ("2s-housner", "2s-0.95", "N_O"): {"mean": 25.0, "min": 3.0, "max": 89.0},
    ("2s-housner", "2s-0.95", "scatter"): {"mean": 43.0},
}


def reductions(
    summary: pd.DataFrame,
    comparisons: Iterable[tuple[str, str]] = COMPARISONS,
    subsets: Mapping[str, Iterable[str]] | None = None,
) -> pd.DataFrame:
    """Mean, min and max over records of the per-record reductions (Sect. 5).

    The paper reports, from e_an,2s to 0.95 e_an,2s over its 20 records, an
    N_O reduction of 25 % on average (3 % min, 89 % max) and a scatter
    reduction of 43 % on average: statistics over maps of the per-map
    reduction (:func:`rocklab.seismic.reductions.record_reductions`), as computed here.

    Parameters
    ----------
    summary : pandas.DataFrame
        :func:`rocklab.seismic.indices.summary_table`.
    comparisons : sequence of (baseline, model)
        Default :data:`COMPARISONS`; pairs missing from ``summary`` are skipped.
    subsets : dict of str to iterable of str, optional
        Named sets of records to summarise as well (e.g. the records that
        match Table 4); every record of ``summary`` is always summarised,
        as subset ``"all"``.

    Returns
    -------
    pandas.DataFrame
        records (subset name), baseline, model, index (N_O | scatter),
        statistic (mean | min | max), reduction_pct, n_records (records
        where it is defined), paper_pct.
    """
    rows = []
    present = set(summary["model"])
    groups = {"all": list(dict.fromkeys(summary["record"])), **{k: list(v) for k, v in (subsets or {}).items()}}
    for baseline, model in comparisons:
        if not {baseline, model} <= present:
            continue
        red = record_reductions(summary, baseline, model)
        for group, records in groups.items():
            for index in ("N_O", "scatter"):
                values = red[index].reindex(records).dropna()
                paper = PAPER_REDUCTIONS.get((baseline, model, index), {})
                for stat in ("mean", "min", "max"):
                    rows.append(
                        {
                            "records": group,
                            "baseline": baseline,
                            "model": model,
                            "index": index,
                            "statistic": stat,
                            "reduction_pct": getattr(values, stat)() if len(values) else np.nan,
                            "n_records": int(len(values)),
                            "paper_pct": paper.get(stat, np.nan),
                        }
                    )
    return pd.DataFrame(
        rows, columns=["records", "baseline", "model", "index", "statistic", "reduction_pct", "n_records", "paper_pct"]
    )


#: Records summarised apart in :func:`reductions`: those of Table 4's station and
#: component whose PGA and PGV match Table 4 (:func:`rocklab.seismic.accelerograms.table4_agreement`).
TABLE4_SUBSET = "table4_pga_pgv"

#: Columns of :func:`record_comparison`.
COMPARISON_COLUMNS = [
    "table4_row",
    "record",
    "baseline",
    "model",
    "N_O_baseline",
    "N_O_model",
    "N_O_reduction_pct",
    "scatter_baseline",
    "scatter_model",
    "scatter_reduction_pct",
    "paper_min_pct",
    "paper_max_pct",
    "in_paper_range",
    "table4_match",
    "table4_differences",
    "reason",
]


def _in_paper_range(reduction: float, paper: Mapping[str, float]) -> bool:
    """True if ``reduction`` [%] rounds into the paper's range (it prints whole percents)."""
    return bool(paper["min"] - 0.5 <= reduction < paper["max"] + 0.5)


def _comparison_reason(row: Mapping[str, Any], paper: Mapping[str, float]) -> str:
    """Why a record's reduction is undefined or outside the paper's per-record range (empty if it is not)."""
    base, new, red = row["N_O_baseline"], row["N_O_model"], row["N_O_reduction_pct"]
    b, m = row["baseline"], row["model"]
    if pd.isna(base):
        return "no map of this record in the run" if row["table4_match"] is not None else "no record of this row"
    if base == 0:
        return f"no overturning with {b}: reduction undefined"
    words = []
    if new == 0:
        words.append(f"every overturning of {b} removed (N_O {base:.3f} -> 0)")
    elif red < 0:
        words.append(f"more overturnings with {m}")
    if paper and not _in_paper_range(red, paper):
        side = "below the paper's smallest" if red < paper["min"] else "above the paper's largest"
        words.append(f"{side} reduction")
        if base >= 0.9:
            words.append(f"the wall falls in {100 * base:.0f} % of the {b} map, few cells are left to stand")
        elif base < 0.1:
            words.append(f"only {100 * base:.0f} % of the {b} map overturns, in thin bands")
        if row["table4_differences"]:
            words.append(f"record differs from Table 4: {row['table4_differences']}")
    return "; ".join(words)


def record_comparison(
    summary: pd.DataFrame,
    agreement: pd.DataFrame | None = None,
    table4: pd.DataFrame | None = None,
    comparisons: Iterable[tuple[str, str]] = COMPARISONS,
) -> pd.DataFrame:
    """Record by record: each comparison's reductions beside Table 4 and the paper's range.

    The paper gives no per-record value in its text (Fig. 22 shows them as
    bars); it gives, for e_an,2s -> 0.95 e_an,2s, the range of the per-record
    N_O reduction, 3 % to 89 % (:data:`PAPER_REDUCTIONS`), in whole percents,
    so a reduction is within it when it rounds into it (2.5 % to 89.5 %).
    Each record's reduction is set against that range, with the record's
    agreement with its Table 4 row, and the reason where the reduction is
    undefined or out of the range.

    Parameters
    ----------
    summary : pandas.DataFrame
        :func:`rocklab.seismic.indices.summary_table`.
    agreement : pandas.DataFrame, optional
        :func:`rocklab.seismic.accelerograms.table4_agreement` (default: of
        the shipped records).
    table4 : pandas.DataFrame, optional
        :func:`rocklab.seismic.accelerograms.read_table4` (default: the
        paper's).
    comparisons : sequence of (baseline, model)
        Default :data:`COMPARISONS`; pairs missing from ``summary`` are skipped.

    Returns
    -------
    pandas.DataFrame
        :data:`COMPARISON_COLUMNS`, one row per comparison and Table 4 row
        (rows without a shipped record have no indices), then the records of
        ``summary`` that are not Table 4's (no ``table4_row``).
        ``in_paper_range`` is empty where the paper gives no range or the
        reduction is undefined.
    """
    from rocklab.seismic.accelerograms import read_table4, table4_agreement

    agreement = table4_agreement() if agreement is None else agreement
    table4 = read_table4() if table4 is None else table4
    present = set(summary["model"])
    s = summary.set_index(["record", "model"])
    records: list[tuple[int | None, str]] = [(int(r.row), r.record) for r in table4.itertuples()]
    records += [(None, r) for r in dict.fromkeys(summary["record"]) if r not in set(table4["record"])]
    rows = []
    for baseline, model in comparisons:
        if not {baseline, model} <= present:
            continue
        red = record_reductions(summary, baseline, model)
        paper = PAPER_REDUCTIONS.get((baseline, model, "N_O"), {})
        paper = paper if {"min", "max"} <= set(paper) else {}
        for t4_row, record in records:
            shipped = (record, baseline) in s.index and (record, model) in s.index
            known = record in agreement.index
            row: dict[str, Any] = {
                "table4_row": t4_row,
                "record": record,
                "baseline": baseline,
                "model": model,
                "N_O_baseline": s.loc[(record, baseline), "N_O"] if shipped else np.nan,
                "N_O_model": s.loc[(record, model), "N_O"] if shipped else np.nan,
                "N_O_reduction_pct": red.loc[record, "N_O"] if shipped else np.nan,
                "scatter_baseline": s.loc[(record, baseline), "scatter"] if shipped else np.nan,
                "scatter_model": s.loc[(record, model), "scatter"] if shipped else np.nan,
                "scatter_reduction_pct": red.loc[record, "scatter"] if shipped else np.nan,
                "paper_min_pct": paper.get("min", np.nan),
                "paper_max_pct": paper.get("max", np.nan),
                "table4_match": bool(agreement.loc[record, "pga_pgv_match"]) if known else None,
                "table4_differences": agreement.loc[record, "differences"] if known else "",
            }
            defined = not pd.isna(row["N_O_reduction_pct"])
            row["in_paper_range"] = _in_paper_range(row["N_O_reduction_pct"], paper) if paper and defined else None
            row["reason"] = _comparison_reason(row, paper)
            rows.append(row)
    out = pd.DataFrame(rows, columns=COMPARISON_COLUMNS)
    # integers with gaps for the records that are not Table 4's (a float column would write "1.0")
    out["table4_row"] = pd.Series([r["table4_row"] for r in rows], index=out.index, dtype=object)
    return out
