"""The markdown tables of the documentation pages, made from the numbers file.

A template places one with ``{{ table("name") }}`` (:data:`TABLES`,
:mod:`rocklab.report.pages`); each takes the numbers file (every stage's
summary, one section each) and returns the table's markdown.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from typing import Any, Concatenate, ParamSpec

import pandas as pd

from rocklab.dissipation.statistics import TABLE3_WINDOWS, table3_markdown
from rocklab.lab.hierarchy import plural
from rocklab.lab.validity import Verdict
from rocklab.physics.boundary import Boundary
from rocklab.report.environments import environment_moves, environment_sections
from rocklab.report.format import NOT_MEASURED, markdown_table, show

#: The rejections of a series' row (an unreadable test belongs to no series).
SERIES_REJECTIONS = (
    Verdict.INSTRUMENT_MALFUNCTION,
    Verdict.RESIDUAL_OUT_OF_PLUMB,
    Verdict.DISTURBED_INITIAL_CONDITIONS,
)


#: The arguments of a table after the numbers file (the boundary condition of :func:`findings`).
P = ParamSpec("P")


def _of(
    section: str,
) -> Callable[[Callable[Concatenate[Mapping[str, Any], P], str]], Callable[Concatenate[Mapping[str, Any], P], str]]:
    """A table of the numbers file that reads "not measured." where its stage,
    ``section``, did not run (no summary)."""

    def decorate(
        table: Callable[Concatenate[Mapping[str, Any], P], str],
    ) -> Callable[Concatenate[Mapping[str, Any], P], str]:
        @functools.wraps(table)
        def wrapped(n: Mapping[str, Any], *args: P.args, **kwargs: P.kwargs) -> str:
            return NOT_MEASURED + "." if n.get(section) is None else table(n, *args, **kwargs)

        return wrapped

    return decorate


@_of("quality_control")
def qc_series(n: Mapping[str, Any]) -> str:
    """Verdicts of every series (``series.csv``)."""
    rows = [
        [
            s["series"],
            show(s["n_valid"]),
            show(s["n_rejected"]),
            *(show(s[v]) for v in SERIES_REJECTIONS),
        ]
        for s in n["quality_control"]["series"]
    ]
    header = ["series", "valid", "rejected", *(v.value for v in SERIES_REJECTIONS)]
    return markdown_table(header, rows)


@_of("dissipation")
def table3(n: Mapping[str, Any]) -> str:
    """Table 3 of the paper from the page's numbers, as results/table3.md has it
    (:func:`rocklab.dissipation.statistics.table3_markdown`, the one rendering of the table)."""
    rows = [
        {"boundary": str(b), "column": column, "window": TABLE3_WINDOWS[column], **stats}
        for b in (Boundary.ONE_SIDED, Boundary.TWO_SIDED)
        for column, stats in (n["dissipation"][b.key]["table3"] or {}).items()
    ]
    if not rows:
        return "No valid test."
    return table3_markdown(pd.DataFrame(rows).astype({"paper": float}))


@_of("dissipation")
def stands_apart(n: Mapping[str, Any]) -> str:
    """Series whose mean e_exp/e_an stands apart within their boundary condition."""
    rows = [
        [name, s["series"], show(s["e_ratio_mean"], ".3f"), show(s["modified_z"], ".1f")]
        for key, name in (("two_sided", Boundary.TWO_SIDED), ("one_sided", Boundary.ONE_SIDED))
        for s in n["dissipation"][key]["stands_apart"]
    ]
    return markdown_table(["boundary", "series", "e_exp/e_an", "modified z"], rows) if rows else "None."


@_of("dissipation")
def effects(n: Mapping[str, Any]) -> str:
    """Kruskal-Wallis tests of the means of the factor's units by level (``effects.csv``)."""
    rows = [
        [
            name,
            test.split("__")[0],
            test.split("__")[1],
            ", ".join(
                f"{level}: {show(mean, '.6g')} ({plural(e['unit_level'], units)})" for level, mean, units in e["levels"]
            ),
            show(e["p"], ".2f") if e["p"] is not None else e["test"],
        ]
        for key, name in (("two_sided", Boundary.TWO_SIDED), ("one_sided", Boundary.ONE_SIDED))
        for test, e in n["dissipation"]["effects"]["kruskal"].get(key, {}).items()
    ]
    return markdown_table(["boundary", "factor", "quantity", "means by level (units)", "p"], rows)


@_of("dissipation")
def push_pull(n: Mapping[str, Any]) -> str:
    """Pushed against pulled tests of the series released both ways."""
    rows = [
        [
            series,
            quantity,
            f"{show(e['n_push'], '.0f')} / {show(e['n_pull'], '.0f')}",
            show(e["relative_change_pct"], ".3g"),
            show(e["welch_p"], ".2g"),
        ]
        for series, by in n["dissipation"]["effects"]["push_pull"].items()
        for quantity, e in by.items()
    ]
    header = ["series", "quantity", "tests pushed / pulled", "change by pulling (%)", "Welch p"]
    return markdown_table(header, rows) if rows else "No series was released both ways."


@_of("diagnosis")
def findings(n: Mapping[str, Any], boundary: str) -> str:
    """The causes named for one boundary condition, with their parameters."""
    d = n["diagnosis"][boundary]
    if d is None:
        return NOT_MEASURED + "."
    rows = []
    for effect, f in d["findings"].items():
        for param, value in f["params"].items():
            ci = f["ci95"].get(param) or [None, None]
            span = f["range"].get(param) or [None, None]
            rows.append(
                [
                    f"`{effect}`",
                    param,
                    f"{show(value, '.4g')} [{show(ci[0], '.4g')}, {show(ci[1], '.4g')}]",
                    f"{show(span[0], '.4g')}-{show(span[1], '.4g')}",
                    f"{show(f['n_series'])} of {show(d['n_series'])}",
                    # a summary written before the pool listed the series it left out did not measure it
                    ("; ".join(f["left_out"]) or "none") if "left_out" in f else show(None),
                ]
            )
    return markdown_table(["cause", "parameter", "value [95 % CI]", "range over series", "named in", "left out"], rows)


@_of("diagnosis")
def minority(n: Mapping[str, Any], boundary: str) -> str:
    """Causes named in fewer than half of the series of a boundary condition."""
    if n["diagnosis"][boundary] is None:
        return NOT_MEASURED + "."
    rows = [
        [f"`{m['effect']}`", m["series"], "; ".join(f"{k} = {show(v, '.4g')}" for k, v in m["params"].items())]
        for m in n["diagnosis"][boundary]["minority"]
    ]
    return markdown_table(["cause", "series", "parameters"], rows) if rows else "None."


@_of("diagnosis")
def diagnosis_series(n: Mapping[str, Any]) -> str:
    """The verdict of every series."""
    rows = [
        [s["series"], s["boundary"], show(s["n_tests"]), s["verdict"], show(s["unexplained"])]
        for s in n["diagnosis"]["series"]
    ]
    return markdown_table(["series", "boundary", "tests", "causes named", "unexplained"], rows)


@_of("diagnosis")
def series_changes(n: Mapping[str, Any]) -> str:
    """The parameters that change over the tests of their series: where, how much, and what the pool made
    of each."""
    # a summary written before the series were tested for changes did not measure them
    if "changes" not in n["diagnosis"]:
        return NOT_MEASURED + "."

    def row(c: Mapping[str, Any]) -> list[str]:
        lo, hi = c["ci95_size"] or (None, None)
        return [
            c["series"],
            f"`{c['effect']}`",
            c["parameter"],
            c["kind"] + (f" at test {c['where_test']}" if c["where_test"] else ""),
            f"{show(c['before'], '.4g')} → {show(c['after'], '.4g')}",
            f"{show(c['size'], '.3g')} [{show(lo, '.3g')}, {show(hi, '.3g')}] ({show(c['n_tests'])} tests)",
            "not pooled"
            if c["u_states"] is None
            else f"counted, standard error widened by {show(c['u_states'], '.3g')}",
        ]

    rows = [row(c) for c in n["diagnosis"]["changes"]["changed"]]
    header = ["series", "cause", "parameter", "change", "before → after", "size [95 % CI]", "in the pool"]
    return markdown_table(header, rows) if rows else "None."


def _effect_cell(e: Mapping[str, Any], spec: str = ".3g") -> str:
    """ "estimate [low, high]" of a campaign-level row, or "-" where it was not testable."""
    if e.get("estimate") is None:
        return "-"
    return f"{show(e['estimate'], spec)} [{show(e['ci_low'], spec)}, {show(e['ci_high'], spec)}]"


@_of("campaign_level")
def campaign_statements(n: Mapping[str, Any]) -> str:
    """The paper's campaign-wide statements tested (``diagnosis/campaign_effects.csv``)."""
    c = n["campaign_level"]
    rows = [
        [
            e["paper"],
            f"{e['boundary']}: {e['response']}, {e['covariate'] if e['covariate'] != 'mean' else 'its mean'}",
            e["claim"],
            f"{e['term']}: {_effect_cell(e)}" if e["term"] else _effect_cell(e),
            show(e["p_holm"], ".2g"),
            f"{plural(e['unit_level'], e['n_units'])} ({show(e['n_series'])}, {show(e['n_tests'])})",
            f"**{e['verdict']}{': ' + e['why_not_testable'] if e['why_not_testable'] else ''}**",
        ]
        for e in (c["statements"][key] for key in c["order"])
    ]
    header = [
        "the paper", "parameter, covariate", "claim", "effect [95 % CI]", "Holm p", "units (series, tests)", "verdict",
    ]  # fmt: skip
    return markdown_table(header, rows)


@_of("campaign_level")
def campaign_found(n: Mapping[str, Any]) -> str:
    """The effects the exploratory checks found (Holm-adjusted), beyond the paper's statements."""
    c = n["campaign_level"]
    rows = [
        [
            f"{e['boundary']}: {e['response']}",
            e["covariate"],
            f"{e['term']}: {_effect_cell(e)}",
            show(e["p_holm"], ".2g"),
            show(e["n_series"]),
        ]
        for e in c["found"]
    ]
    header = ["parameter", "covariate", "effect [95 % CI]", "Holm p", "series"]
    return markdown_table(header, rows) if rows else "None."


@_of("limestone")
def limestone_groups(n: Mapping[str, Any]) -> str:
    """The limestone blocks by slenderness."""
    rows = [
        [
            show(g["h_over_b"]),
            show(g["n_tests"]),
            show(g["e_an"], ".3f"),
            show(g["measured_median_ratio"], ".3f"),
            g["verdict"] + (f" (weak: {g['weak']})" if g["weak"] else ""),
            f"{show(g['ratio_rms_base'], '.4f')} → {show(g['ratio_rms_model'], '.4f')}",
        ]
        for g in n["limestone"]["groups"]
    ]
    header = ["H/B", "trials", "e_an (Eq. 2)", "measured ratio (median)", "causes named", "held-out rms of the ratio"]
    return markdown_table(header, rows)


def _reduction(base: float | None, new: float | None) -> str:
    if base is None or base == 0 or new is None:
        return "-"
    return f"{100 * (1 - new / base):.0f}"


@_of("maps")
def maps_records(n: Mapping[str, Any]) -> str:
    """N_O of every record and model, and the reductions from 2s-housner to 2s-0.95."""
    m = n["maps"]
    header = ["record", *(f"N_O `{model}`" for model in m["models"])]
    two_sided = {"2s-housner", "2s-0.95"} <= set(m["models"])
    if two_sided:
        header += ["N_O red. %", "scatter `2s-housner` → `2s-0.95`", "scatter red. %"]
    rows = []
    for record in m["records"]:
        r = m["by_record"][record]
        row = [record, *(show(r.get(model, {}).get("N_O"), ".3f") for model in m["models"])]
        if two_sided:
            base, new = r.get("2s-housner", {}), r.get("2s-0.95", {})
            sb, sn = base.get("scatter"), new.get("scatter")
            row += [
                _reduction(base.get("N_O"), new.get("N_O")),
                f"{show(sb, '.3f') if sb is not None else '-'} → {show(sn, '.3f') if sn is not None else '-'}",
                _reduction(sb, sn),
            ]
        rows.append(row)
    return markdown_table(header, rows)


def calibrated_walls(n: Mapping[str, Any]) -> str:
    """The calibrated walls against e alone, and each finding switched off (issue 13, item 4)."""
    rows = []
    walls = n.get("calibrated") or {}
    for c in (walls[prefix] for prefix in ("2s", "1s") if prefix in walls):
        e, full = c["e_alone"], c["calibrated"]
        rows.append([f"`{e['model']}` (e alone)", show(e["N_O"], ".3f"), show(e["scatter"], ".3f"), "", ""])
        rows.append(
            [
                f"`{full['model']}`",
                show(full["N_O"], ".3f"),
                show(full["scatter"], ".3f"),
                f"{show(full['N_O_change_pct'], '+.0f')} / {show(full['scatter_change_pct'], '+.0f')}",
                "",
            ]
        )
        if c.get("sizes"):
            z = c["sizes"]
            rows.append([f"`{z['model']}` (absolute sizes)", show(z["N_O"], ".3f"), show(z["scatter"], ".3f"), "", ""])
        for finding, f in sorted(c["findings"].items(), key=lambda item: item[1]["rank"]):
            rows.append(
                [
                    f"`{f['model']}` (no {finding})",
                    show(f["N_O"], ".3f"),
                    show(f["scatter"], ".3f"),
                    "",
                    f"{show(f['N_O_shift'], '+.3f')} (rank {show(f['rank'])})",
                ]
            )
    header = ["model", "mean N_O", "mean scatter", "N_O / scatter vs e alone (%)", "N_O shift without it"]
    return markdown_table(header, rows)


@_of("maps")
def maps_comparison(n: Mapping[str, Any]) -> str:
    """Record by record, N_O from 2s-housner to 2s-0.95 against Table 4 and the paper's range."""
    comparison = n["maps"]["comparison"]["by_comparison"].get("2s-housner__2s-0.95", {"records": []})
    paper = n["maps"]["reductions"].get("2s-housner__2s-0.95", {}).get("N_O", {})
    rows = [
        [
            show(r["row"]) if r["row"] is not None else "-",
            r["record"],
            "not a Table 4 record" if r["table4_match"] is None else r["table4_differences"] or "as Table 4",
            f"{show(r['N_O_baseline'], '.3f')} → {show(r['N_O_model'], '.3f')}",
            show(r["N_O_reduction_pct"], ".1f") if r["N_O_reduction_pct"] is not None else "-",
            show(r["in_paper_range"]) if r["in_paper_range"] is not None else "-",
            show(r["scatter_reduction_pct"], ".0f") if r["scatter_reduction_pct"] is not None else "-",
            r["reason"] or "",
        ]
        for r in comparison["records"]
    ]
    header = [
        "T4 row",
        "record",
        "record against Table 4",
        "N_O `2s-housner` → `2s-0.95`",
        "N_O red. %",
        f"in the paper's {show(paper.get('paper_min'))}-{show(paper.get('paper_max'))} %",
        "scatter red. %",
        "where it differs, why",
    ]
    return markdown_table(header, rows)


@_of("performance")
def performance_jobs(n: Mapping[str, Any]) -> str:
    """Job times of the workflow by rule."""
    jobs = n["performance"]["jobs"]
    rows = [
        [f"`{rule}`", show(j["jobs"]), show(j["total_s"], ".0f"), show(j["longest_s"], ".1f")]
        for rule, j in jobs.items()
    ]
    return markdown_table(["rule (or folder of jobs)", "jobs", "job time, total (s)", "longest job (s)"], rows)


@_of("performance")
def performance_stages(n: Mapping[str, Any]) -> str:
    """The main job stage by stage (``bench/workflow.py``), or that it was not measured."""
    wf = n["performance"].get("workflow")
    if wf is None:
        return "Not measured: `make bench` has not run on these results (`results/bench/workflow.json`)."
    rows = [
        [f"`{stage}`", show(s["jobs"]), show(s["job_s"], ".1f"), show(s["longest_s"], ".1f"), show(s["cpu_s"], ".1f")]
        for stage, s in wf["stages"].items()
    ]
    header = ["stage (rule or folder of jobs)", "jobs", "job time, total (s)", "longest job (s)", "CPU time (s)"]
    return markdown_table(header, rows)


@_of("performance")
def discovery_cells(n: Mapping[str, Any]) -> str:
    """The series of ``bench/discovery.py`` one by one: the hidden cause, the design's factors, the verdict and
    what it missed, or that it was not measured."""
    d = n["performance"].get("discovery")
    if d is None:
        return "Not measured: `make bench` has not run on these results (`results/bench/discovery.json`)."
    rows = [
        [
            show(c["design_seed"]),
            c["cause"],
            c["boundary"],
            show(c["fs"], ".0f"),
            f"{c['wall']} ({show(c['h_over_b'], '.1f')})",
            show(c["n_tests"]),
            show(c["n_impacts"]),
            ", ".join(c["verdict"]) or "none",
            "yes" if c["named_right"] else "no",
            c["miss"],
        ]
        for c in d["cells"]
    ]
    header = ["shuffle", "hidden", "boundary", "Hz", "wall (h/b)", "tests", "impacts", "verdict", "right"]
    header += ["what it missed"]
    return markdown_table(header, rows)


#: What the shake-table page says where the target was not run.
NOT_RUN = (
    "Not run: the target `shake_table` has not run on these results "
    "(`snakemake shake_table`, see its config key `shake_table_dir`)."
)


def _shake_table(table: Callable[[Mapping[str, Any]], str]) -> Callable[[Mapping[str, Any]], str]:
    """``table`` of the numbers file's shake_table section, :data:`NOT_RUN` where the target did not run."""

    def wrapped(n: Mapping[str, Any]) -> str:
        st = n.get("shake_table")
        return NOT_RUN if st is None else table(st)

    wrapped.__doc__ = table.__doc__
    return wrapped


@_shake_table
def shake_table_status(st: Mapping[str, Any]) -> str:
    """Whether the shake-table target ran, and on how many tests."""
    parts = [
        f"{s}: {show(st[s]['n_tests'])} tests of {show(st[s]['n_ground_motions'])} ground motions"
        for s in st["specimens"]
    ]
    return "Results of the target `shake_table` (" + "; ".join(parts) + ")."


def _probabilistic(v: Mapping[str, Any], key: str) -> str:
    """A Brier score or log loss, "-" for a 0/1 predictor (scored by accuracy alone)."""
    return "-" if v[key] is None else show(v[key], ".3f")


@_shake_table
def shake_table_scores(st: Mapping[str, Any]) -> str:
    """Held-out accuracy, Brier score and log loss of every model and specimen."""
    rows = [
        [
            s,
            f"`{m}`",
            show(v["accuracy"], ".3f"),
            _probabilistic(v, "brier"),
            _probabilistic(v, "log_loss"),
            show(v["n_tests"]),
        ]
        for s in st["specimens"]
        for m, v in st[s]["scores"].items()
    ]
    return markdown_table(["specimen", "model", "accuracy", "Brier score", "log loss", "tests"], rows)


@_shake_table
def shake_table_differences(st: Mapping[str, Any]) -> str:
    """The calibrated block's held-out accuracy minus each other model's, with paired 95 % intervals over records."""
    rows = []
    for s in st["specimens"]:
        v = st[s]["scores"]["block-calibrated"]
        for key, name in (("pgv", "pgv-threshold"), ("dem", "dem"), ("nominal", "block-nominal")):
            d, lo, hi = (v[f"diff_vs_{key}{end}"] for end in ("", "_lo", "_hi"))
            rows.append([s, f"`{name}`", f"{show(d, '+.3f')} [{show(lo, '+.3f')}, {show(hi, '+.3f')}]"])
    return markdown_table(["specimen", "against", "accuracy difference [95 % CI]"], rows)


@_shake_table
def shake_table_transfer(st: Mapping[str, Any]) -> str:
    """One replica's fit predicting the other (held out by record), beside the PGV threshold transferred."""
    rows = [
        [
            v["train"],
            v["test"],
            show(v["accuracy"], ".3f"),
            show(v["brier"], ".3f"),
            show(st["transfer_pgv"][k]["accuracy"], ".3f"),
            show(st[v["test"]]["scores"]["pgv-threshold"]["accuracy"], ".3f"),
        ]
        for k, v in st["transfer"].items()
    ]
    header = [
        "fitted on",
        "predicting",
        "block accuracy",
        "block Brier",
        "PGV threshold transferred",
        "PGV threshold fitted there",
    ]
    return markdown_table(header, rows)


@_shake_table
def shake_table_nominal(st: Mapping[str, Any]) -> str:
    """What the nominal block gets wrong, per specimen."""
    rows = [
        [
            s,
            show(st[s]["observed_overturns"]),
            show(st[s]["nominal_overturns"]),
            show(st[s]["nominal_missed"]),
            show(st[s]["nominal_false_alarms"]),
            show(st[s]["min_pga_overturned_g"], ".3f"),
            f"{show(st[s]['neither_edge_overturns'])} of {show(st[s]['neither_edge_tests'])}",
        ]
        for s in st["specimens"]
    ]
    header = [
        "specimen",
        "overturns observed",
        "predicted by the nominal block",
        "missed",
        "false alarms",
        "lowest PGA overturned (g)",
        "overturned where no edge can start rocking",
    ]
    return markdown_table(header, rows)


@_shake_table
def shake_table_parameters(st: Mapping[str, Any]) -> str:
    """The fitted parameters with their 95 % intervals, whether each departs from the nominal block, grid edges."""
    rows = [
        [
            s,
            q["cause"],
            name,
            f"{show(q['value'], '.3g')} [{show(q['ci_low'], '.3g')}, {show(q['ci_high'], '.3g')}] {q['units']}",
            show(q["null"], ".3g"),
            show(q["named"]) if "derived" not in q["cause"] else "-",
            "yes" if q["at_grid_edge"] else "",
        ]
        for s in st["specimens"]
        for name, q in st[s]["parameters"].items()
    ]
    header = ["specimen", "what", "parameter", "value [95 % CI]", "nominal", "departs from it", "on its grid's edge"]
    return markdown_table(header, rows)


#: The tables a template may place with ``{{ table("name") }}``.
TABLES: dict[str, Callable[[Mapping[str, Any]], str]] = {
    "qc_series": qc_series,
    "table3": table3,
    "stands_apart": stands_apart,
    "effects": effects,
    "push_pull": push_pull,
    "findings_two_sided": lambda n: findings(n, "two_sided"),
    "findings_one_sided": lambda n: findings(n, "one_sided"),
    "minority_two_sided": lambda n: minority(n, "two_sided"),
    "minority_one_sided": lambda n: minority(n, "one_sided"),
    "diagnosis_series": diagnosis_series,
    "series_changes": series_changes,
    "campaign_statements": campaign_statements,
    "campaign_found": campaign_found,
    "limestone_groups": limestone_groups,
    "maps_records": maps_records,
    "calibrated_walls": calibrated_walls,
    "maps_comparison": maps_comparison,
    "performance_jobs": performance_jobs,
    "performance_stages": performance_stages,
    "discovery_cells": discovery_cells,
    "environment_sections": environment_sections,
    "environment_moves": environment_moves,
    "shake_table_status": shake_table_status,
    "shake_table_scores": shake_table_scores,
    "shake_table_nominal": shake_table_nominal,
    "shake_table_parameters": shake_table_parameters,
    "shake_table_differences": shake_table_differences,
    "shake_table_transfer": shake_table_transfer,
}
