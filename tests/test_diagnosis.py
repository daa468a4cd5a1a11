"""Model diagnosis: the peak map against the exact simulator, and hidden effects recovered."""

import json

import numpy as np
import pytest

from rocklab import diagnosis as D
from rocklab import impact as I
from rocklab.rocking import RockingModel, simulate_free
from rocklab.wall import frequency_parameter, half_diagonal, quarter_period_housner, slenderness_angle

ALPHA = float(slenderness_angle(1.3, 0.12))
P = float(frequency_parameter(half_diagonal(1.3, 0.12)))


def _sim_peaks(model, theta0, t_end=8.0):
    """Outer peaks |theta_k| of the exact simulator (inner gap excursions dropped)."""
    h = simulate_free(model, theta0, 0.0, t_end=t_end, fs=400)
    imp = h.impacts
    pk = imp.theta_peak_before.to_numpy()
    keep = np.ones(pk.size, bool)
    if model.gap > 0:
        keep = (imp.kind.to_numpy() == "base") & (imp.thetadot_before.to_numpy() < 0)
        keep[0] = True
    return pk[keep]


@pytest.mark.parametrize("kw, values, boundary, rtol", [
    ({}, {}, "two-sided", 1e-6),
    ({"impact": I.Scaled(I.HousnerTwoSided(), 0.9)}, {"c": 0.9}, "two-sided", 1e-6),
    ({"alpha_rock": 0.85 * ALPHA}, {"alpha_r_over_alpha": 0.85}, "two-sided", 1e-6),
    ({"impact": I.Sided(I.Scaled(I.HousnerTwoSided(), np.exp(0.1)), I.Scaled(I.HousnerTwoSided(), np.exp(-0.1)))},
     {"s": 0.2}, "two-sided", 1e-6),
    # first-order energy loss in flight: small zeta only
    ({"flight_damping": 0.01}, {"zeta": 0.01}, "two-sided", 5e-3),
    ({}, {}, "one-sided", 1e-6),
    ({"impact": I.AmplitudeLaw(I.OneSided(), 1.2, 0.4)}, {"a": 1.2, "b": 0.4}, "one-sided", 1e-6),
    ({"gap": 0.1 * ALPHA}, {"gap_over_alpha": 0.1}, "one-sided", 1e-6),
])
def test_peak_map_matches_simulate_free(kw, values, boundary, rtol):
    model = RockingModel(alpha=ALPHA, p=P, boundary=boundary, **kw)
    theta0 = 0.8 * model.alpha_pos
    pk = _sim_peaks(model, theta0)
    n = min(pk.size - 1, 6)
    ps = D.PeakSeries("x", ALPHA, P, boundary, "push", 1, pk[: n + 1], 0.0, np.zeros(n), 1.0, 1e-6)
    M = D.free_peaks(np.array([theta0]), np.array([1.0]), D.model_params([ps], (), values), n)[0]
    big = pk[1: n + 1] > 1e-3 * ALPHA      # the simulator logs peaks to 1e-4 alpha
    np.testing.assert_allclose(M[big], pk[1: n + 1][big], rtol=rtol)


def test_quarter_period_exact_and_housner_limit():
    # exact block: the simulator's first impact; slender block: Housner's closed form
    h = simulate_free(RockingModel(alpha=ALPHA, p=P), 0.9 * ALPHA, 0.0, t_end=2.0, fs=400)
    assert D.quarter_period(0.9 * ALPHA, ALPHA, P) == pytest.approx(h.impacts.t.iloc[0], rel=1e-6)
    assert P * D.quarter_period(0.9 * 0.01, 0.01, P) == pytest.approx(quarter_period_housner(0.9), rel=1e-4)


def _series(n, boundary="two-sided", seed=0, noise=2e-5, t_end=12.0, **kw):
    """Synthetic tests: exact simulator, a still segment before release, transducer noise."""
    rng = np.random.default_rng(seed)
    model = RockingModel(alpha=ALPHA, p=P, boundary=boundary, **kw)
    recs = []
    for i in range(n):
        sign = 1 if (i % 2 == 0 or boundary == "one-sided") else -1
        th0 = sign * rng.uniform(0.85, 0.95) * model.alpha_pos
        h = simulate_free(model, th0, 0.0, t_end=t_end, fs=400)
        theta = np.r_[np.full(120, th0), np.nan_to_num(h.theta)]
        t = np.arange(theta.size) / 400.0
        recs.append(dict(test_id=f"T{i}", t=t, theta=theta + rng.normal(0, noise, t.size), fs=400.0,
                         alpha=ALPHA, p=P, boundary=boundary, direction="push" if sign > 0 else "pull"))
    return recs


CASES = {
    "null-2s": ({}, "two-sided", 12.0),
    "scale": ({"impact": I.Scaled(I.HousnerTwoSided(), 0.9)}, "two-sided", 8.0),
    "alpha": ({"alpha_rock": 0.85 * ALPHA}, "two-sided", 12.0),
    "amp-1s": ({"impact": I.AmplitudeLaw(I.OneSided(), 1.2, 0.4)}, "one-sided", 3.0),
    "null-1s": ({}, "one-sided", 3.0),
    "gap-1s": ({"gap": 0.15 * ALPHA}, "one-sided", 3.0),
}


@pytest.fixture(scope="module")
def campaign():
    recs = {k: _series(6, b, seed=i, t_end=te, **kw) for i, (k, (kw, b, te)) in enumerate(CASES.items())}
    entries = D.diagnose_campaign(recs, n_boot=20, n_history=1)
    return {(e["scope"], e["key"]): e for e in entries}


def _finding(entry, effect):
    return next(f for f in entry["findings"] if f["effect"] == effect)


def test_null_series_is_none(campaign):
    for key in ("null-2s", "null-1s"):
        e = campaign["series", key]
        assert e["verdict"] == [] and not e["unexplained"]
        assert e["what_is_wrong"].startswith("the base model explains the data within the noise")


def test_restitution_scale_recovered(campaign):
    e = campaign["series", "scale"]
    assert e["verdict"] == ["restitution_scale"]
    f = _finding(e, "restitution_scale")
    assert f["params"]["c"] == pytest.approx(0.9, abs=0.01)
    lo, hi = f["ci95"]["c"]
    assert lo <= f["params"]["c"] <= hi < 1.0
    assert f["gain"]["free_run_log_peak_rms"] > 0
    # the base model keeps rocking longer than the wall
    assert e["base"]["errors"]["n_impacts"]["model"] < e["base"]["errors"]["n_impacts"]["measured"] or \
        e["base"]["errors"]["peak_decay_pct_per_impact"]["model"] < \
        e["base"]["errors"]["peak_decay_pct_per_impact"]["measured"]


def test_instability_angle_recovered(campaign):
    e = campaign["series", "alpha"]
    assert e["verdict"] == ["instability_angle"]
    f = _finding(e, "instability_angle")
    assert f["params"]["alpha_r_over_alpha"] == pytest.approx(0.85, abs=0.01)
    assert f["ci95"]["alpha_r_over_alpha"][1] < 1.0


def test_amplitude_law_recovered_one_sided(campaign):
    e = campaign["series", "amp-1s"]
    assert e["verdict"] == ["restitution_amplitude"]
    f = _finding(e, "restitution_amplitude")
    assert f["params"]["b"] == pytest.approx(0.4, abs=0.05)
    assert f["ci95"]["b"][0] > 0
    assert set(e["base"]["alternatives"]) == {"two-sided e (Hogan 1992)", "e = 0 (Liberatore & Spera 2003)"}


def test_contact_gap_recovered_with_its_signature(campaign):
    e = campaign["series", "gap-1s"]
    assert e["verdict"] == ["contact_gap"]
    f = _finding(e, "contact_gap")
    assert f["params"]["gap_over_alpha"] == pytest.approx(0.15, abs=0.02)
    assert "negative rotations" in f["evidence"]["signature"]
    # no negative rotations, no gap named
    assert "contact_gap" not in campaign["series", "null-1s"]["verdict"]


def test_write_diagnosis(campaign, tmp_path):
    entries = list(campaign.values())
    D.write_diagnosis(entries, tmp_path / "diagnosis.json", tmp_path / "diagnosis.md")
    assert len(json.loads((tmp_path / "diagnosis.json").read_text())) == len(entries)
    assert (tmp_path / "diagnosis.md").read_text().startswith("# Model diagnosis")


def test_boundary_entries_and_report(campaign):
    assert {k for k in campaign if k[0] == "boundary"} == {("boundary", "two-sided"), ("boundary", "one-sided")}
    entries = list(campaign.values())
    for e in entries:
        assert {"scope", "key", "n_tests", "base", "what_is_wrong", "verdict", "unexplained", "findings"} <= set(e)
    json.dumps(entries)
    md = D.diagnosis_markdown(entries)
    assert "## series scale" in md and "restitution_scale" in md
