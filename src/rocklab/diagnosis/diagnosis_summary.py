"""What the diagnosis stages publish for the docs: the campaign's and the limestone blocks' diagnoses.

Written by the diagnosis jobs beside ``diagnosis.json`` and
``limestone_diagnosis.json`` (``results/summaries/diagnosis.json``,
``results/summaries/limestone.json``, :mod:`rocklab.summaries`); the page
``docs/diagnosis.md`` quotes them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import cast

import numpy as np

from rocklab.diagnosis import catalogue
from rocklab.diagnosis.causes import Stage
from rocklab.diagnosis.result import (
    CampaignDiagnosis,
    ChangingSeries,
    FamilyComparison,
    LimestoneDiagnosis,
    PooledFinding,
    SeriesDiagnosis,
)
from rocklab.physics.boundary import Boundary
from rocklab.summaries import Tolerance

#: How far two machines may take the diagnoses' numbers apart. A fit stops
#: when a step moves the parameters by less than 1e-6 of their range, or the
#: deviance by less than 1e-6 of itself (:mod:`rocklab.diagnosis.estimation`),
#: so a parameter that the data barely fix (near its null, or confounded with
#: another) stops a little elsewhere with the floating point of the machine
#: (s_e of series 2b-2s: -0.000118036 on one machine, -0.000117894 on
#: another), and so do the intervals and errors made from the fits. Every
#: measured number is held to a thousandth of itself, or 1e-6 for one near
#: zero; counts, verdicts and names stay exact (:func:`rocklab.summaries.differences`).
#: Measured between four floating-point environments (bench/environments.py):
#: s_e of series 2b-2s moved by 6e-4 of itself (7e-8), every other number by
#: less than 2e-6 of itself; the limestone blocks' fits not at all.
TOLERANCES = {"*": Tolerance(abs=1e-6, rel=1e-3)}


def _finding(f: PooledFinding) -> dict:
    return {
        "params": f.params,
        "ci95": f.ci95,
        "range": f.evidence.get("range", {}),
        "n_series": f.n_series,
        # the series its parameters leave out, and why, in words (the page's "left out" column)
        "left_out": [str(g) for g in f.left_out or []],
    }


def _changes(d: CampaignDiagnosis) -> dict:
    """The series tested for a change of their parameters over their tests, and each change found: where,
    how much, and what its boundary condition's pool made of it (``u_states``, the spread of its states its
    standard error was widened by; None where no pool counts it)."""
    tested = [s for s in d.series if s.changes]
    pooled: dict[tuple[str | None, str, str], ChangingSeries] = {
        (c.series, f.effect, c.parameter): c
        for b in d.boundaries
        for f in b.findings
        for c in f.changes_within or []
        if f.effect in b.verdict
    }
    return {
        "n_series": len(tested),
        "n_parameters": sum(len(s.changes or []) for s in tested),
        "changed": [
            {
                "series": s.key,
                "boundary": s.boundary,
                "effect": c.effect,
                "parameter": c.parameter,
                "kind": str(c.kind),
                "where_test": c.where_test,
                "before": c.before,
                "after": c.after,
                "size": c.size,
                "ci95_size": c.ci95_size,
                "n_tests": c.n_tests,
                "u_states": p.u_states if (p := pooled.get((s.key, c.effect, c.parameter))) is not None else None,
            }
            for s in tested
            for c in s.changed
        ],
    }


def _after_selection_gain(series_entries: Sequence[SeriesDiagnosis], effect: str) -> dict | None:
    """Held-out errors of the free run with and without a cause estimated after selection
    (:attr:`rocklab.diagnosis.causes.Stage.AFTER_SELECTION`), pooled over the series that name
    it: for each error its finding measures (the free run's, not a deviance), the root of the
    test-weighted mean of each series' squared rms error, ``base`` without the cause (error +
    gain) and ``model`` with it."""
    named = [(s.n_tests, f) for s in series_entries if (f := s.finding(effect)) is not None]
    if not named:
        return None
    measures = [k for k, v in named[0][1].error_heldout.items() if v is not None]
    n = np.array([w for w, _ in named], dtype=float)

    def pooled(x: Sequence[float]) -> float:
        return math.sqrt(np.sum(n * np.asarray(x, dtype=float) ** 2) / np.sum(n))

    return {
        k: {
            # the measures the first series has, which every one has
            "base": pooled([cast(float, f.error_heldout[k]) + cast(float, f.gain[k]) for _, f in named]),
            "model": pooled([cast(float, f.error_heldout[k]) for _, f in named]),
        }
        for k in measures
    }


def diagnosis_summary(diagnosis: CampaignDiagnosis | str | Path) -> dict:
    """The model diagnosis of the campaign by boundary condition and series.

    Parameters
    ----------
    diagnosis : CampaignDiagnosis, str or pathlib.Path
        The diagnosis, or ``diagnosis.json`` as written by :func:`rocklab.diagnosis.write_diagnosis`:
        the one place of the docs that reads its fields.

    Returns
    -------
    dict
        ``series`` (the verdict of each), ``n_series``, ``n_unexplained``, ``changes`` (the series tested
        for a change of their parameters over their tests, the changes found, :func:`_changes`) and per
        boundary (``two_sided``, ``one_sided``; ``None`` where the campaign has
        none) the base model's errors, the causes named with their intervals, the
        held-out errors, the gain of each cause estimated after selection (``after_selection``) and
        the minority causes.
    """
    d = CampaignDiagnosis.of(diagnosis)
    series = d.series
    rows: list[dict] = []
    out: dict = {
        "series": rows,
        "n_series": len(series),
        "n_unexplained": len(d.unexplained),
        "changes": _changes(d),
    }
    out.update({b.key: None for b in Boundary})
    for s in series:
        rows.append(
            {
                "series": s.key,
                "boundary": s.boundary,
                "n_tests": s.n_tests,
                "verdict": ", ".join(s.verdict) or "none",
                "unexplained": bool(s.unexplained),
            }
        )
    for e in d.boundaries:
        # an entry has its boundary condition and base model (the schema)
        assert e.boundary is not None and e.base is not None
        mine = d.series_of(e.boundary)
        out[Boundary(e.boundary).key] = {
            "n_tests": e.n_tests,
            "n_series": e.n_series,
            "n_impacts": e.n_impacts,
            "base_model": e.base.model,
            "base": e.base.errors,
            "what_is_wrong": e.what_is_wrong,
            "verdict": ", ".join(e.verdict) or "none",
            "unexplained": bool(e.unexplained),
            "findings": {f.effect: _finding(f) for f in e.findings},
            "heldout": e.heldout,
            # absent where no series was large enough to extend the model
            "extended": (e.extended or {}).get("statement"),  # type: ignore[call-overload]
            # each cause estimated once the model is chosen (the stop): what it gains, and the series
            # that do not name it
            "after_selection": {
                c.name: {
                    "heldout": _after_selection_gain(mine, c.name),
                    "not_named": [s.key for s in mine if c.name not in s.verdict],
                }
                for c in catalogue.CAUSES
                if c.stage is Stage.AFTER_SELECTION
            },
            "minority": [{"series": s.key, "effect": f.effect, "params": f.params} for s, f in d.minority(e.boundary)],
        }
    return out


def _family(families: Sequence[FamilyComparison]) -> dict | None:
    """The first generalised family of the limestone blocks (issue 12): form, parameters, intervals, gains."""
    if not families:
        return None
    f = families[0]
    return {
        "effect": f.effect,
        "form": f.form,
        "params": f.params,
        "ci95": {k: list(v) for k, v in f.ci95.items()},
        "reduces_to": f.reduces_to,
        "discovered": f.discovered,
        "best_listed": f.best_listed,
        "dbic_vs_base": f.dbic_vs_base,
        "heldout_gain": f.heldout_gain,
    }


def limestone_summary(diagnosis: LimestoneDiagnosis | str | Path) -> dict:
    """The restitution diagnosis of the UMinho limestone blocks.

    Parameters
    ----------
    diagnosis : LimestoneDiagnosis, str or pathlib.Path
        The diagnosis (:func:`rocklab.diagnosis.block_tests.diagnose_blocks`), or
        ``limestone_diagnosis.json`` as written by the rule ``limestone_diagnosis``.
    """
    d = diagnosis if isinstance(diagnosis, LimestoneDiagnosis) else LimestoneDiagnosis.from_json(diagnosis)
    a = d.all
    # every block group has its slenderness (the pooled entry of all blocks has none)
    h_over_b = [float(g.h_over_b) for g in d.groups if g.h_over_b is not None]
    return {
        "source": d.source,
        "n_tests": a.n_tests,
        "n_impacts": a.n_impacts,
        "n_groups": len(d.groups),
        "h_over_b": {"min": min(h_over_b), "max": max(h_over_b)},
        "e_an": a.base["e_an"],
        "measured_median_ratio": a.base["measured_median_ratio"],
        "what_is_wrong": a.what_is_wrong,
        "verdict": ", ".join(a.verdict) or "none",
        "unexplained": bool(a.unexplained),
        "residual_structure": "; ".join(map(str, a.residual_structure)) or "none",
        "rejected": a.rejected,
        "signatures": a.signatures,
        "heldout_ratio_rms": {"base": a.heldout["base"]["ratio_rms"], "model": a.heldout["model"]["ratio_rms"]},
        "slenderness": d.slenderness,
        "family": _family(a.families),
        "groups": [
            {
                "h_over_b": round(hb),
                "n_tests": g.n_tests,
                "e_an": g.base["e_an"],
                "measured_median_ratio": g.base["measured_median_ratio"],
                "verdict": ", ".join(g.verdict) or "none",
                "weak": ", ".join(g.weak_evidence) or "",
                "ratio_rms_base": g.heldout["base"]["ratio_rms"],
                "ratio_rms_model": g.heldout["model"]["ratio_rms"],
            }
            for g, hb in zip(d.groups, h_over_b, strict=True)
        ],
    }
