"""The scoring of bench/discovery.py: what counts as named right, not identifiable, a confident misname."""

import importlib.util
from pathlib import Path

import pytest

from rocklab.benchmarks import _discovery, _miss

_spec = importlib.util.spec_from_file_location("discovery", Path(__file__).parents[1] / "bench" / "discovery.py")
discovery = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(discovery)


def entry(verdict, findings=(), unexplained=False, **kw):
    return {"verdict": list(verdict), "findings": list(findings), "unexplained": unexplained, **kw}


def test_the_binomial_interval_meets_its_closed_forms_at_the_ends():
    n = 36
    # none or all of n: the one-sided Clopper-Pearson bound is (alpha / 2)^(1/n)
    assert discovery.binomial_interval(0, n) == pytest.approx([0.0, 1 - 0.025 ** (1 / n)])
    assert discovery.binomial_interval(n, n) == pytest.approx([0.025 ** (1 / n), 1.0])
    lo, hi = discovery.binomial_interval(18, n)
    assert lo < 0.5 < hi and hi - 0.5 == pytest.approx(0.5 - lo)
    assert discovery.binomial_interval(0, 0) is None


def test_a_series_that_says_its_cause_is_not_identifiable_is_counted_apart():
    truth = {"restitution_drift": {"c": 0.93, "drift": 0.15}}
    why = "a drift is a slope over tests and needs 4 of them, the series has 3"
    s = discovery.score(entry([], not_identifiable={"restitution_drift": why}), truth)
    assert s["not_identifiable"] and s["why_not_identifiable"] == why and not s["named_right"]
    silent = discovery.score(entry([]), truth)
    assert not silent["not_identifiable"] and silent["missing"] == ["restitution_drift"]
    small = discovery.score(entry([], too_small="one test"), truth)
    assert small["not_identifiable"] and small["why_not_identifiable"] == "one test"


def test_a_wrong_name_is_confident_unless_flagged():
    truth = {"flight_damping": {"zeta": 0.01}}
    finding = {"effect": "restitution_scale", "params": {"c": 0.97}, "ci95": {"c": [0.96, 0.98]}}
    assert discovery.score(entry(["restitution_scale"], [finding]), truth)["confident_misname"]
    assert not discovery.score(entry(["restitution_scale"], [finding], unexplained=True), truth)["confident_misname"]


def test_a_wrong_name_that_may_stand_in_for_a_hidden_cause_is_not_confident():
    truth = {"flight_damping": {"zeta": 0.01}}
    why = "2 flights above 0.3 alpha (5 needed)"
    scale = {"effect": "restitution_scale", "params": {"c": 0.97}, "ci95": {"c": [0.96, 0.98]}}
    caveat = {**scale, "may_stand_in_for": {"flight_damping": why}}
    blind = {"not_identifiable": {"flight_damping": why}}
    s = discovery.score(entry(["restitution_scale"], [caveat], **blind), truth)
    assert not s["confident_misname"] and s["may_stand_in_for"] == {"restitution_scale": ["flight_damping"]}
    assert s["not_identifiable"] and s["wrong"] == ["restitution_scale"]
    # a second wrong name without the caveat is still confident
    angle = {"effect": "instability_angle", "params": {"alpha_r_over_alpha": 0.99}, "ci95": {}}
    both = discovery.score(entry(["restitution_scale", "instability_angle"], [caveat, angle], **blind), truth)
    assert both["confident_misname"]
    row = {"cause": "flight_damping", "boundary": "one-sided-gap", "fs": 400.0, "wall": "paper", "n_tests": 10}
    assert "restitution_scale (may stand in for flight_damping" in _miss({**row, **s})
    assert "instability_angle (not flagged)" in _miss({**row, **both})


def test_coverage_counts_the_truths_held_by_the_systematic_part_only():
    from rocklab.diagnosis.estimation.systematic import widened

    truth = {"restitution_scale": {"c": 0.95}}
    stat, u = [0.9504, 0.9506], 0.0003
    ci = widened(stat, 0.9505, 0.2, 2.0, u)
    found = {"effect": "restitution_scale", "params": {"c": 0.9505}, "ci95": {"c": ci}, "ci95_joint": {"c": ci}}
    parts = [({"c": [0.9, 1.0]}, {"c": 0.0}), ({"c": stat}, {"c": u})]
    s = discovery.score(entry(["restitution_scale"], [found]), truth, parts)
    assert s["named_right"] and s["params_covered"] == 1 and s["params_widened_by_systematic"] == 1
    # widened again by the model's bias (rocklab.diagnosis.estimation.bias): still by the systematic part
    wider = {**found, "ci95": {"c": widened(ci, 0.9505, 0.2, 2.0, 0.0002)}}
    assert discovery.score(entry(["restitution_scale"], [wider]), truth, parts)["params_widened_by_systematic"] == 1
    # a statistical interval that holds the truth on its own
    held = [({"c": [0.949, 0.951]}, {"c": u})]
    found_held = {**found, "ci95": {"c": widened([0.949, 0.951], 0.9505, 0.2, 2.0, u)}}
    assert discovery.score(entry(["restitution_scale"], [found_held]), truth, held)["params_widened_by_systematic"] == 0
    # no logged part gives the interval: nothing counted
    assert discovery.score(entry(["restitution_scale"], [found]), truth)["params_widened_by_systematic"] == 0
    # a miss says by how much, in units of the smallest effect worth naming (0.005 for c)
    missed = {**found, "ci95": {"c": [0.9525, 0.96]}}
    (outside,) = discovery.score(entry(["restitution_scale"], [missed]), truth)["outside"]
    assert outside.endswith("by 0.5 of the smallest effect worth naming")


def test_the_rates_leave_the_not_identifiable_out_of_the_named_right_rate():
    row = {"boundary": "two-sided", "fs": 400.0, "wall": "paper", "n_tests": 3}
    scale = {"restitution_scale": {}}
    cells = [
        {**row, "cause": "restitution_scale", **discovery.score(entry(["restitution_scale"]), scale)},
        {**row, "cause": "restitution_drift", **discovery.score(entry([], too_small="one test"), {"x": {}})},
        {**row, "cause": "null", **discovery.score(entry(["stop_threshold"]), {})},
    ]
    r = discovery.rates(cells)
    assert r["named_right_rate"] == 1.0 and r["n_not_identifiable"] == 1
    assert r["not_identifiable"] == ["restitution_drift (two-sided, 400 Hz, paper, 3 tests): one test"]
    assert r["false_name_rate_null"] == 1.0 and r["confident_misname_rate"] == pytest.approx(1 / 3)
    bench = {
        **r,
        **{k: 0 for k in ("n_skipped", "wall_s", "workers")},
        "design_seeds": [0],
        "design": "d",
        "pass": False,
        "targets": {"named_right_rate": {"met": True}, "coverage_95": {"met": False}},
        "cells": [{**c, "h_over_b": 9.6, "n_impacts": 10, "design_seed": 0} for c in cells],
    }
    d = _discovery(bench)
    assert d["missed"] == ["coverage_95"]
    assert [c["miss"] for c in d["cells"]] == [
        "",
        "not identifiable: one test",
        "named beside the truth: stop_threshold (not flagged)",
    ]


def test_the_named_right_rate_splits_into_verdicts_and_their_intervals():
    """Two right verdicts, one of two parameters with one outside its interval, one of one inside; a wrong
    verdict: verdicts right 2/3, named right 1/3, coverage 2/3, and at that coverage the right verdicts
    would be all inside with probability (2/3)^2 and 2/3: (4/9 + 2/3) / 2 of them, times 2/3.  Named
    right reads the simultaneous intervals: where those of the first hold both, it is named right, its own
    intervals still miss (named right against them 1/3)."""
    row = {"boundary": "two-sided", "fs": 400.0, "wall": "paper", "n_tests": 5}
    two = {"restitution_amplitude": {"a": 1.0, "b": 0.1}}
    both = {
        "effect": "restitution_amplitude",
        "params": {"a": 1.0, "b": 0.1},
        "ci95": {"a": [0.9, 1.1], "b": [0.2, 0.3]},
        "ci95_joint": {"a": [0.85, 1.15], "b": [0.05, 0.35]},
    }
    one = {"restitution_scale": {"c": 0.95}}
    inside = {"effect": "restitution_scale", "params": {"c": 0.95}, "ci95": {"c": [0.94, 0.96]}}
    inside["ci95_joint"] = inside["ci95"]
    cells = [
        {**row, "cause": "restitution_amplitude", **discovery.score(entry(["restitution_amplitude"], [both]), two)},
        {**row, "cause": "restitution_scale", **discovery.score(entry(["restitution_scale"], [inside]), one)},
        {**row, "cause": "restitution_scale", **discovery.score(entry(["instability_angle"], []), one)},
    ]
    r = discovery.rates(cells)
    assert r["verdict_right_rate"] == pytest.approx(2 / 3) and r["named_right_marginal_rate"] == pytest.approx(1 / 3)
    assert r["named_right_rate"] == pytest.approx(2 / 3)
    assert cells[0]["outside"] and not cells[0]["outside_joint"]
    assert r["coverage_95"] == pytest.approx(2 / 3)
    assert r["named_right_at_coverage"] == pytest.approx((4 / 9 + 2 / 3) / 2 * 2 / 3)
