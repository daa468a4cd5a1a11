"""What the dissipation stages publish for the docs (Sects. 3-4, and the campaign-level effects).

Written by the dissipation job from the tables it has just written
(``results/summaries/dissipation.json``) and by the campaign-effects job
(``results/summaries/campaign_level.json``, :mod:`rocklab.summaries`); the
pages ``docs/dissipation.md`` and ``docs/diagnosis.md`` quote them.
"""

from __future__ import annotations

import ast
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import pandas as pd

from rocklab.dissipation.claims import margin_rule
from rocklab.inference.verdicts import ClaimVerdict
from rocklab.lab.hierarchy import MIN_DF, MIN_UNITS_PER_LEVEL
from rocklab.physics.boundary import Boundary
from rocklab.summaries import LAST_DIGIT, Tolerance

#: How far two machines may take the dissipation summary apart: closed-form
#: statistics of the measured motions, seeded bootstrap included, which no
#: floating-point environment moved (bench/environments.py): the last digit kept.
TOLERANCES = {"*": LAST_DIGIT}
#: How far two machines may take the campaign-level numbers apart: they are
#: regressions of the series' fitted parameters (``diagnosis.json``), which
#: carry the fits' tolerance (:data:`rocklab.diagnosis.diagnosis_summary.TOLERANCES`);
#: measured, the Holm p values moved by 2e-6 of themselves.
CAMPAIGN_LEVEL_TOLERANCES = {"*": Tolerance(abs=1e-6, rel=1e-3)}

#: Quantities of ``summary.csv`` the pages quote.
SUMMARY_QUANTITIES = (
    "e_ratio",
    "theta0_over_alpha",
    "T_quarter_p",
    "T_quarter_p_housner",
    "n_cycles",
    "duration_p",
)


def _stats(row: Mapping[str, Any]) -> dict[str, Any]:
    """Mean and 95 % interval (on walls, :func:`rocklab.dissipation.statistics.boundary_summary`) of one row
    of ``summary.csv`` or ``table3.csv``, the units it rests on, and why it has no interval ("" when it has)."""
    note = row["ci_note"]
    return {
        "mean": row["mean"],
        "ci_low": row["ci_low"],
        "ci_high": row["ci_high"],
        "n_tests": row["n_tests"],
        "n_series": row["n_series"],
        "n_walls": row["n_walls"],
        "df": row["df"],
        # an empty note reads back from the CSV as NaN
        "ci_note": note if isinstance(note, str) else "",
    }


def _laws(laws: pd.DataFrame, series: pd.DataFrame) -> dict[str, dict[str, dict[str, Any]]]:
    """Amplitude laws pooled by boundary condition, and the median R² of the
    series' own fits of the peak law."""
    pooled = laws[laws["grouping"] == "boundary"]
    out: dict[str, dict[str, dict[str, Any]]] = {b.key: {} for b in Boundary}
    for r in pooled.itertuples():
        out[Boundary(r.boundary).key][r.law] = {"a": r.a, "b": r.b, "r2": r.r2, "n": r.n}
    per_series = laws[(laws["grouping"] == "series") & (laws["law"] == "peak")]
    # a series whose tests were all rejected has no boundary in series.csv, and no law
    known = series.dropna(subset=["boundary"]).set_index("series")["boundary"]
    boundary = per_series["series"].map(known.map(lambda b: Boundary(b).key))
    for key, r2 in per_series.groupby(boundary)["r2"]:
        out[key].setdefault("peak", {})["series_median_r2"] = r2.median()
    return out


def _level(value: object) -> str:
    """A factor level as text: contact depth 60.0 -> '60', 'clay brick' as is."""
    return f"{value:g}" if isinstance(value, (int, float)) else str(value)


def _effects(effects: pd.DataFrame) -> dict[str, dict[str, Any]]:
    """Kruskal-Wallis tests by boundary and factor, on the units of the factor's level; push/pull by series."""
    out: dict[str, dict[str, Any]] = {"kruskal": {}, "push_pull": {}}
    for r in effects[effects["factor"] != "push/pull"].itertuples():
        levels = ast.literal_eval(r.levels)
        means = ast.literal_eval(r.level_means)
        units = ast.literal_eval(r.n_units)
        out["kruskal"].setdefault(Boundary(r.boundary).key, {})[f"{r.factor}__{r.value}"] = {
            "p": r.p,
            "unit_level": r.unit_level,
            "test": r.test,
            # pairs, not a mapping: the levels keep their order in the sorted file
            "levels": [[_level(k), m, n] for k, m, n in zip(levels, means, units, strict=True)],
        }
    for r in effects[effects["factor"] == "push/pull"].itertuples():
        out["push_pull"].setdefault(r.series, {})[r.value] = {
            "relative_change_pct": 100 * r.relative_change,
            "welch_p": r.welch_p,
            "n_push": r.n_push,
            "n_pull": r.n_pull,
        }
    return out


def dissipation_summary(tables: Mapping[str, str | Path]) -> dict[str, Any]:
    """The boundary summaries, Table 3, the amplitude laws, the effects and the outliers.

    Parameters
    ----------
    tables : mapping
        Paths of the stage's tables as written (``tests``, ``series``, ``laws``,
        ``effects``, ``table3``, ``summary``: the outputs of the rule
        ``dissipation_tables``), read back so that the docs quote what the files hold.

    Returns
    -------
    dict
        Per boundary (``two_sided``, ``one_sided``) the quantities of
        :data:`SUMMARY_QUANTITIES` (mean, 95 % interval on walls, tests, series, walls),
        Table 3 against the paper, the series that stand apart; the fewest walls of an interval, the largest
        difference of Eqs. 10 and 11, the amplitude laws (Eqs. 15, 17) and
        the factors' effects.
    """
    summary, table3, tests, series = (pd.read_csv(tables[k]) for k in ("summary", "table3", "tests", "series"))
    out: dict[str, Any] = {}
    for boundary in Boundary:
        key = boundary.key
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
    # the fewest walls of a t interval (rocklab.lab.hierarchy.too_few_units: MIN_DF residual df)
    out["min_walls_interval"] = MIN_DF + 1
    out["eq10_eq11_max_abs_diff"] = (tests["e_exp_eq10"] - tests["e_exp_eq11"]).abs().max()
    out["amplitude_laws"] = _laws(pd.read_csv(tables["laws"]), series)
    out["effects"] = _effects(pd.read_csv(tables["effects"]))
    return out


def campaign_level_summary(path: str | Path) -> dict[str, Any]:
    """Issue 12, item 2: the paper's campaign-wide statements tested and the effects found.

    Parameters
    ----------
    path : str or pathlib.Path
        ``diagnosis/campaign_effects.csv`` as written by the rule ``campaign_effects``.
    """
    table = pd.read_csv(path, keep_default_na=False, na_values=[""])
    fields = (
        "verdict", "why_not_testable", "estimate", "ci_low", "ci_high", "p", "p_holm", "unit_level", "n_units",
        "n_series", "n_tests", "margin", "term", "claim",
    )  # fmt: skip
    stated = table[table["statement"].fillna("") != ""]
    rest = table[table["statement"].fillna("") == ""]
    judged = rest[rest["verdict"] != ClaimVerdict.NOT_TESTABLE]
    return {
        # the margins by boundary condition and response (rocklab.dissipation.claims.margin_of) and their rule
        "margins": {
            b: g.groupby("response")["margin"].first().to_dict()
            for b, g in table.dropna(subset=["margin"]).groupby("boundary")
        },
        "margin_rule": margin_rule(),
        # the level of the simultaneous intervals of the paper's statements (Bonferroni over the family)
        "statements_verdict_level": stated["verdict_level"].min() if len(stated) else None,
        # what a verdict needs (rocklab.lab.hierarchy)
        "min_units_per_level": MIN_UNITS_PER_LEVEL,
        "min_df": MIN_DF,
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
        "n_supported": int((stated["verdict"] == ClaimVerdict.SUPPORTED).sum()),
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
            for _, r in judged[judged["verdict"] == ClaimVerdict.CONTRADICTED].iterrows()
        ],
    }
