"""The numbers the documentation quotes, read from a results folder.

:func:`extract` reads the outputs of the workflow (``qc.csv``, the
dissipation tables, ``diagnosis.json``, ``limestone_diagnosis.json``, the
map tables, the job benchmarks, when ``make bench`` has run,
``bench/*.json``, and when the target ``shake_table`` has run, its tables)
into one nested dictionary, one section per stage, saved as the numbers
file by :func:`write_numbers`. A quantity that the results do not hold is
``None`` (the pages say "not measured"). The sections listed in
``numbers["volatile"]`` change from run to run (timings) or come from a
target outside ``all``; comparisons of two numbers files leave them out
(:func:`stable`).

Floats are kept to :data:`SIGNIFICANT` significant digits, enough for any
number a page prints, so that the file reads well and compares exactly.
"""

from __future__ import annotations

import ast
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

from rocklab.io import benchmark_times

#: Significant digits kept of every float.
SIGNIFICANT = 6

#: Sections left out of the comparison of two numbers files: those whose values
#: change from run to run (timings) and those of targets outside ``all``
#: (``shake_table``: its data live outside the repository), which the results
#: of ``make run`` do not hold.
VOLATILE = ("performance", "shake_table")

#: The two boundary conditions and their keys in the numbers file.
BOUNDARIES = {"two-sided": "two_sided", "one-sided": "one_sided"}

#: The QC verdicts of ``qc.csv``, valid first.
VERDICTS = (
    "valid",
    "instrument_malfunction",
    "residual_out_of_plumb",
    "disturbed_initial_conditions",
    "unreadable",
)

#: Channel faults as ``qc.csv`` flags name them.
CHANNEL_FLAGS = {
    "spikes_repaired": "spike(s) repaired",
    "dead": " dead",
    "stuck": " stuck from",
    "clipped": " clipped from",
    "dropout": " dropout from",
    "backup_used": "backup ch",
    "in_plane_lost": "in-plane channel lost",
}

#: Quantities of ``summary.csv`` the pages quote.
SUMMARY_QUANTITIES = (
    "e_ratio",
    "theta0_over_alpha",
    "T_quarter_p",
    "T_quarter_p_housner",
    "n_cycles",
    "duration_p",
)


def number(x):
    """A float kept to :data:`SIGNIFICANT` digits, an int as is, NaN as ``None``."""
    if x is None:
        return None
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    x = float(x)
    if not math.isfinite(x):
        return None
    return float(f"{x:.{SIGNIFICANT}g}")


def _tree(x):
    """``x`` with every number passed through :func:`number`."""
    if isinstance(x, dict):
        return {str(k): _tree(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_tree(v) for v in x]
    if isinstance(x, str):
        return x
    return number(x)


def _csv(results: Path, name: str) -> pd.DataFrame:
    return pd.read_csv(results / name)


def _stats(row) -> dict:
    """Mean and 95 % interval of one row of ``summary.csv`` or ``table3.csv``."""
    return {
        "mean": row["mean"],
        "ci_low": row["ci_low"],
        "ci_high": row["ci_high"],
        "n_tests": row["n_tests"],
        "n_series": row["n_series"],
    }


def quality_control(results: Path) -> dict:
    """Verdicts, the margins of the decisions and the channel faults (``qc.csv``)."""
    qc = _csv(results, "qc.csv")
    reason = qc["reject_reason"].fillna("valid")
    flags = qc["flags"].fillna("")
    valid = reason == "valid"

    def span(column, mask, scale=1.0):
        values = scale * qc.loc[mask, column].dropna()
        return {"min": values.min(), "max": values.max()} if len(values) else {"min": None, "max": None}

    series = _csv(results, "series.csv")
    return {
        "n_tests": len(qc),
        "n_series": qc["series"].nunique(),
        "verdicts": {v: int((reason == v).sum()) for v in VERDICTS},
        "release_velocity_pct": {
            "valid": span("release_velocity_ratio", valid, 100),
            "disturbed": span("release_velocity_ratio", reason == "disturbed_initial_conditions", 100),
        },
        "residual_top_mm": {
            "valid_max": span("residual_top_mm", valid)["max"],
            "out_of_plumb_min": span("residual_top_mm", reason == "residual_out_of_plumb")["min"],
        },
        "channel_faults": {k: int(flags.str.contains(v, regex=False).sum()) for k, v in CHANNEL_FLAGS.items()},
        "series": [
            {
                "series": r.series,
                "n_valid": r.n_valid,
                "n_rejected": r.n_rejected,
                "instrument_malfunction": r.rejected_instrument_malfunction,
                "residual_out_of_plumb": r.rejected_residual_out_of_plumb,
                "disturbed_initial_conditions": r.rejected_disturbed_initial_conditions,
            }
            for r in series.itertuples()
        ],
    }


def _laws(laws: pd.DataFrame, series: pd.DataFrame) -> dict:
    """Amplitude laws pooled by boundary condition, and the median R² of the
    series' own fits of the peak law."""
    pooled = laws[laws["grouping"] == "boundary"]
    out = {key: {} for key in BOUNDARIES.values()}
    for r in pooled.itertuples():
        out[BOUNDARIES[r.boundary]][r.law] = {"a": r.a, "b": r.b, "r2": r.r2, "n": r.n}
    per_series = laws[(laws["grouping"] == "series") & (laws["law"] == "peak")]
    boundary = per_series["series"].map(series.set_index("series")["boundary"].map(BOUNDARIES))
    for key, r2 in per_series.groupby(boundary)["r2"]:
        out[key].setdefault("peak", {})["series_median_r2"] = r2.median()
    return out


def _effects(effects: pd.DataFrame) -> dict:
    """Kruskal-Wallis tests by boundary and factor; push/pull by series."""
    out = {"kruskal": {}, "push_pull": {}}
    for r in effects[effects["factor"] != "push/pull"].itertuples():
        levels = ast.literal_eval(r.levels)
        means = ast.literal_eval(r.level_means)
        out["kruskal"].setdefault(BOUNDARIES[r.boundary], {})[f"{r.factor}__{r.value}"] = {
            "p": r.p,
            # pairs, not a mapping: the levels keep their order in the sorted file
            "levels": [[_level(k), m] for k, m in zip(levels, means, strict=True)],
        }
    for r in effects[effects["factor"] == "push/pull"].itertuples():
        out["push_pull"].setdefault(r.series, {})[r.value] = {
            "relative_change_pct": 100 * r.relative_change,
            "welch_p": r.welch_p,
            "n_push": r.n_push,
            "n_pull": r.n_pull,
        }
    return out


def _level(value) -> str:
    """A factor level as text: contact depth 60.0 -> '60', 'clay brick' as is."""
    return f"{value:g}" if isinstance(value, (int, float)) else str(value)


def dissipation(results: Path) -> dict:
    """Sects. 3-4: the boundary summaries, Table 3, amplitude laws, effects, outliers."""
    summary = _csv(results, "summary.csv")
    table3 = _csv(results, "table3.csv")
    tests = _csv(results, "tests.csv")
    series = _csv(results, "series.csv")
    out = {}
    for boundary, key in BOUNDARIES.items():
        rows = summary[summary["boundary"] == boundary].set_index("quantity")
        t = tests[tests["boundary"] == boundary]
        s = series[series["boundary"] == boundary]
        apart = s[s["stands_apart"].astype(bool)]
        kept = t[~t["series"].isin(apart["series"])]
        out[key] = {
            **{q: _stats(rows.loc[q]) for q in SUMMARY_QUANTITIES if q in rows.index},
            "table3": {
                r.column: {**_stats(r._asdict()), "paper": r.paper}
                for r in table3[table3["boundary"] == boundary].itertuples()
            },
            "theta0_over_alpha_fall_mean": t["theta0_over_alpha_fall"].mean(),
            "thetadot_release_median": t["thetadot_release"].median(),
            "centre_amplification": {
                **(_stats(rows.loc["centre_amplification"]) if "centre_amplification" in rows.index else {}),
                # every test, not the series means: how far from rigid any facade went
                "test_min": t["centre_amplification"].min(),
                "test_max": t["centre_amplification"].max(),
            },
            "stands_apart": [
                {"series": r.series, "e_ratio_mean": r.e_ratio_mean, "modified_z": r.modified_z}
                for r in apart.itertuples()
            ],
            "max_abs_modified_z": s["modified_z"].abs().max(),
            "e_ratio_mean_without_apart": kept["e_ratio"].mean() if len(apart) else None,
        }
    out["eq10_eq11_max_abs_diff"] = (tests["e_exp_eq10"] - tests["e_exp_eq11"]).abs().max()
    out["amplitude_laws"] = _laws(_csv(results, "amplitude_laws.csv"), series)
    out["effects"] = _effects(_csv(results, "effects.csv"))
    return out


def _finding(f: dict) -> dict:
    return {
        "params": f["params"],
        "ci95": f["ci95"],
        "range": f.get("evidence", {}).get("range", {}),
        "n_series": f.get("n_series"),
    }


def _stop_gain(series_entries: list[dict]) -> dict | None:
    """Held-out errors of the free run with and without the stop threshold,
    pooled over the series that name it: the root of the test-weighted mean
    of each series' squared rms error."""
    rows = []
    for s in series_entries:
        for f in s["findings"]:
            if f["effect"] == "stop_threshold":
                err, gain = f["error_heldout"], f["gain"]
                rows.append(
                    (
                        s["n_tests"],
                        err["n_impacts_rms"] + gain["n_impacts_rms"],
                        err["n_impacts_rms"],
                        err["duration_pct_rms"] + gain["duration_pct_rms"],
                        err["duration_pct_rms"],
                    )
                )
    if not rows:
        return None
    n, *cols = np.asarray(rows, dtype=float).T

    def pooled(x):
        return math.sqrt(np.sum(n * x**2) / np.sum(n))

    return {
        "n_impacts_rms": {"base": pooled(cols[0]), "model": pooled(cols[1])},
        "duration_pct_rms": {"base": pooled(cols[2]), "model": pooled(cols[3])},
    }


def diagnosis(results: Path) -> dict:
    """The model diagnosis of the campaign by boundary condition and series."""
    entries = json.loads((results / "diagnosis.json").read_text())
    series = [e for e in entries if e["scope"] == "series"]
    out = {"series": [], "n_series": len(series), "n_unexplained": sum(bool(s["unexplained"]) for s in series)}
    out.update({key: None for key in BOUNDARIES.values()})
    for s in series:
        out["series"].append(
            {
                "series": s["key"],
                "boundary": s["boundary"],
                "n_tests": s["n_tests"],
                "verdict": ", ".join(s["verdict"]) or "none",
                "unexplained": bool(s["unexplained"]),
            }
        )
    for e in entries:
        if e["scope"] != "boundary":
            continue
        mine = [s for s in series if s["boundary"] == e["boundary"]]
        out[BOUNDARIES[e["boundary"]]] = {
            "n_tests": e["n_tests"],
            "n_series": e["n_series"],
            "n_impacts": e["n_impacts"],
            "base_model": e["base"]["model"],
            "base": e["base"]["errors"],
            "what_is_wrong": e["what_is_wrong"],
            "verdict": ", ".join(e["verdict"]) or "none",
            "unexplained": bool(e["unexplained"]),
            "findings": {f["effect"]: _finding(f) for f in e["findings"]},
            "heldout": e["heldout"],
            # absent where no series was large enough to extend the model
            "extended": e.get("extended", {}).get("statement"),
            "stop_heldout": _stop_gain(mine),
            "no_stop": [s["key"] for s in mine if "stop_threshold" not in s["verdict"]],
            "minority": [
                {"series": s["key"], "effect": f["effect"], "params": f["params"]}
                for s in mine
                for f in s["findings"]
                if f["effect"] not in e["verdict"]
            ],
        }
    return out


def campaign_level(results: Path) -> dict | None:
    """Issue 12, item 2: the paper's campaign-wide statements tested and the effects found
    (``diagnosis/campaign_effects.csv``); None without the table."""
    path = results / "diagnosis" / "campaign_effects.csv"
    if not path.is_file():
        return None
    table = pd.read_csv(path, keep_default_na=False, na_values=[""])
    fields = ("verdict", "estimate", "ci_low", "ci_high", "p", "n_series", "n_tests", "margin", "term", "claim")
    stated = table[table["statement"].fillna("") != ""]
    rest = table[table["statement"].fillna("") == ""]
    judged = rest[~rest["verdict"].str.startswith("not testable")]
    near = stated[stated["claim"].str.startswith("mean within")]
    return {
        # the relative margin of the verdicts (config diagnosis: campaign_margin)
        "margin_relative": (near["margin"] / near["claimed_value"].abs()).iloc[0] if len(near) else None,
        "order": stated["statement"].tolist(),
        "statements": {
            r["statement"]: {
                **{f: r[f] for f in fields},
                "boundary": r["boundary"],
                "response": r["response"],
                "covariate": r["covariate"],
                "paper": r["paper"],
            }
            for _, r in stated.iterrows()
        },
        "n_statements": len(stated),
        "n_supported": int((stated["verdict"] == "supported").sum()),
        "n_effects": len(rest),
        "n_judged": len(judged),
        "n_not_testable": len(rest) - len(judged),
        "verdicts": {v: int(n) for v, n in judged["verdict"].value_counts().sort_index().items()},
        # the exploratory effects found: the campaign's facts beyond the paper's words
        "found": [
            {
                "boundary": r["boundary"],
                "response": r["response"],
                "covariate": r["covariate"],
                "term": r["term"],
                "estimate": r["estimate"],
                "ci_low": r["ci_low"],
                "ci_high": r["ci_high"],
                "p_holm": r["p_holm"],
                "n_series": r["n_series"],
            }
            for _, r in judged[judged["verdict"] == "contradicted"].iterrows()
        ],
    }


def _family(families: list[dict]) -> dict | None:
    """The first generalised family of the limestone blocks (issue 12): form, parameters, intervals, gains."""
    if not families:
        return None
    f = families[0]
    return {
        "effect": f["effect"],
        "form": f["form"],
        "params": f["params"],
        "ci95": {k: list(v) for k, v in f["ci95"].items()},
        "reduces_to": f["reduces_to"],
        "discovered": f["discovered"],
        "best_listed": f["best_listed"],
        "dbic_vs_base": f["dbic_vs_base"],
        "heldout_gain": f["heldout_gain"],
    }


def limestone(results: Path) -> dict:
    """The restitution diagnosis of the UMinho limestone blocks."""
    d = json.loads((results / "limestone_diagnosis.json").read_text())
    a = d["all"]
    return {
        "source": d["source"],
        "n_tests": a["n_tests"],
        "n_impacts": a["n_impacts"],
        "n_groups": len(d["groups"]),
        "h_over_b": {"min": min(g["h_over_b"] for g in d["groups"]), "max": max(g["h_over_b"] for g in d["groups"])},
        "e_an": a["base"]["e_an"],
        "measured_median_ratio": a["base"]["measured_median_ratio"],
        "what_is_wrong": a["what_is_wrong"],
        "verdict": ", ".join(a["verdict"]) or "none",
        "unexplained": bool(a["unexplained"]),
        "residual_structure": "; ".join(a["residual_structure"]) or "none",
        "rejected": a["rejected"],
        "signatures": a["signatures"],
        "heldout_ratio_rms": {"base": a["heldout"]["base"]["ratio_rms"], "model": a["heldout"]["model"]["ratio_rms"]},
        "slenderness": d["slenderness"],
        "family": _family(a.get("families") or []),
        "groups": [
            {
                "h_over_b": round(g["h_over_b"]),
                "n_tests": g["n_tests"],
                "e_an": g["base"]["e_an"],
                "measured_median_ratio": g["base"]["measured_median_ratio"],
                "verdict": ", ".join(g["verdict"]) or "none",
                "weak": ", ".join(g["weak_evidence"]) or "",
                "ratio_rms_base": g["heldout"]["base"]["ratio_rms"],
                "ratio_rms_model": g["heldout"]["model"]["ratio_rms"],
            }
            for g in d["groups"]
        ],
    }


def _scatter_reductions(summary: pd.DataFrame, baseline: str, model: str) -> dict:
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

    def changes(x):
        return (x["changes_duration"] + x["changes_amplitude"]) / 2

    def reversals(x):
        return (x["reversals_duration"] + x["reversals_amplitude"]) / 2 / x["n_overturned"]

    def bounded(x):
        return changes(x) / np.minimum(x["n_overturned"], x["n_cells"] - x["n_overturned"])

    def reduction(f):
        r = 100 * (1 - f(m) / f(b))
        return {"mean": r.mean(), "min": r.min(), "max": r.max()}

    return {
        "n_records": int(both.sum()),
        "reversals_only": reduction(reversals),
        "by_min_of_overturned_and_standing": reduction(bounded),
        "raw_changes": reduction(changes),
    }


def _record_comparison(comparison: pd.DataFrame) -> dict:
    """Record by record, each comparison of ``comparison.csv`` (the reductions
    against the paper's per-record range) and the Table 4 rows without a
    shipped record."""
    c = comparison.astype({"table4_differences": str, "reason": str}).replace({"nan": ""})
    missing = c[c["table4_match"].isna() & c["table4_row"].notna()].drop_duplicates("table4_row")
    out = {"missing_rows": [f"{int(r.table4_row)} ({r.record})" for r in missing.itertuples()], "by_comparison": {}}
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


def maps(results: Path) -> dict:
    """Sect. 5: the overturning indices of every record and model, the reductions."""
    summary = _csv(results / "maps", "summary.csv")
    reductions = _csv(results / "maps", "reductions.csv")
    records = list(dict.fromkeys(summary["record"]))
    models = list(dict.fromkeys(summary["model"]))
    s = summary.set_index(["record", "model"])
    out = {
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
    out["comparison"] = _record_comparison(_csv(results / "maps", "comparison.csv"))
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


def calibrated(results: Path) -> dict | None:
    """Issue 13, item 4: the calibrated wall on the maps (``maps/calibrated.csv``), per
    boundary (``2s``, ``1s``): the e-alone model, the calibrated wall, each finding
    switched off, and the finding that matters most; None without the table or
    when the diagnosis named no cause (an empty table)."""
    if not (results / "maps" / "calibrated.csv").is_file():
        return None
    table = _csv(results / "maps", "calibrated.csv")
    if table.empty:
        return None
    out = {}
    for boundary, rows in table.groupby("boundary", sort=False):
        e_alone = rows[rows["role"] == "e alone"].iloc[0]
        full = rows[rows["role"] == "calibrated"].iloc[0]
        offs = rows[rows["role"] == "finding off"].sort_values("rank")
        out["2s" if boundary == "two-sided" else "1s"] = {
            "e_alone": {"model": e_alone["model"], "N_O": e_alone["N_O_mean"], "scatter": e_alone["scatter_mean"]},
            "calibrated": {
                "model": full["model"],
                "n_records": full["n_records"],
                "N_O": full["N_O_mean"],
                "scatter": full["scatter_mean"],
                "N_O_change_pct": full["N_O_change_pct"],
                "scatter_change_pct": full["scatter_change_pct"],
            },
            "findings": {
                r["finding_off"]: {
                    "model": r["model"],
                    "N_O": r["N_O_mean"],
                    "scatter": r["scatter_mean"],
                    "N_O_shift": r["N_O_shift"],
                    "N_O_shift_abs": r["N_O_shift_abs"],
                    "rank": r["rank"],
                }
                for _, r in offs.iterrows()
            },
            "matters_most": offs["finding_off"].iloc[0] if len(offs) else None,
        }
    # the grid of the calibrated walls' maps (maps.calibrated_n), the e-alone maps read on it
    first = next(iter(sorted((results / "maps" / "calibrated").glob("*/*.nc"))), None)
    if first is not None:
        with xr.open_dataset(first) as ds:
            out["grid_n"] = int(ds.sizes["amplitude_scale"])
    return out


def _benchmarks(results: Path) -> dict:
    """Job times of the workflow from Snakemake's benchmark files: one entry
    per single-job rule (``<rule>.tsv``) and one per folder of jobs
    (``<folder>/<job>.tsv``, keyed ``<folder>_jobs``)."""
    out = {}
    for job in benchmark_times(results).itertuples():
        rule = f"{job.stage}_jobs" if "/" in job.job else job.stage
        entry = out.setdefault(rule, {"jobs": 0, "total_s": 0.0, "longest_s": 0.0})
        entry["jobs"] += 1
        entry["total_s"] += job.s
        entry["longest_s"] = max(entry["longest_s"], job.s)
    return out


def _bench(results: Path, name: str):
    path = results / "bench" / f"{name}.json"
    return json.loads(path.read_text()) if path.is_file() else None


def _scale(bench: dict) -> dict:
    """The smallest and largest campaign of ``bench/scale.py`` and the line through them."""
    runs = {"small": bench["runs"][0], "large": bench["runs"][-1]}
    keys = {"n_tests": "n_tests", "s": "wall_s", "cpu_s": "cpu_s", "peak_mb": "peak_rss_tree_mb"}
    keys["load"] = "load_avg_1min_before"
    keys["snakemake_cpu_s"] = "snakemake_cpu_s"
    out = {f"{size}_{k}": run.get(key) for size, run in runs.items() for k, key in keys.items()}
    per_test = bench.get("reduce_s_per_test") or [None, None]
    out["small_reduce_s_per_test"], out["large_reduce_s_per_test"] = per_test[0], per_test[-1]
    ten = bench.get("ten_times_embedded") or {}
    cpu_ten = ten.get("cpu_s")
    return {
        "cores": bench["cores"],
        **out,
        "cpu_s_per_test": bench.get("cpu_s_per_test"),
        "memory_ratio": bench.get("memory_ratio"),
        "at_most_linear": bench.get("at_most_linear"),
        "ten_times_n_tests": ten.get("n_tests"),
        "ten_times_cpu_s": cpu_ten,
        "ten_times_wall_s_at_least": cpu_ten / bench["cores"] if cpu_ten is not None else None,
    }


def performance(results: Path) -> dict:
    """Timings: the workflow's job times and, when measured, ``make bench``."""
    jobs = _benchmarks(results)
    out = {
        "jobs": jobs,
        "n_jobs": sum(j["jobs"] for j in jobs.values()),
        "total_job_s": sum(j["total_s"] for j in jobs.values()),
    }
    kin = _bench(results, "kinematics")
    out["kinematics"] = (
        {k: kin[k] for k in ("record", "n_steps", "batched_s", "scipy_loop_s", "ratio", "max_abs_diff_theta_rad")}
        if kin
        else None
    )
    sim = _bench(results, "simulator")
    keys = ("histories", "t_batch_s", "t_reference_s", "speedup", "overturned_batch", "overturned_reference")
    out["simulator"] = (
        {
            **{k: sim[k] for k in keys},
            "mismatches": sim["mismatches"],
            "mismatches_beyond_tolerance": len(sim["mismatches_beyond_tolerance"]),
            "pass": sim["pass"],
        }
        if sim
        else None
    )
    mp = _bench(results, "maps")
    out["maps"] = (
        {
            "map_s": {m: v["map_s"] for m, v in mp["models"].items()},
            **{
                k: mp[k]
                for k in ("reference_s_per_history", "speedup_vs_reference", "all_maps_count", "all_maps_s", "pass")
            },
        }
        if mp
        else None
    )
    wf = _bench(results, "workflow")
    keys = ("cores", "wall_s", "cpu_s", "peak_rss_tree_mb", "load_avg_1min_before", "n_jobs", "job_s")
    keys += ("job_s_over_wall", "snakemake_cpu_s", "target_s", "wall_over_target", "pass", "stages")
    out["workflow"] = {k: wf[k] for k in keys} if wf else None
    fc = _bench(results, "fresh_clone")
    keys = ("cores", "load_before", "install_s", "workflow_s", "total_s", "install_cpu_s", "workflow_cpu_s")
    keys += ("target_total_s", "target_workflow_s", "total_over_target", "workflow_over_target")
    out["fresh_clone"] = {k: fc[k] for k in keys} | {"load_1min": fc["load_before"][0]} if fc else None
    sc = _bench(results, "scale")
    out["scale"] = _scale(sc) if sc else None
    ref = _bench(results, "maps_reference")
    out["maps_reference"] = (
        {
            "records": ref["records"],
            "workers": ref["workers"],
            "total_s": ref["total_s"],
            "complete": ref["complete"],
            "n_maps": len(ref["maps"]),
            "agreement_pct_min": min(m["agreement_pct"] for m in ref["maps"]),
            "n_full_agreement": sum(m["agreement_pct"] == 100 for m in ref["maps"]),
            "off_boundary": sum(m["unexplained"] for m in ref["maps"]),
            "pass": ref["pass"],
        }
        if ref
        else None
    )
    return out


def shake_table(results: Path) -> dict | None:
    """The shake-table outcomes (target ``shake_table``), ``None`` when it was not run."""
    root = results / "shake_table"
    if not (root / "scores.csv").is_file():
        return None
    scores = _csv(root, "scores.csv")
    params = _csv(root, "parameters.csv")
    preds = _csv(root, "predictions.csv")
    errors = _csv(root, "nominal_errors.csv")
    out = {"specimens": sorted(scores.specimen.unique())}
    for s, g in preds.groupby("specimen"):
        obs, nom = g.observed.astype(bool), g.nominal_overturns.astype(bool)
        e = errors[(errors.specimen == s) & (errors.by == "onset_edge")].set_index("bin")
        neither = e.loc["neither edge"] if "neither edge" in e.index else None
        out[s] = {
            "n_tests": len(g),
            "n_ground_motions": g.ground_motion.nunique(),
            "observed_overturns": int(obs.sum()),
            "nominal_overturns": int(nom.sum()),
            "nominal_missed": int((obs & ~nom).sum()),
            "nominal_false_alarms": int((~obs & nom).sum()),
            "min_pga_overturned_g": g.pga_g[obs].min() if obs.any() else None,
            "neither_edge_tests": None if neither is None else int(neither.n_tests),
            "neither_edge_overturns": None if neither is None else int(neither.observed_overturns),
            "scores": {
                r.model: {"accuracy": r.accuracy, "brier": r.brier, "log_loss": r.log_loss, "n_tests": r.n_tests}
                for r in scores[scores.specimen == s].itertuples()
            },
            "parameters": {
                r.parameter: {
                    "value": r.value,
                    "ci_low": r.ci_low,
                    "ci_high": r.ci_high,
                    "null": r.null,
                    "named": bool(r.named),
                    "cause": r.cause,
                }
                for r in params[params.specimen == s].itertuples()
            },
        }
    grids = [xr.load_dataset(path) for path in sorted(root.glob("outcomes_*.nc"))]
    out["n_histories"] = sum(int(ds.attrs["n_histories"]) for ds in grids) if grids else None
    out["grid"] = {k: int(v) for k, v in grids[0].overturned.sizes.items() if k != "test"} if grids else None
    jobs = _benchmarks(results).get("shake_table_jobs")
    out["job_time_s"] = None if jobs is None else jobs["total_s"]
    # wall-clock and CPU time of each job: under a loaded machine the CPU time
    # is the one that compares from run to run
    bench = {
        t.stem: pd.read_csv(t, sep="\t").iloc[0] for t in sorted((results / "benchmarks" / "shake_table").glob("*.tsv"))
    }
    out["job_times_s"] = {k: float(b["s"]) for k, b in bench.items()}
    out["job_cpu_s"] = {k: float(b["cpu_time"]) for k, b in bench.items()}
    out["job_cpu_total_s"] = sum(out["job_cpu_s"].values()) if bench else None
    return out


#: One section of the numbers file per stage, and the function that reads it.
SECTIONS = {
    "quality_control": quality_control,
    "dissipation": dissipation,
    "diagnosis": diagnosis,
    "limestone": limestone,
    "campaign_level": campaign_level,
    "maps": maps,
    "calibrated": calibrated,
    "performance": performance,
    "shake_table": shake_table,
}


def extract(results_dir) -> dict:
    """Every number the documentation quotes, read from ``results_dir``.

    Returns a dictionary with one section per stage (:data:`SECTIONS`) and
    ``volatile``, the sections that change from run to run.
    """
    results = Path(results_dir)
    return {"volatile": list(VOLATILE), **{name: _tree(read(results)) for name, read in SECTIONS.items()}}


def stable(numbers: dict) -> dict:
    """``numbers`` without its volatile sections: what two runs must agree on."""
    return {k: v for k, v in numbers.items() if k not in numbers.get("volatile", ()) and k != "volatile"}


def dumps(numbers: dict) -> str:
    """The numbers file's text: sorted keys, so that a change shows as a diff."""
    return json.dumps(numbers, indent=1, sort_keys=True, ensure_ascii=False) + "\n"


def write_numbers(numbers: dict, path) -> None:
    Path(path).write_text(dumps(numbers))


def read_numbers(path) -> dict:
    return json.loads(Path(path).read_text())
