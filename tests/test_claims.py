"""The margins of the claims (rocklab.dissipation.claims): each the smallest change of a parameter
that changes the reference wall's simulated free-rocking duration by the tolerance, shipped for
every parameter of the catalogue, recomputed here on a cheap instance."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from rocklab.diagnosis import catalogue
from rocklab.dissipation.claims import (
    DURATION_TOLERANCE,
    PAPER_CLAIMS,
    free_rocking_duration,
    margin_of,
    margin_rule,
    margins,
    outcome_margin,
    reference_value,
    reference_wall,
    verdict,
)
from rocklab.physics import restitution


def _duration(boundary, cause, parameter, value):
    return free_rocking_duration(reference_wall(boundary, cause, {parameter: value}))


def test_the_shipped_margins_cover_every_parameter_of_the_catalogue_in_its_boundary_conditions():
    expected = {(c.name, q.name, b) for c in catalogue.in_order() for q in c.params for b in c.boundaries}
    table = margins()
    assert set(zip(table.cause, table.parameter, table.boundary)) == expected
    assert len(table) == len(expected)


@pytest.mark.parametrize("cause, parameter", [("restitution_scale", "c"), ("instability_angle", "alpha_r_over_alpha")])
def test_a_shipped_margin_is_recomputed(cause, parameter):
    # the one-sided wall comes to rest in about ten impacts: a cheap instance of the table
    table = margins().set_index(["cause", "parameter", "boundary"])
    shipped = table.loc[(cause, parameter, "one-sided")]
    assert outcome_margin(cause, parameter, "one-sided") == pytest.approx(shipped.margin, rel=1e-3)
    v0 = reference_value(cause, parameter, "one-sided")
    assert _duration("one-sided", cause, parameter, v0) == pytest.approx(shipped.duration_p, rel=1e-5)


def test_the_margin_changes_the_duration_by_the_tolerance_and_a_smaller_change_by_less():
    """The defining property, checked on the simulator directly: at the margin (the side it was found
    on) the duration changes by the tolerance, at half of it by about half as much (a smooth outcome)."""
    cause, parameter, boundary = "restitution_scale", "c", "one-sided"
    v0 = reference_value(cause, parameter, boundary)
    m = margin_of("e_ratio", boundary)
    d0 = _duration(boundary, cause, parameter, v0)
    changes = {s: abs(_duration(boundary, cause, parameter, v0 + s * m) / d0 - 1) for s in (1, -1)}
    assert max(changes.values()) == pytest.approx(DURATION_TOLERANCE, rel=1e-2)
    assert min(changes.values()) <= DURATION_TOLERANCE * (1 + 1e-2)
    half = max(abs(_duration(boundary, cause, parameter, v0 + s * m / 2) / d0 - 1) for s in (1, -1))
    assert 0.3 * DURATION_TOLERANCE < half < 0.7 * DURATION_TOLERANCE


def test_the_duration_of_the_reference_wall_follows_housner_closed_form():
    """Independent check of the outcome: Housner's two-sided wall released from rest at theta0 lands at
    the speed of his energy balance, each impact keeps e of it, and each flight of apex A lasts
    4 acosh(1 / (1 - A / alpha)) / p (his piecewise-linear flight, exact for the linear form)."""
    from dataclasses import replace

    model = replace(reference_wall("two-sided"), form="linear")
    alpha, e = model.alpha, restitution.CALIBRATED_RATIO_TWO_SIDED * restitution.two_sided(model.alpha)
    phi, total = 0.9, math.acosh(1 / (1 - 0.9))
    # apex after an impact: the landing speed of a flight of apex phi, (1 - phi)^2 ... in Housner's variables
    while True:
        v = math.sqrt(1 - (1 - phi) ** 2)  # thetadot / (p alpha) at the impact
        w = e * v
        if w < 1e-3 * math.sqrt(2 * (1 - math.cos(alpha))) / alpha:
            break
        phi = 1 - math.sqrt(1 - w**2)
        total += 2 * math.acosh(1 / (1 - phi))
    assert free_rocking_duration(model) == pytest.approx(total, rel=2e-3)


def test_responses_take_their_parameters_margin_and_the_smaller_across_boundaries():
    table = margins().set_index(["cause", "parameter", "boundary"]).margin
    for b in ("two-sided", "one-sided"):
        assert margin_of("e_ratio", b) == table[("restitution_scale", "c", b)]
        assert margin_of("theta0_over_alpha", b) == table[("instability_angle", "alpha_r_over_alpha", b)]
        assert margin_of("restitution_amplitude.b", b) == table[("restitution_amplitude", "b", b)]
    assert margin_of("e_ratio") == min(margin_of("e_ratio", b) for b in ("two-sided", "one-sided"))
    # a one-sided cause: its one wall
    assert margin_of("contact_gap.gap_over_alpha") == margin_of("contact_gap.gap_over_alpha", "one-sided")


def test_a_parameter_without_a_simulated_consequence_has_no_margin_and_no_support():
    # a drift acts nowhere on a wall in mid-series, nor the scatter of a stop threshold on its mean wall
    for response in ("restitution_drift.drift", "stop_threshold.spread_log", "nothing"):
        assert np.isnan(margin_of(response))
        assert verdict("zero", -1e-9, 1e-9, 0.9, 0.0, margin_of(response)) == "inconclusive"
    assert "restitution_drift.drift" in margin_rule()["none"]
    # recomputed: no change in the whole range reaches the tolerance
    assert np.isnan(outcome_margin("restitution_drift", "drift", "one-sided"))


def test_a_law_of_the_impact_speed_acts_on_the_simulated_wall_and_has_its_margin():
    """The exact simulator carries the law of the impact speed (physics.impact.SpeedLaw): its knots
    change the simulated outcome, more on the slender two-sided wall, which impacts at many speeds."""
    two, one = margin_of("restitution_speed.g0", "two-sided"), margin_of("restitution_speed.g0", "one-sided")
    assert 0 < two < one < 1
    assert outcome_margin("restitution_speed", "g0", "two-sided") == pytest.approx(two, rel=1e-4)


def test_any_contact_gap_changes_the_outcome_its_margin_is_zero():
    """Inside a gap the wall rocks two-sided (Fig. 12): the duration jumps at the smallest gap."""
    assert margin_of("contact_gap.gap_over_alpha", "one-sided") == 0.0
    d0 = _duration("one-sided", "contact_gap", "gap_over_alpha", 0.0)
    assert _duration("one-sided", "contact_gap", "gap_over_alpha", 1e-4) > 2 * d0
    assert verdict("zero", -1e-6, 1e-6, 0.9, 0.0, 0.0) == "inconclusive"


def test_two_close_to_statements_on_one_mean_cannot_both_be_supported():
    """Every pair of the paper's "close to" statements on one mean lies further apart than twice its margin."""
    near = [c for c in PAPER_CLAIMS if c.kind == "near"]
    for a, b in itertools.combinations(near, 2):
        if (a.boundary, a.response) == (b.boundary, b.response):
            assert abs(a.value - b.value) > 2 * margin_of(a.response, a.boundary), (a.key, b.key)


def test_the_rule_in_numbers():
    rule = margin_rule()
    assert rule["tolerance"] == DURATION_TOLERANCE
    assert rule["scale"] == {
        "two-sided": restitution.CALIBRATED_RATIO_TWO_SIDED,
        "one-sided": restitution.CALIBRATED_RATIO_ONE_SIDED,
    }
    # the two-sided wall, four times less damped, rocks longer
    assert rule["duration_p"]["two-sided"] > 4 * rule["duration_p"]["one-sided"]
    assert rule["zero"] == ["contact_gap.gap_over_alpha"]


def test_no_effect_claims_follow_their_margin_whatever_the_p():
    """A no-effect claim is about an effect that matters (issue 41): an effect the test detects but the
    interval holds within the margin is negligible (supported), one it puts beyond the margin
    contradicts, one that straddles it is inconclusive; with no margin known, only the test can
    contradict the claim of no effect at all."""
    assert verdict("zero", 0.001, 0.004, 1e-6, 0.0, 0.01) == "supported"
    assert verdict("zero", 0.02, 0.05, 1e-6, 0.0, 0.01) == "contradicted"
    assert verdict("zero", -0.05, -0.02, 0.3, 0.0, 0.01) == "contradicted"
    assert verdict("zero", 0.005, 0.02, 1e-6, 0.0, 0.01) == "inconclusive"
    assert verdict("zero", -0.005, 0.005, 0.6, 0.0, 0.01) == "supported"
    assert verdict("zero", 0.001, 0.004, 1e-6, 0.0, np.nan) == "contradicted"
    assert verdict("zero", -0.001, 0.004, 0.6, 0.0, np.nan) == "inconclusive"
