"""The diagnosis as results/diagnosis.json and a readable results/diagnosis.md."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from rocklab.dissipation.statistics import MIN_BOOTSTRAP, counted, note_lines, note_mark


def jsonable(x):
    """``x`` with NumPy scalars as Python numbers and non-finite floats as None (JSON)."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return None if not np.isfinite(x) else float(x)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def write_diagnosis(entries, json_path, md_path=None):
    """Write results/diagnosis.json (and diagnosis.md) from :func:`diagnose_campaign` entries."""
    Path(json_path).write_text(json.dumps(jsonable(entries), indent=1))
    if md_path is not None:
        Path(md_path).write_text(diagnosis_markdown(entries))


def _fmt_params(f):
    return ", ".join(f"{k} = {v:.4g}" for k, v in f["params"].items())


def _rests_on(f):
    """What a finding's interval rests on: "(154 tests, 10 series)", "(21 tests)"."""
    parts = [counted(f[k], noun) for k, noun in (("n_tests", "test"), ("n_series", "series")) if f.get(k) is not None]
    return f" ({', '.join(parts)})" if parts else ""


def _fmt_ci(f, notes):
    """The 95 % interval cell of a finding, or the mark of the reason it has none (:func:`note_mark`)."""
    if f["ci95"]:
        return ", ".join(f"[{a:.4g}, {b:.4g}]" for a, b in f["ci95"].values()) + _rests_on(f)
    if f.get("ci_note"):
        return f"none{note_mark(notes, f['ci_note'])}{_rests_on(f)}"
    return "none"


def diagnosis_markdown(entries) -> str:
    """Readable report (results/diagnosis.md) of :func:`diagnose_campaign` entries."""
    out = [
        "# Model diagnosis",
        "",
        "Per series and per boundary condition: what the base simulation gets wrong, the causes the "
        "data carry (parameters, bootstrap 95 % intervals), and the held-out gain. "
        "Method: `rocklab.diagnosis`.",
        "",
        "Each interval gives the tests it resamples (and, for a boundary condition, the series that name the "
        f"cause); none is given from fewer than {MIN_BOOTSTRAP}, and a series of fewer tests names no cause.",
        "",
    ]
    order = sorted(entries, key=lambda e: (e["scope"] != "boundary", e["key"]))
    for e in order:
        title = f"{'boundary condition' if e['scope'] == 'boundary' else 'series'} {e['key']}"
        size = counted(e["n_tests"], "test") + (f", {counted(e['n_series'], 'series')}" if "n_series" in e else "")
        out += [
            f"## {title} ({e['boundary']}, {size})",
            "",
            f"Base model: {e['base']['model']}.",
            "",
            f"What it gets wrong: {e['what_is_wrong']}",
            "",
        ]
        v = ", ".join(e["verdict"]) if e["verdict"] else "none"
        line = f"**Verdict: {v}**"
        if e.get("too_small"):
            line = f"**Verdict: too small to name a cause** — {e['too_small']}"
        elif e["unexplained"]:
            line += " — **unexplained** structure remains: " + "; ".join(e.get("residual_structure", []))
        elif e.get("weak_evidence"):
            line += (
                " — structure remains ("
                + "; ".join(e["residual_structure"])
                + ") that "
                + " or ".join(e["weak_evidence"])
                + " would remove, short of the evidence to name it: "
                + "; ".join(e["weak_evidence"].values())
            )
        out += [line, ""]
        if e["findings"]:
            out += [
                "| effect | parameters | 95% CI | held-out deviance/obs "
                "| gain (deviance/obs; free-run log-peak rms) | evidence |",
                "|---|---|---|---|---|---|",
            ]
            notes = {}
            for f in e["findings"]:
                g = f["gain"]
                fr = g.get("free_run_log_peak_rms")
                ev = f["evidence"].get("signature") or f["evidence"].get("series", "")
                out.append(
                    f"| {f['effect']} | {_fmt_params(f)} | {_fmt_ci(f, notes)} | "
                    f"{_f(f['error_heldout']['deviance_per_obs'], '.3g')} | "
                    f"{_f(g['deviance_per_obs'], '.3g')}; {'' if fr is None else f'{fr:.3f}'} | {ev} "
                    f"{f['evidence'].get('fit', '') if f['effect'] == 'stop_threshold' else ''} |"
                )
            out += ["", *(line for note in note_lines(notes) for line in (note, ""))]
        for f in e["findings"]:
            if f.get("discovered"):
                g = f["heldout_gain"]
                out += [
                    f"Discovered beyond the catalogue: {f['effect']}, {f['family']}; {f['reduces_to']}; held-out "
                    f"deviance gain per observation {g['vs_base']:.3g} (standard error {g['vs_base_se']:.2g}) against "
                    f"the base model, {g['vs_best_listed']:.3g} ({g['vs_best_listed_se']:.2g}) against the listed "
                    f"causes alone ({', '.join(f['best_listed']) or 'none'}).",
                    "",
                ]
        h = e.get("heldout")
        if h and h["base"].get("free_run_log_peak_rms") is not None:
            hb, hm = h["base"], h["model"]
            out += [
                f"Held-out (tests left out): free-run log-peak rms {hb['free_run_log_peak_rms']:.3f} base, "
                f"{hm['free_run_log_peak_rms']:.3f} chosen model; one-step impact-velocity rms "
                f"{hb['impact_rms']:.4f} → {hm['impact_rms']:.4f}; flight-time rms "
                f"{_f(hb.get('time_rms'))} → {_f(hm.get('time_rms'))}.",
                "",
            ]
        if e.get("extended"):
            out += [f"Extended model: {e['extended']['statement']}", ""]
        if e.get("series_verdicts"):
            small = set(e.get("too_small_series", []))
            out += [
                "Series verdicts: "
                + "; ".join(
                    f"{k}: {'too small to name a cause' if k in small else ', '.join(v) or 'none'}"
                    for k, v in e["series_verdicts"].items()
                ),
                "",
            ]
        alt = e["base"].get("alternatives")
        if alt:
            for name, er in alt.items():
                out.append(
                    f"- literature alternative {name}: {er['n_impacts']['model']:.0f} impacts, "
                    f"{er['duration_s']['model']:.2f} s, free-run log-peak rms {er['log_peak_rms']:.3f}"
                )
            out.append("")
    return "\n".join(out)


def _f(x, fmt=".4f"):
    return "n/a" if x is None else format(x, fmt)
