"""The diagnosis as results/diagnosis.json and a readable results/diagnosis.md."""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from typing import Any, cast

from rocklab.diagnosis.catalogue import by_name
from rocklab.diagnosis.causes import Stage
from rocklab.diagnosis.result import BoundaryDiagnosis, CampaignDiagnosis, Finding, PooledFinding, SeriesDiagnosis
from rocklab.disk import write_text
from rocklab.inference.intervals import MIN_BOOTSTRAP
from rocklab.inference.notes import counted, note_lines, note_mark


def write_diagnosis(
    diagnosis: CampaignDiagnosis | Iterable[SeriesDiagnosis | BoundaryDiagnosis | Mapping[str, Any]],
    json_path: str | os.PathLike[str],
    md_path: str | os.PathLike[str] | None = None,
) -> None:
    """Write results/diagnosis.json (and diagnosis.md).

    Parameters
    ----------
    diagnosis : CampaignDiagnosis or list of dict
        The diagnosis, or the entries :func:`~rocklab.diagnosis.pooling.diagnose_campaign` computes.
    json_path, md_path : path-like
        The files (no diagnosis.md where ``md_path`` is None).
    """
    diagnosis = CampaignDiagnosis.of(diagnosis)
    diagnosis.to_json(json_path)
    if md_path is not None:
        write_text(md_path, diagnosis_markdown(diagnosis))


def _fmt_params(f: Finding | PooledFinding) -> str:
    return ", ".join(f"{k} = {v:.4g}" for k, v in f.params.items())


def _rests_on(f: Finding | PooledFinding) -> str:
    """What a finding's interval rests on: "(154 tests, 10 series)", "(21 tests)"."""
    parts = [
        counted(getattr(f, k), noun)
        for k, noun in (("n_tests", "test"), ("n_series", "series"))
        if getattr(f, k, None) is not None
    ]
    return f" ({', '.join(parts)})" if parts else ""


def _fmt_ci(f: Finding | PooledFinding, notes: dict[str, str]) -> str:
    """The 95 % interval cell of a finding, or the mark of the reason it has none (:func:`note_mark`)."""
    if f.ci95:
        return ", ".join(f"[{a:.4g}, {b:.4g}]" for a, b in f.ci95.values()) + _rests_on(f)
    if f.ci_note:
        return f"none{note_mark(notes, f.ci_note)}{_rests_on(f)}"
    return "none"


def diagnosis_markdown(
    diagnosis: CampaignDiagnosis | Iterable[SeriesDiagnosis | BoundaryDiagnosis | Mapping[str, Any]],
) -> str:
    """Readable report (results/diagnosis.md) of a diagnosis.

    Parameters
    ----------
    diagnosis : CampaignDiagnosis or list of dict
        The diagnosis, or the entries :func:`~rocklab.diagnosis.pooling.diagnose_campaign` computes.
    """
    out = [
        "# Model diagnosis",
        "",
        "Per series and per boundary condition: what the base simulation gets wrong, the causes the "
        "data carry (parameters, bootstrap 95 % intervals), and the held-out gain. "
        "Method: `rocklab.diagnosis`.",
        "",
        "Each interval gives the tests it rests on (and, for a boundary condition, the series that name the "
        f"cause); a series of fewer than {MIN_BOOTSTRAP} tests has the cluster-robust t interval of its few "
        "degrees of freedom in place of the bootstrap, a series of one test names no cause, and a boundary "
        f"condition gives no interval from fewer than {MIN_BOOTSTRAP} series.",
        "",
    ]
    diagnosis = CampaignDiagnosis.of(diagnosis)
    if diagnosis.not_finished:
        # named before the rest, since what follows leaves them out (their boundary's entry too)
        out += ["## Series whose diagnosis did not finish", ""]
        out += [
            # an unfinished series' entry has its tests counted (series.not_finished)
            f"- {e.key} ({e.boundary}, {counted(cast(int, e.n_tests), 'test')}): {e.not_finished}"
            for e in diagnosis.not_finished
        ]
        out += [""]
    out += _changes_section(diagnosis)
    # a boundary condition's entry or a series', told apart by ``pooled``; an entry has its key (the schema)
    e: Any
    for e in [
        *sorted(diagnosis.boundaries, key=lambda e: cast(str, e.key)),
        *sorted(diagnosis.series, key=lambda e: cast(str, e.key)),
    ]:
        pooled = isinstance(e, BoundaryDiagnosis)
        title = f"{'boundary condition' if pooled else 'series'} {e.key}"
        size = counted(e.n_tests, "test") + (f", {counted(e.n_series, 'series')}" if pooled else "")
        out += [
            f"## {title} ({e.boundary}, {size})",
            "",
            f"Base model: {e.base.model}.",
            "",
            f"What it gets wrong: {e.what_is_wrong}",
            "",
        ]
        v = ", ".join(e.verdict) if e.verdict else "none"
        line = f"**Verdict: {v}**"
        weak = None if pooled else e.weak_evidence
        if e.too_small:
            line = f"**Verdict: too small to name a cause** — {e.too_small}"
        elif e.unexplained:
            line += " — **unexplained** structure remains: " + "; ".join(map(str, e.residual_structure))
        elif weak:
            line += (
                " — structure remains ("
                + "; ".join(map(str, e.residual_structure))
                + ") that "
                + " or ".join(weak)
                + " would remove, short of the evidence to name it: "
                + "; ".join(weak.values())
            )
        out += [line, ""]
        if not pooled and e.not_identifiable:
            out += [
                "Not identifiable in this series, its absence from the verdict says nothing: "
                + "; ".join(f"{k} ({why})" for k, why in e.not_identifiable.items()),
                "",
            ]
        stand = [] if pooled else [f for f in e.findings if f.may_stand_in_for]
        if stand:
            out += [
                "Named with a caveat, the model with a cause this series cannot identify, or cannot tell from "
                "the named one, in its place fits as well: "
                + "; ".join(f"{f.effect} may stand in for {', '.join(f.may_stand_in_for)}" for f in stand),
                "",
            ]
        if e.findings:
            out += [
                "| effect | parameters | 95% CI | held-out deviance/obs "
                "| gain (deviance/obs; free-run log-peak rms) | evidence |",
                "|---|---|---|---|---|---|",
            ]
            notes: dict[str, str] = {}
            for f in e.findings:
                g = f.gain
                fr = g.get("free_run_log_peak_rms")
                ev = f.evidence.get("signature") or f.evidence.get("series", "")
                out.append(
                    f"| {f.effect} | {_fmt_params(f)} | {_fmt_ci(f, notes)} | "
                    f"{_f(f.error_heldout['deviance_per_obs'], '.3g')} | "
                    f"{_f(g['deviance_per_obs'], '.3g')}; {'' if fr is None else f'{fr:.3f}'} | {ev} "
                    f"{f.evidence.get('fit', '') if by_name(f.effect).stage is Stage.AFTER_SELECTION else ''} |"
                )
            out += ["", *(line for note in note_lines(notes) for line in (note, ""))]
            # a series that cannot estimate a cause is left out of its pool, never put at the null value
            gone = [f for f in e.findings if pooled and f.left_out]
            out += [f"{f.effect}, left out: {'; '.join(map(str, f.left_out))}." for f in gone] + ([""] if gone else [])
            # a series whose parameter changes over its tests is counted, not as one wall state
            moving = [f for f in e.findings if pooled and f.changes_within]
            out += [
                f"{f.effect}, counted though changing over their tests: {'; '.join(map(str, f.changes_within))}."
                for f in moving
            ] + ([""] if moving else [])
        if not pooled and e.changed:
            # beside the law, which stays named
            out += ["Changes over the tests: " + "; ".join(f"{c.effect}: {c}" for c in e.changed) + ".", ""]
        for f in e.discovered:
            g = f.heldout_gain
            out += [
                f"Discovered beyond the catalogue: {f.effect}, {f.family}; {f.reduces_to}; held-out "
                f"deviance gain per observation {g['vs_base']:.3g} (standard error {g['vs_base_se']:.2g}) against "
                f"the base model, {g['vs_best_listed']:.3g} ({g['vs_best_listed_se']:.2g}) against the listed "
                f"causes alone ({', '.join(f.best_listed) or 'none'}).",
                "",
            ]
        h = e.heldout
        if h and h["base"].get("free_run_log_peak_rms") is not None:
            hb, hm = h["base"], h["model"]
            out += [
                f"Held-out (tests left out): free-run log-peak rms {hb['free_run_log_peak_rms']:.3f} base, "
                f"{hm['free_run_log_peak_rms']:.3f} chosen model; one-step impact-velocity rms "
                f"{hb['impact_rms']:.4f} → {hm['impact_rms']:.4f}; flight-time rms "
                f"{_f(hb.get('time_rms'))} → {_f(hm.get('time_rms'))}.",
                "",
            ]
        if e.extended:
            out += [f"Extended model: {e.extended['statement']}", ""]
        if pooled and e.series_verdicts:
            small = set(e.too_small_series)
            out += [
                "Series verdicts: "
                + "; ".join(
                    f"{k}: {'too small to name a cause' if k in small else ', '.join(v) or 'none'}"
                    for k, v in e.series_verdicts.items()
                ),
                "",
            ]
        if e.base.alternatives:
            for name, er in e.base.alternatives.items():
                out.append(
                    f"- literature alternative {name}: {er['n_impacts']['model']:.0f} impacts, "
                    f"{er['duration_s']['model']:.2f} s, free-run log-peak rms {er['log_peak_rms']:.3f}"
                )
            out.append("")
    return "\n".join(out)


def _changes_section(diagnosis: CampaignDiagnosis) -> list[str]:
    """The lines of "Changes within a series": how many series were tested, and each change found."""
    tested = [e for e in diagnosis.series if e.changes]
    if not tested:
        return []
    changed = [e for e in tested if e.changed]
    out = [
        "## Changes within a series",
        "",
        f"{counted(len(tested), 'series')} tested for a change of their parameters over their tests "
        f"({counted(sum(len(e.changes or []) for e in tested), 'parameter')}): "
        + (f"{len(changed)} {'shows' if len(changed) == 1 else 'show'} one." if changed else "none shows one."),
        "",
    ]
    out += [f"- series {e.key}, {c.effect}: {c}" for e in changed for c in e.changed]
    return out + ([""] if changed else [])


def _f(x: float | None, fmt: str = ".4f") -> str:
    return "n/a" if x is None else format(x, fmt)
