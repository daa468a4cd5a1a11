"""Benchmark: calibration of the whole diagnosis on virtual series with a known truth (issue 24).

    python bench/discovery.py --out results/bench [--budget-s 1200] [--workers 2] [--design-seeds 0 1] [--replicates 3]
                              [--noise-mm 0.002] [--generator {virtual,contact,recorded,all}]

The virtual lab (:func:`rocklab.lab.virtual_lab.series_records`) writes
series that hide one cause of the catalogue or one member of a family, or
nothing (nulls), on each boundary condition it applies to (two-sided,
one-sided without a gap, one-sided with a gap of 0.03 alpha, the gap then
part of the truth), sampled at 100, 200, 400 or 1000 Hz, on a stocky wall
(h/b about 4), the paper's (1a, h/b 9.6) or a slender one (2a, h/b 14.4),
of 3, 5 or 10 tests, each test recorded until the wall comes to rest
(:data:`RECORD_S`); :func:`rocklab.diagnosis.diagnose_series` (the
workflow's n_boot) diagnoses each.  The full cross (some 1,300 series) does
not fit the time budget: the design is fractional and balanced, every
(cause, boundary) cell and each null cell of (boundary, rate) gets
:data:`REPLICATES` (``--replicates``) combinations of rate, slenderness and
size in turn from a fixed shuffle of their 36, on each shuffle of
``--design-seeds`` (by default the first, on which the diagnosis' rules
were first checked, and another held out from it; the rates are over all), so each level of each factor
appears about equally often.  Seeds are fixed (the series' index).  Series
still waiting when ``--budget-s`` has passed are not run (``n_skipped``
says how many).  Every channel carries the virtual lab's noise and mains
hum (:data:`NOISE_MM`); ``--noise-mm`` runs the same design with other
instruments (``noise_mm`` in the output says which).

A second generator, not the model the diagnosis fits (``--generator``, both by
default): the contact lab (:mod:`rocklab.lab.contact_lab`, a rigid block on
compliant MuJoCo contacts with Coulomb friction, two-sided walls only) writes
the same tests (:func:`rocklab.lab.virtual_lab.series_records`, its simulator
the contact lab's) for each knob of :data:`CONTACT_KNOBS` (the docs' table of
knob and cause, docs/virtual-lab.md) :data:`CONTACT_REPLICATES` times and the
default contact at each rate, on the same shuffles.  Nothing there is set as a
cause: each series' truth is read from the block (:func:`contact_truth`), by a
rule fixed before any diagnosis: c = e measured over Eq. 2 at the nominal alpha
(the diagnosis' base e), zeta = the viscous zeta that loses what the block's long
flights lose (the knob and the pivot's spring-damper,
:func:`rocklab.lab.contact_lab.flight_zeta`), r = alpha_r / alpha of the edges
as built.  A cause whose parameter departs from its null by more than its
smallest effect worth naming (the catalogue's ``practical``: 0.005 for c and r,
2e-4 for zeta) is hidden and must be named; below, it is optional: named, its
interval must hold the truth, not named, nothing is missing.  A series with
nothing worth naming is a null.

A third, the virtual lab through its files (``recorded``): the series
:data:`RECORDED_CELLS` lists (the classes of issue 42: a transducer 2 % out of
calibration on walls with nothing to find, losses in flight and the amplitude
law recorded by a gyroscope at 1000 Hz and a motion capture at 200 Hz on both
boundaries, a wall with a gap on a gyroscope, hinge friction on one-sided
walls, the nulls of each instrument, a rocking edge crushed half-way through
a series of twelve tests on every instrument and boundary, scored by
:func:`score_change`), each on the paper's or the slender
wall and a size from the shuffle, written in the lab's format with the
instrument and reduced as the workflow does
(:func:`rocklab.diagnosis.recorded.recorded_series`: the channels' checks, the
gain check, an inertial record's integration and rate steps, a rotation
record's bridges), their truth the scenario's (:func:`scenario`).  The same
:func:`score` and :func:`rates` judge every generator; ``by_generator`` holds
each one's, ``by_class`` the recorded cells' by class.

Writes ``<out>/discovery.json``: ``named_right_rate`` (the verdict is the
hidden causes, every true parameter inside the verdict's simultaneous 95 %
intervals ``ci95_joint``, which claim all its values at once; over the
series whose design can carry their hidden cause: ``n_not_identifiable``
and ``not_identifiable`` list the others, where the diagnosis says
``too_small`` or names the hidden cause in its ``not_identifiable``),
its parts ``verdict_right_rate`` (the verdict is the hidden causes,
intervals aside), ``named_right_marginal_rate`` (every true parameter
inside its own 95 % interval) and ``named_right_at_coverage`` (the rate
those verdicts would reach were each true parameter inside its own
interval independently with the measured ``coverage_95``: with k
parameters a series is all inside with probability coverage^k, some 0.90
for two at 0.95, why a verdict's claim needs simultaneous intervals),
``false_name_rate_null`` (a cause named on a null series, the gap of a
wall with a gap aside),
``confident_misname_rate`` (a cause that is not hidden named without the
``unexplained`` flag nor the caveat ``may_stand_in_for``: a cause the design cannot identify, or a rival
its tests cannot tell from the named one, may be what it carries), ``coverage_95`` (share of the true parameters of the
hidden causes named inside their 95 % intervals;
``n_params_widened_by_systematic`` of them that the statistical interval
alone missed and its systematic part holds: the pulls of the groups,
:mod:`rocklab.diagnosis.estimation.systematic`, and the model's bias,
:mod:`rocklab.diagnosis.estimation.bias`), each with its Clopper-Pearson 95 %
interval over the series or parameters it rests on, ``n_series``, the
targets and whether each is met, ``pooled_bias`` (mean signed error of the
named parameters in units of their smallest effect worth naming, its 95 %
interval over series: 0 inside it, no bias shown), and ``cells`` (one row per
series: its generator, factors, truth, verdict, what missed), the top-level
rates the first generator's (the virtual lab's), ``by_generator`` each one's.
Exit status 1 where a target of either is missed.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import re
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np
import pandas as pd

from rocklab._imports import lazy_module
from rocklab.diagnosis import catalogue, diagnose_records, jsonable
from rocklab.diagnosis.estimation import systematic
from rocklab.diagnosis.pooling import pooled_bias
from rocklab.diagnosis.recorded import recorded_series
from rocklab.diagnosis.result import ChangeKind
from rocklab.lab import contact_lab
from rocklab.lab import virtual_lab as vl
from rocklab.physics import impact as I
from rocklab.physics import restitution, wall

stats = lazy_module("scipy.stats")

TARGETS = {
    "named_right_rate": (0.95, None),
    "false_name_rate_null": (None, 0.05),
    "confident_misname_rate": (None, 0.0),
    "coverage_95": (0.90, 0.98),
}
RATES = (100.0, 200.0, 400.0, 1000.0)
#: The generators of the series, in the order of the output.
GENERATORS = ("virtual", "contact", "recorded")
SIZES = (3, 5, 10)
_SPEC = vl.DEFAULT_SPECIMENS.set_index("specimen")
#: Stocky (h/b 4), the paper's slender clay wall (h/b 9.6), the most slender one (h/b 14.4).
WALLS = {
    "stocky": pd.Series({"length_mm": 1130.0, "height_mm": 492.0, "thickness_mm": 123.0}, name="st"),
    "paper": _SPEC.loc["1a"],
    "slender": _SPEC.loc["2a"],
}
BOUNDARIES = ("two-sided", "one-sided", "one-sided-gap")
GAP = 0.03  # gap over alpha of the walls with a gap
#: Series of each cell (cause, boundary; null, boundary, rate), each on another combination of rate,
#: slenderness and size: three make the rates' binomial intervals some +- 0.07 to 0.1, in some 3 minutes.
REPLICATES = 3
#: The shuffles of the design run: the first, on which the diagnosis' rules were first checked, and
#: another, held out from it; the rates are over both.
DESIGN_SEEDS = (0, 1)
#: Longest free rocking simulated [s]: every wall of the design comes to rest before it (a slender two-sided
#: wall of Housner's e rocks some 110 s).  The virtual lab holds the last angle of a history cut while the
#: wall still rocks, a wall frozen in flight, which the diagnosis rightly reads as a wall that stops dead.
#: The contact lab's block too (wall 2a on the default contact: at rest after some 100 s, 12 s of one core).
RECORD_S = 400.0
#: Noise and mains hum of every channel [mm]: the virtual lab's default, the real campaign's.  ``--noise-mm``
#: runs the design with other instruments (a tenth of it: the model's own errors, which this noise hides, show).
NOISE_MM = vl.Effects().noise_mm


def _scaled_by_test(base, c, drift, n):
    """e = c e_base exp(drift (i / (n - 1) - 1/2)) in test i of n: a restitution that drifts between tests."""
    return lambda i: {"impact": I.Scaled(base, c * math.exp(drift * (i / max(n - 1, 1) - 0.5)))}


def _by_speed(g):
    """e = e_an,2s g(thetadot^- / thetadot_r): a law of the impact speed (the family restitution_speed)."""

    def e(thetadot, side, alpha, p):
        return restitution.two_sided(alpha) * g(abs(thetadot) / wall.overturning_velocity(alpha, p))

    return I.Custom(e)


def _sticking(v_stick, c):
    """e = c e_an,2s, but a landing slower than v_stick thetadot_r sticks (e = 0)."""

    def e(thetadot, side, alpha, p):
        fast = abs(thetadot) > v_stick * wall.overturning_velocity(alpha, p)
        return c * restitution.two_sided(alpha) if fast else 0.0

    return I.Custom(e)


def scenario(cause, boundary, alpha, n):
    """(simulator model, series keywords, truth {cause: {parameter: value}}) of a hidden cause on a boundary.

    ``boundary`` one-sided-gap: the wall swings through a gap of
    :data:`GAP` alpha, its calibration that of the transverse impact.
    """
    one = boundary != "two-sided"
    gap = boundary == "one-sided-gap"
    base_key = "transverse_impact" if gap else "impact"
    base = I.Transverse() if gap else (I.OneSided() if one else I.HousnerTwoSided())
    model = {"gap": GAP * alpha} if gap else ({} if one else {"impact": base})
    truth = {"contact_gap": {"gap_over_alpha": GAP}} if gap else {}
    kw = {}
    c = 1.2 if one else 0.93
    if cause == "null":
        pass
    elif cause == "restitution_scale":
        model[base_key] = I.Scaled(base, c)
        truth[cause] = {"c": c}
    elif cause == "restitution_amplitude":
        a, b = (1.2, 0.5) if one else (0.97, 0.06)
        model[base_key] = I.AmplitudeLaw(base, a, b)
        truth[cause] = {"a": a, "b": b}
    elif cause == "instability_angle":
        kw["alpha_ratio"] = 0.75 if one else 0.9
        truth[cause] = {"alpha_r_over_alpha": kw["alpha_ratio"]}
    elif cause == "flight_damping":
        model["zeta"] = 0.01
        truth[cause] = {"zeta": 0.01}
    elif cause == "hinge_asymmetry":
        # e_+ = e_an, e_- = 0.96 e_an: e_an sqrt(0.96) exp(+-s_e/2), a scale beside the asymmetry
        model["impact"] = I.Sided(base, I.Scaled(base, 0.96))
        truth[cause] = {"s_alpha": 0.0, "s_e": -math.log(0.96)}
        truth["restitution_scale"] = {"c": math.sqrt(0.96)}
    elif cause == "restitution_drift":
        law = _scaled_by_test(base, c, 0.15, n)
        return (
            lambda i: {**model, base_key: law(i)["impact"]},
            kw,
            {**truth, cause: {"c": c, "drift": 0.15}},
        )
    elif cause == "instability_amplitude":
        model["hinge_rounding"] = 0.3
        kw["alpha_ratio"] = 0.9
        truth[cause] = {"alpha_r_over_alpha": 0.9, "rounding": 0.3}
    elif cause == "restitution_speed":
        model["impact"] = _by_speed(lambda x: 0.9 + 0.1 * x)
        truth[cause] = {f"g{j}": 0.9 + 0.1 * j / 3 for j in range(4)}
    elif cause == "flight_loss[friction]":
        model["mu"] = 0.02 * alpha
        kw["theta0_range"] = (0.85, 0.95)  # released below alpha - mu: friction would hold it at rest
        truth["flight_loss"] = {"zeta": 0.0, "mu_over_alpha": 0.02, "kappa_alpha": 0.0}
    elif cause == "flight_loss[drag]":
        model["kappa"] = 0.06 / alpha
        truth["flight_loss"] = {"zeta": 0.0, "mu_over_alpha": 0.0, "kappa_alpha": 0.06}
    elif cause == "edge_crushed":
        # the rocking edge of a sharp wall crushed before test n // 2 (issue 42): a change within the series
        kw["alpha_ratio"] = lambda i: 1.0 if i < n // 2 else CRUSHED_RATIO
    elif cause == "stop_threshold":
        model["impact"] = _sticking(0.15, 0.95)
        truth["restitution_scale"] = {"c": 0.95}
        truth[cause] = {"v_stop_over_vr": 0.15}
    else:
        raise ValueError(f"no scenario for {cause}")
    return model, kw, truth


#: Hidden causes by boundary condition: every listed cause and family member the boundary carries.
CAUSES = {
    "two-sided": (
        "restitution_scale",
        "restitution_amplitude",
        "instability_angle",
        "flight_damping",
        "hinge_asymmetry",
        "restitution_drift",
        "instability_amplitude",
        "restitution_speed",
        "flight_loss[friction]",
        "flight_loss[drag]",
        "stop_threshold",
    ),
    "one-sided": (
        "restitution_scale",
        "restitution_amplitude",
        "instability_angle",
        "flight_damping",
        "restitution_drift",
        "flight_loss[friction]",
    ),
    "one-sided-gap": ("restitution_scale", "restitution_amplitude", "instability_angle", "flight_damping"),
}


#: The recorded generator's cells: (class, cause, boundary, instrument, rate [Hz]); "instrument error" is a null
#: whose transducer :data:`FAULTY_CHANNEL` reads :data:`FAULTY_GAIN` of the truth.
RECORDED_CELLS = (
    ("instrument error", "null", "two-sided", "transducers", 400.0),
    ("instrument error", "null", "one-sided", "transducers", 400.0),
    ("flight loss", "flight_loss[drag]", "two-sided", "inertial", 1000.0),
    ("flight loss", "flight_loss[drag]", "two-sided", "rotation", 200.0),
    ("flight loss", "flight_damping", "two-sided", "inertial", 1000.0),
    ("flight loss", "flight_damping", "one-sided", "inertial", 1000.0),
    ("amplitude law", "restitution_amplitude", "two-sided", "inertial", 1000.0),
    ("amplitude law", "restitution_amplitude", "one-sided", "inertial", 1000.0),
    ("amplitude law", "restitution_amplitude", "two-sided", "rotation", 200.0),
    ("amplitude law", "restitution_amplitude", "one-sided", "rotation", 200.0),
    ("gap", "restitution_amplitude", "one-sided-gap", "inertial", 1000.0),
    ("gap", "flight_damping", "one-sided-gap", "inertial", 1000.0),
    ("hinge friction", "flight_loss[friction]", "one-sided", "transducers", 400.0),
    ("hinge friction", "flight_loss[friction]", "one-sided", "inertial", 1000.0),
    ("null", "null", "two-sided", "inertial", 1000.0),
    ("null", "null", "one-sided", "inertial", 1000.0),
    ("null", "null", "two-sided", "rotation", 200.0),
    ("null", "null", "one-sided", "rotation", 200.0),
    *(
        ("change within series", "edge_crushed", b, instrument, fs)
        for b in ("two-sided", "one-sided")
        for instrument, fs in (("transducers", 400.0), ("inertial", 1000.0), ("rotation", 200.0))
    ),
)
#: A change within a series (:data:`RECORDED_CELLS`' "change within series"): the rocking angle over alpha
#: after the edge is crushed, 1 before; the series' tests, the crushed edge from test ``CHANGE_TESTS // 2`` on.
#: Twelve tests: a step after six of twelve has a permutation p-value down to 2 / C(12, 6) = 0.002, below the
#: Bonferroni level of a series that tests two parameters (:mod:`rocklab.diagnosis.estimation.change`); ten
#: give 0.008, five cannot name one.
CRUSHED_RATIO, CHANGE_TESTS = 0.9, 12
FAULTY_CHANNEL, FAULTY_GAIN = 2, 0.98
#: The specimens of the recorded cells' walls (written with the campaign's specimens.csv).
RECORDED_WALLS = {"paper": "1a", "slender": "2a"}
#: Longest free rocking of a recorded test [s]: the paper's and the slender wall are at rest before it (a
#: slender two-sided wall of Housner's e rocks some 110 s); a file of 400 s at 1000 Hz costs more to write
#: and read than its diagnosis.
RECORDED_S = 150.0


def recorded_design(seeds=DESIGN_SEEDS):
    """The recorded generator's designs of the shuffles ``seeds``: each of :data:`RECORDED_CELLS` once per
    shuffle, on a wall of :data:`RECORDED_WALLS` and a size of :data:`SIZES` in turn from the shuffle's
    order; series numbered on."""
    combos = [(w, n) for w in RECORDED_WALLS for n in SIZES]
    rows = []
    for seed in seeds:
        order = np.random.default_rng(seed).permutation(len(combos))
        for i, (cls, cause, boundary, instrument, fs) in enumerate(RECORDED_CELLS):
            w, n = combos[order[i % len(combos)]]
            n = CHANGE_TESTS if cause == "edge_crushed" else n
            rows.append(
                {"generator": "recorded", "class": cls, "cause": cause, "boundary": boundary}
                | {"instrument": instrument, "fs": fs, "wall": w, "n_tests": n, "design_seed": seed, "seed": len(rows)}
            )
    return rows


def design(seeds=DESIGN_SEEDS, replicates=REPLICATES):
    """The fractional designs of the shuffles ``seeds``, one after the other, their series numbered on."""
    rows = []
    for seed in seeds:
        rows += [{**r, "design_seed": seed, "seed": len(rows) + r["seed"]} for r in _shuffle(seed, replicates)]
    return rows


def _shuffle(seed, replicates):
    """One fractional design: one row per series (cause, boundary, rate, wall, size, seed); ``seed`` the
    shuffle of the combinations of rate, slenderness and size, of which each cell takes ``replicates``
    in turn."""
    combos = [(fs, w, n) for fs in RATES for w in WALLS for n in SIZES]
    order = np.random.default_rng(seed).permutation(len(combos))
    cells = [(c, b) for b in BOUNDARIES for c in CAUSES[b]]
    # nulls: every boundary at every rate, slenderness and size rotating
    cells += [("null", b) for b in BOUNDARIES for _ in RATES]
    rows = []
    for i, (cause, boundary) in enumerate(cells):
        for j in range(replicates):
            fs, w, n = combos[order[(i * replicates + j) % len(combos)]]
            if cause == "null":
                fs = RATES[i % len(RATES)]
            rows.append({"cause": cause, "boundary": boundary, "fs": fs, "wall": w, "n_tests": n, "seed": len(rows)})
    return rows


def _inside(ci, x):
    return ci is not None and len(ci) == 2 and ci[0] <= x <= ci[1]


class _Intervals(logging.Handler):
    """The statistical intervals and systematic uncertainties the diagnosis of a series logs
    (:func:`rocklab.diagnosis.estimation.resampling.parameter_intervals`), in the order it logs them."""

    def __init__(self):
        super().__init__(logging.INFO)
        self.parts = []

    def emit(self, record):
        if hasattr(record, "statistical"):
            self.parts.append((record.statistical, record.systematic))


def _widened_by_systematic(cause, name, x, estimate, ci, parts):
    """Whether the truth ``x`` lies in the interval ``ci`` of ``estimate`` only by its systematic part: the
    statistical interval that, widened by the pulls of the groups, is ``ci`` or (widened again by the
    model's bias, :mod:`rocklab.diagnosis.estimation.bias`) within it misses ``x``."""
    q = next(q for q in catalogue.by_name(cause).params if q.name == name)
    for stat, u in reversed(parts):
        if name in stat and estimate is not None:
            lo, hi = systematic.widened(stat[name], estimate, q.lower, q.upper, u[name])
            tol = 1e-9 * (q.upper - q.lower)
            if ci[0] <= lo + tol and hi - tol <= ci[1]:
                return not _inside(stat[name], x)
    return False


def _by_how_much(cause, name, x, ci):
    """How far the truth ``x`` lies outside ``ci``, in units of its cause's smallest effect worth naming."""
    q = next(q for q in catalogue.by_name(cause).params if q.name == name)
    if q.practical is None or ci is None or len(ci) != 2:
        return ""
    return f" by {max(ci[0] - x, x - ci[1]) / q.practical:.2g} of the smallest effect worth naming"


def _error(cause, name, x, estimate):
    """(estimate - truth) over the parameter's smallest effect worth naming; None without either."""
    q = next(q for q in catalogue.by_name(cause).params if q.name == name)
    return None if q.practical is None or estimate is None else (estimate - x) / q.practical


def score(entry, truth, parts=(), optional=None):
    """What a diagnosis got right of a hidden truth (the per-cell row's outcome).

    ``parts``: the (statistical intervals, systematic uncertainties) the
    diagnosis logged (:class:`_Intervals`), to count the truths its intervals
    hold by their systematic part only.  ``optional``: causes present in the
    truth below their smallest effect worth naming (the contact lab's, :func:`contact_truth`):
    named, they are scored as hidden ones (their parameters inside the
    intervals or a miss); not named, nothing is missing.

    A series whose design the diagnosis declares unable to carry its hidden
    cause (``too_small``, or the cause in its ``not_identifiable``, and not
    named) is ``not_identifiable``: said, not silently missed, and kept out
    of the named-right rate.
    """
    named = set(entry["verdict"])
    truth = {**truth, **{c: v for c, v in (optional or {}).items() if c in named}}
    hidden = set(truth)
    found = {f["effect"]: f for f in entry["findings"]}
    covered, widened, missed, missed_joint, errors = 0, 0, [], [], []
    for cause in sorted(hidden & named):
        for k, x in truth[cause].items():
            ci = found[cause].get("ci95", {}).get(k)
            errors.append(_error(cause, k, x, found[cause].get("params", {}).get(k)))
            ok = _inside(ci, x)
            covered += ok
            widened += ok and _widened_by_systematic(cause, k, x, found[cause].get("params", {}).get(k), ci, parts)
            if not ok:
                missed.append(f"{cause}.{k} = {x:g} outside {ci}{_by_how_much(cause, k, x, ci)}")
            joint = (found[cause].get("ci95_joint") or {}).get(k)
            if not _inside(joint, x):
                missed_joint.append(f"{cause}.{k} = {x:g} outside {joint}{_by_how_much(cause, k, x, joint)}")
    n_params = sum(len(truth[c]) for c in hidden & named)
    blind = entry.get("not_identifiable") or {}
    unseen = sorted(c for c in hidden - named if c in blind)
    return _named(entry, named, found, sorted(named - hidden)) | {
        "named_right": named == hidden and not missed_joint,
        "named_right_marginal": named == hidden and not missed,
        "verdict_right": named == hidden,
        "missing": sorted(hidden - named),
        "params_covered": int(covered),
        "params_widened_by_systematic": int(widened),
        "params_named": int(n_params),
        "outside": missed,
        "outside_joint": missed_joint,
        "errors_in_smallest": [e for e in errors if e is not None],
        "not_identifiable": bool(entry.get("too_small")) or bool(unseen),
        "why_not_identifiable": entry.get("too_small") or "; ".join(blind[c] for c in unseen),
    }


def _named(entry, named, found, wrong):
    """What a verdict named, the causes ``wrong`` among them, and whether one is a confident misname: a
    wrong cause named neither with the caveat that it may stand in for one the design cannot identify
    nor under the ``unexplained`` flag (the rule of :func:`score` and :func:`score_change`)."""
    caveat = {c: sorted(found.get(c, {}).get("may_stand_in_for") or {}) for c in wrong}
    return {
        "verdict": sorted(named),
        "unexplained": bool(entry["unexplained"]),
        "wrong": wrong,
        "may_stand_in_for": {c: v for c, v in caveat.items() if v},
        "confident_misname": any(not v for v in caveat.values()) and not entry["unexplained"],
        "too_small": entry.get("too_small"),
    }


#: What a crushed edge changes (:func:`score_change`): the cause and its parameter.
CHANGED = ("instability_angle", "alpha_r_over_alpha")


def score_change(entry, n_tests):
    """What a diagnosis got right of a rocking edge crushed part-way through a series (issue 42), as
    :func:`score` says it.

    Named right: a change point of the instability angle found one test or less from where the edge was
    crushed (test ``n_tests // 2``), the 95 % interval of its size holding the truth
    (:data:`CRUSHED_RATIO` - 1), and no cause named but the instability angle (a cause of the series: half its
    tests rock on the crushed edge).  The verdict is right where a change of that parameter is found, of either
    kind, anywhere.  A series whose test of a change says it cannot reject (too few tests, its ``note``) is not
    identifiable.
    """
    effect, name = CHANGED
    k, size = n_tests // 2, CRUSHED_RATIO - 1.0
    named = set(entry["verdict"])
    found = {f["effect"]: f for f in entry["findings"]}
    tested = [c for c in entry.get("changes") or [] if c["effect"] == effect and c["parameter"] == name]
    seen = [c for c in tested if c["kind"] != ChangeKind.NONE]
    placed = [c for c in seen if c["kind"] == ChangeKind.CHANGE_POINT and abs(c["where_index"] - k) <= 1]
    ci = placed[0]["ci95_size"] if placed else None
    covered = _inside(ci, size)
    wrong = sorted(named - {effect})
    notes = [c["note"] for c in tested if c.get("note")]
    untestable = bool(entry.get("too_small")) or (not seen and bool(notes))
    outside = (
        []
        if covered or not placed
        else [f"change of {name} = {size:+g} outside {ci}{_by_how_much(effect, name, size, ci)}"]
    )
    return _named(entry, named, found, wrong) | {
        "named_right": covered and not wrong,
        "named_right_marginal": covered and not wrong,
        "verdict_right": bool(seen) and not wrong,
        "missing": [] if seen else [f"a change of {effect}.{name} by {size:+g} from test {k}"],
        "params_covered": int(covered),
        "params_widened_by_systematic": 0,
        "params_named": len(placed[:1]),
        "outside": outside,
        "outside_joint": outside,
        "errors_in_smallest": [_error(effect, name, size, placed[0]["size"])] if placed else [],
        "not_identifiable": untestable,
        "why_not_identifiable": (entry.get("too_small") or "; ".join(notes)) if untestable else "",
    }


#: The contact lab's cells (:mod:`rocklab.lab.contact_lab`): knob -> (ContactModel keywords, VirtualTest.alpha_ratio),
#: the docs' table (docs/virtual-lab.md) of which knob stands for which cause.  Every cell on near-sharp edges
#: (0.05 mm): the default 0.5 mm rounding puts alpha_r / alpha at 0.991-0.994, beyond instability_angle's smallest
#: effect worth naming, on every wall.  ``low_mu`` is a share of alpha: the impulse an impact needs grows with it.
CONTACT_KNOBS = {
    "default": ({}, None),
    "zeta": ({"zeta": 0.01}, None),
    "inset": ({}, 0.9),
    "impedance": ({"impedance": (0.5, 0.9, 0.001)}, None),
    "low_mu": ({"mu_over_alpha": 0.7}, None),
    "soft_contact": ({"contact_time_s": 0.01}, None),
}
EDGE_RADIUS_MM = 0.05
#: Series of each contact cell (the default one at each rate instead), on the shuffle's combinations.
CONTACT_REPLICATES = 2
#: The contact lab's truths, read from the block (:func:`contact_truth`): cause -> (parameter, what gives it).
CONTACT_PARAMS = {
    "restitution_scale": "c",
    "flight_damping": "zeta",
    "instability_angle": "alpha_r_over_alpha",
}


def contact_design(seeds=DESIGN_SEEDS, replicates=CONTACT_REPLICATES):
    """The contact lab's designs of the shuffles ``seeds`` (two-sided walls only): each knob of
    :data:`CONTACT_KNOBS` ``replicates`` times, the default contact at each rate, on the combinations of
    rate, slenderness and size of the virtual design's shuffle; series numbered on."""
    combos = [(fs, w, n) for fs in RATES for w in WALLS for n in SIZES]
    rows = []
    for seed in seeds:
        order = np.random.default_rng(seed).permutation(len(combos))
        cells = [(k, j) for k in CONTACT_KNOBS if k != "default" for j in range(replicates)]
        cells += [("default", j) for j in range(len(RATES))]
        for i, (knob, j) in enumerate(cells):
            fs, w, n = combos[order[i % len(combos)]]
            if knob == "default":
                fs = RATES[j]
            rows.append(
                {"generator": "contact", "knob": knob, "boundary": "two-sided", "fs": fs, "wall": w}
                | {"n_tests": n, "design_seed": seed, "seed": len(rows)}
            )
    return rows


def _worth_naming(cause, values):
    """Whether a cause's true parameters depart from its null by more than its smallest effect worth naming."""
    return any(abs(values[q.name] - q.null) > (q.practical or 0.0) for q in catalogue.by_name(cause).params)


def contact_truth(truths):
    """(required, optional) truths of a contact-lab series from its tests' measured truths (truth.csv's fields).

    The rule, from the block's physics, before any diagnosis: ``c`` =
    median over tests of e_true / e_analytic, the block's measured e (the
    median of its contact episodes) over Eq. 2 at the nominal alpha, which
    is the e of the diagnosis' base model (``wall_model.e0``, also under
    ``instability_angle``); ``zeta`` = median of ``zeta_flight``, the viscous
    zeta that loses what the block's long flights lose
    (:func:`rocklab.lab.contact_lab.flight_zeta`: the knob and the pivot's
    spring-damper); ``alpha_r_over_alpha`` = ``alpha_rock`` / ``alpha``.  A
    cause whose parameter departs from its null by more than its smallest
    effect worth naming (the catalogue's ``practical``) is required; below,
    optional (:func:`score`).
    """
    values = {
        "restitution_scale": {"c": float(np.median([t["e_true"] / t["e_analytic"] for t in truths]))},
        "flight_damping": {"zeta": float(np.nanmedian([t["columns"]["zeta_flight"] for t in truths]))},
        "instability_angle": {"alpha_r_over_alpha": float(truths[0]["alpha_rock"] / truths[0]["alpha"])},
    }
    values = {c: v for c, v in values.items() if all(np.isfinite(list(v.values())))}
    required = {c: v for c, v in values.items() if _worth_naming(c, v)}
    return required, {c: v for c, v in values.items() if c not in required}


def _contact_records(name, sp, row, noise_mm=NOISE_MM):
    """The records of a contact-lab series as :func:`rocklab.lab.virtual_lab.series_records` makes the virtual
    lab's (the same tests, release draws, instruments and noise), and the truths of its tests."""
    model, alpha_ratio = CONTACT_KNOBS[row["knob"]]
    alpha = float(wall.slenderness_angle(sp["height_mm"], sp["thickness_mm"]))
    model = {"edge_radius_mm": EDGE_RADIUS_MM, **model}
    if "mu_over_alpha" in model:
        model["mu"] = model.pop("mu_over_alpha") * alpha
    truths = []

    def simulate(test, specimen, layout, rng=None, t_end=RECORD_S):
        t, E, truth = contact_lab.simulate_contact_test(test, specimen, layout, rng, t_end)
        truths.append(truth)
        return t, E, truth

    recs = vl.series_records(
        name,
        sp,
        "two-sided",
        model,
        n=row["n_tests"],
        fs=row["fs"],
        seed=row["seed"],
        t_end=RECORD_S,
        noise_mm=noise_mm,
        alpha_ratio=alpha_ratio,
        simulate=simulate,
    )
    return recs, truths


def _scenario_of(row, sp):
    """The simulated boundary and :func:`scenario` of a design row on the wall ``sp`` (the virtual lab's
    generators: in memory or through the lab's files)."""
    alpha = float(wall.slenderness_angle(sp["height_mm"], sp["thickness_mm"]))
    boundary = "two-sided" if row["boundary"] == "two-sided" else "one-sided"
    return (boundary, *scenario(row["cause"], row["boundary"], alpha, row["n_tests"]))


def run_cell(row, n_boot, noise_mm=NOISE_MM):
    """Simulate and diagnose one series of the design; its row with the outcome and the times."""
    t0 = time.perf_counter()
    sp = WALLS[row["wall"]]
    optional, extra = {}, {}
    if row.get("generator") == "contact":
        sp = sp.copy()
        # the block's mass scales only the contact forces (contact_lab.simulate_contact): the clay's for all
        sp["unit_weight_kN_m3"] = _SPEC.loc["1a", "unit_weight_kN_m3"]
        name = f"contact-{row['knob']}-{row['seed']}"
        recs, truths = _contact_records(name, sp, row, noise_mm)
        truth, optional = contact_truth(truths)
        row = {**row, "cause": "+".join(sorted(truth)) or "null"}
        extra = {"truth": truth, "optional": optional, "n_lifted": sum(t["columns"]["n_lifted"] for t in truths)}
        extra["max_slip_mm"] = max(t["columns"]["max_slip_mm"] for t in truths)
    elif row.get("generator") == "recorded":
        boundary, model, kw, truth = _scenario_of(row, sp)
        # a test id is a file name: no brackets (flight_loss[drag])
        name = re.sub(r"[^\w-]", "-", f"{row['instrument']}-{row['cause']}-{row['boundary']}-{row['seed']}")
        faults = [vl.Fault("gain", FAULTY_CHANNEL, level=FAULTY_GAIN)] if row["class"] == "instrument error" else []
        recs, rejected = recorded_series(
            name,
            RECORDED_WALLS[row["wall"]],
            boundary,
            model,
            instrument=row["instrument"],
            n=row["n_tests"],
            fs=row["fs"],
            seed=row["seed"],
            t_end=RECORDED_S,
            noise_mm=noise_mm,
            faults=faults,
            **kw,
        )
        extra = {"truth": truth, "rejected": rejected}
    else:
        boundary, model, kw, truth = _scenario_of(row, sp)
        name = f"{row['cause']}-{row['boundary']}-{row['seed']}"
        recs = vl.series_records(
            name,
            sp,
            boundary,
            model,
            n=row["n_tests"],
            fs=row["fs"],
            seed=row["seed"],
            t_end=RECORD_S,
            noise_mm=noise_mm,
            **kw,
        )
    t1 = time.perf_counter()
    logger = logging.getLogger("rocklab.diagnosis.estimation.resampling")
    parts = _Intervals()
    logger.addHandler(parts)
    level = logger.level
    logger.setLevel(logging.INFO)
    try:
        entry = diagnose_records(recs, name, n_boot=n_boot, n_history=0, seed=0)
    finally:
        logger.removeHandler(parts)
        logger.setLevel(level)
    entry = (
        {"verdict": [], "findings": [], "unexplained": False, "too_small": "no test of two impacts"}
        if entry is None
        else entry.to_dict()
    )
    scored = (
        score_change(jsonable(entry), row["n_tests"])
        if row["cause"] == "edge_crushed"
        else score(jsonable(entry), truth, parts.parts, optional)
    )
    out = {"generator": "virtual", **row, "h_over_b": float(sp["height_mm"] / sp["thickness_mm"]), **scored, **extra}
    out["n_impacts"] = int(entry.get("n_impacts", 0))
    return out | {"simulate_s": t1 - t0, "diagnose_s": time.perf_counter() - t1}


def binomial_interval(k, n, level=0.95):
    """Clopper-Pearson interval of a share k / n: what n units can say of a rate."""
    if n == 0:
        return None
    a = 1.0 - level
    lo = float(stats.beta.ppf(a / 2, k, n - k + 1)) if k > 0 else 0.0
    hi = float(stats.beta.ppf(1 - a / 2, k + 1, n - k)) if k < n else 1.0
    return [lo, hi]


def rates(cells):
    """The four measures of calibration over the cells run, the counts they rest on and their binomial
    intervals: a rate over a few dozen series or parameters is known to some +- 0.1.

    The named-right rate is over the series with a hidden cause whose design
    can carry it (``n_not_identifiable`` the others, said by the diagnosis).
    """
    df = pd.DataFrame(cells)
    null = df[df.cause == "null"]
    caused = df[df.cause != "null"]
    seen = caused[~caused.not_identifiable]
    named = int(df.params_named.sum())
    covered = int(df.params_covered.sum())
    false = int((null.wrong.map(len) > 0).sum())
    confident = int(df.confident_misname.sum())
    right = int(seen.named_right.sum())
    verdicts = seen[seen.verdict_right]
    coverage = covered / named if named else None
    return {
        "n_series": len(df),
        "n_null": len(null),
        "n_caused": len(caused),
        "n_not_identifiable": int(caused.not_identifiable.sum()),
        "not_identifiable": [
            f"{c.cause} ({c.boundary}, {c.fs:.0f} Hz, {c.wall}, {c.n_tests} tests): {c.why_not_identifiable}"
            for c in caused[caused.not_identifiable].itertuples()
        ],
        "named_right_rate": right / len(seen) if len(seen) else None,
        "named_right_ci95": binomial_interval(right, len(seen)),
        "named_right_marginal_rate": int(seen.named_right_marginal.sum()) / len(seen) if len(seen) else None,
        "verdict_right_rate": len(verdicts) / len(seen) if len(seen) else None,
        "verdict_right_ci95": binomial_interval(len(verdicts), len(seen)),
        # every true parameter of a series inside its interval, were each inside with the measured coverage
        # independently: what intervals of that coverage let the named-right rate reach on these verdicts
        "named_right_at_coverage": (
            float(np.mean(coverage ** verdicts.params_named.to_numpy(float))) * len(verdicts) / len(seen)
            if len(seen) and coverage is not None and len(verdicts)
            else None
        ),
        # the gap of a null wall with a gap is its truth, not a false name
        "false_name_rate_null": false / len(null) if len(null) else None,
        "false_name_ci95": binomial_interval(false, len(null)),
        "confident_misname_rate": confident / len(df) if len(df) else None,
        "confident_misname_ci95": binomial_interval(confident, len(df)),
        "coverage_95": coverage,
        "coverage_ci95": binomial_interval(covered, named),
        "n_params_named": named,
        "n_params_widened_by_systematic": int(df.params_widened_by_systematic.sum()),
        "pooled_bias": _pooled_bias(df),
    }


def _pooled_bias(df):
    """Mean signed error of the named parameters in units of their smallest effect worth naming, the
    series the units of its interval (:func:`rocklab.diagnosis.pooling.pooled_bias`)."""
    err = [(e, s) for s, errs in zip(df.index, df.errors_in_smallest) for e in errs]  # a row is a series
    if not err:
        return None
    b = pooled_bias([e for e, _ in err], [0.0] * len(err), [1.0] * len(err), [str(s) for _, s in err], "series")
    return {"mean": b.mean, "ci95": b.ci95, "n_series": b.n_units, "note": b.note}


def _met(value, bounds):
    lo, hi = bounds
    return value is not None and (lo is None or value >= lo) and (hi is None or value <= hi)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/bench"))
    ap.add_argument("--budget-s", type=float, default=1200.0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--n-boot", type=int, default=40)
    ap.add_argument("--design-seeds", type=int, nargs="+", default=list(DESIGN_SEEDS))
    ap.add_argument("--replicates", type=int, default=REPLICATES)
    ap.add_argument("--noise-mm", type=float, default=NOISE_MM, help="noise and hum of every channel [mm]")
    ap.add_argument("--generator", choices=(*GENERATORS, "all"), default="all")
    args = ap.parse_args()
    t0 = time.perf_counter()
    gens = GENERATORS if args.generator == "all" else (args.generator,)
    rows = design(args.design_seeds, args.replicates) if "virtual" in gens else []
    rows += contact_design(args.design_seeds) if "contact" in gens else []
    rows += recorded_design(args.design_seeds) if "recorded" in gens else []
    cells, skipped = [], []
    with ProcessPoolExecutor(args.workers) as pool:
        pending = {pool.submit(run_cell, row, args.n_boot, args.noise_mm): row for row in rows[: args.workers]}
        queue = rows[args.workers :]
        while pending:
            done = next(as_completed(pending))
            pending.pop(done)
            cells.append(done.result())
            c = cells[-1]
            print(
                f"{c['generator']:8s} {c.get('knob', c.get('instrument', '')):13s}{c['cause']:24s} "
                f"{c['boundary']:14s} {c['fs']:5.0f} Hz "
                f"{c['wall']:8s} {c['n_tests']:2d} tests: "
                f"{','.join(c['verdict']) or '-'}{' right' if c['named_right'] else ''} "
                f"({c['simulate_s'] + c['diagnose_s']:.0f} s)",
                flush=True,
            )
            if queue and time.perf_counter() - t0 < args.budget_s:
                nxt = queue.pop(0)
                pending[pool.submit(run_cell, nxt, args.n_boot, args.noise_mm)] = nxt
            elif queue:
                skipped, queue = queue, []
    cells.sort(key=lambda c: (GENERATORS.index(c["generator"]), c["seed"]))
    by_generator = {}
    for g in gens:
        mine = [c for c in cells if c["generator"] == g]
        r = rates(mine) if mine else {}
        r["targets"] = {k: {"low": lo, "high": hi, "met": _met(r.get(k), (lo, hi))} for k, (lo, hi) in TARGETS.items()}
        r["n_skipped"] = sum(row.get("generator", "virtual") == g for row in skipped)
        r["pass"] = all(t["met"] for t in r["targets"].values()) and not r["n_skipped"]
        if g == "recorded" and mine:
            r["by_class"] = {
                k: rates([c for c in mine if c["class"] == k]) for k in dict.fromkeys(c["class"] for c in mine)
            }
        by_generator[g] = r
    # the top level: the virtual lab's rates, the page's (rocklab.benchmarks._discovery); the contact lab's alone
    result = dict(by_generator[gens[0]])
    result["by_generator"] = by_generator
    result["pass"] = all(r["pass"] for r in by_generator.values())
    result["design"] = (
        f"fractional: each (cause, boundary) cell and each null (boundary, rate) cell {args.replicates} "
        f"time{'s' if args.replicates != 1 else ''}, each with another of the "
        f"{len(RATES) * len(WALLS) * len(SIZES)} combinations of rate, slenderness and size from a fixed shuffle"
    )
    result["contact_design"] = (
        f"each contact knob ({', '.join(k for k in CONTACT_KNOBS if k != 'default')}) {CONTACT_REPLICATES} times, "
        "the default contact at each rate, two-sided, on the same shuffles"
    )
    result["recorded_design"] = (
        f"each of {len(RECORDED_CELLS)} cells (class, cause, boundary, instrument, rate) once per shuffle, on the "
        "paper's or the slender wall, written in the lab's format and reduced as the workflow does"
    )
    result["generators"] = list(gens)
    result["design_seeds"] = args.design_seeds
    result["replicates"] = args.replicates
    result["n_skipped"] = len(skipped)
    result["wall_s"] = time.perf_counter() - t0
    result["workers"] = args.workers
    result["n_boot"] = args.n_boot
    result["noise_mm"] = args.noise_mm
    result["cells"] = cells
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "discovery.json").write_text(json.dumps(jsonable(result), indent=1))
    for g, r in by_generator.items():
        print(
            f"{g}: {r.get('n_series', 0)} series: named right {r.get('named_right_rate')} "
            f"({r.get('n_not_identifiable')} not identifiable), false names on nulls {r.get('false_name_rate_null')}, "
            f"confident misnames {r.get('confident_misname_rate')}, coverage {r.get('coverage_95')}, "
            f"pooled bias {r.get('pooled_bias')}"
        )
    print(f"in {result['wall_s']:.0f} s")
    return 0 if result["pass"] else 1


if __name__ == "__main__":
    raise SystemExit(main())
