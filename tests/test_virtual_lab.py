"""The virtual lab: simulated motions as records (rocklab.lab.virtual_record), written as a campaign in the
lab's format (rocklab.lab.virtual_lab)."""

import gzip
import importlib.util
import time

import numpy as np
import pandas as pd
import pytest

from rocklab.lab import kinematics
from rocklab.lab import virtual_lab as vl
from rocklab.lab import virtual_record as vr
from rocklab.physics import wall

HAVE_SIM = importlib.util.find_spec("rocklab.simulation.rocking_model") is not None
needs_sim = pytest.mark.skipif(not HAVE_SIM, reason="rocklab.simulation.rocking_model not available")

SPEC = vl.DEFAULT_SPECIMENS.set_index("specimen").loc["1a"]
LAYOUT = vr.usual_layout("S-1a-2s", SPEC.length_mm, SPEC.height_mm, SPEC.thickness_mm, False)
X, F = vr.transducer_geometry(LAYOUT)


def free_motion(fs=400.0, theta0=0.09, dur=6.0):
    """A decaying two-sided rocking history with impacts at theta = 0."""
    t = np.arange(0, dur, 1 / fs)
    period = 0.8
    env = theta0 * np.exp(-0.6 * t)
    theta = env * np.cos(np.pi * t / period)
    theta[t > 5.0] = 0.0
    imp_t = np.arange(period / 2, 5.0, period)
    impacts = pd.DataFrame({"t": imp_t, "thetadot_before": -np.exp(-0.6 * imp_t)})
    return t, theta, impacts


def read_raw(path):
    with gzip.open(path, "rt") as fh:
        lines = fh.read().splitlines()
    comments = [ln for ln in lines if ln.startswith("#")]
    return comments, lines[len(comments)], lines[len(comments) + 1 :]


def solve(E, weights=None):
    return kinematics.solve_wall_motion(E, X, F, SPEC.thickness_mm, weights=weights)


def test_usual_layout_matches_real_campaign_geometry():
    # Specimen 1a of the real campaign: heights 382, 926, 654 mm.
    assert LAYOUT.wall_z_mm.tolist() == [382, 926, 382, 926, 654]
    one = vr.usual_layout("S", 1420, 800, 113, True)
    assert one.channel.tolist() == [0, 1, 2, 3, 4, 5]
    assert one.iloc[5][["wall_y_mm", "frame_y_mm", "wall_z_mm"]].tolist() == [56.5, 216.5, 400]


def test_exact_round_trip_with_effects_off():
    t, theta, impacts = free_motion()
    tt, E, truth = vr.record_from_motion(
        t, theta, 400.0, LAYOUT, SPEC, impacts=impacts, effects=vr.Effects.off(), rng=1
    )
    sol = solve(E, [1, 1, 0, 1, 1])
    assert np.max(np.abs(sol["theta"] - truth["theta"])) < 1e-9
    i0 = int(round(truth["t_release"] * 400))
    assert np.allclose(truth["theta"][i0 : i0 + len(theta)][: len(theta)], theta[: len(truth["theta"]) - i0])
    assert np.all(truth["theta"][:i0] == theta[0])  # held still without creep
    assert truth["residual_top_mm"] < 1e-9


def test_hold_creep_release_and_rest_phases():
    t, theta, impacts = free_motion()
    eff = vr.Effects.off(creep_rad_s=3e-4, hold_s=(2.0, 2.0), rest_s=(3.0, 3.0))
    tt, E, truth = vr.record_from_motion(t, theta, 400.0, LAYOUT, SPEC, impacts=impacts, effects=eff, t_rest=5.0, rng=2)
    assert truth["t_release"] == pytest.approx(2.0)
    assert tt[-1] == pytest.approx(2.0 + 5.0 + 3.0, abs=0.01)
    hold = truth["theta"][:800]
    assert np.all(np.diff(hold) < 0) and hold[0] - theta[0] == pytest.approx(6e-4, rel=0.01)


def test_noise_and_hum_levels_like_the_real_campaign():
    t = np.arange(0, 4, 1 / 400)
    z = np.zeros_like(t)
    E = vr.instrument_readings(t, z + 0.05, z, z, z, LAYOUT, 113, 1090, vr.Effects(hum_mm=0.0), rng=3)
    E0 = vr.instrument_readings(t, z + 0.05, z, z, z, LAYOUT, 113, 1090, vr.Effects.off(), rng=3)
    noise = E - E0
    assert np.allclose(noise.std(axis=0), 0.002, rtol=0.1)
    E = vr.instrument_readings(t, z, z, z, z, LAYOUT, 113, 1090, vr.Effects(noise_mm=0.0, hum_mm=0.002), rng=3)
    spec = np.abs(np.fft.rfft(E, axis=0)) * 2 / len(t)
    f = np.fft.rfftfreq(len(t), 1 / 400)
    k50 = np.argmin(np.abs(f - 50))
    assert np.all(spec[k50] > 0.0009) and np.all(spec[k50] < 0.0031)
    assert np.all(np.delete(spec, k50, axis=0).max(axis=0) < 1e-4)


def test_ringing_follows_impacts_and_decays():
    t = np.arange(0, 2, 1 / 400)
    z = np.zeros_like(t)
    eff = vr.Effects.off(ringing_mm=0.08)
    E = vr.instrument_readings(t, z, z, z, z, LAYOUT, 113, 1090, eff, impacts=[(1.0, 1.0)], rng=4)
    assert np.all(E[t < 1.0] == 0)
    after = np.abs(E[(t > 1.0) & (t < 1.03), 1]).max()
    late = np.abs(E[t > 1.1, 1]).max()
    assert 0.02 < after < 0.15 and late < 0.01 * after
    # Higher transducers ring more (the wall's top moves most).
    assert np.abs(E[:, 1]).max() > np.abs(E[:, 0]).max() * 0.6


def test_faults_are_injected_as_specified():
    t, theta, impacts = free_motion()
    faults = [
        vr.Fault("dead", 0),
        vr.Fault("stuck", 1, start_s=4.0),
        vr.Fault("clipped", 3, level=0.5),
        vr.Fault("spikes", 4, count=5),
        vr.Fault("gaps", 2, count=3, max_len=4),
    ]
    tt, E, truth = vr.record_from_motion(t, theta, 400.0, LAYOUT, SPEC, impacts=impacts, faults=faults, rng=5)
    assert np.abs(E[:, 0]).max() < 0.02  # dead: ~0
    i4 = np.searchsorted(tt, 4.0)
    assert np.all(E[i4:, 1] == E[i4, 1]) and np.ptp(E[:i4, 1]) > 10  # stuck
    clean = kinematics.transducer_elongation(
        truth["theta"], truth["phi"], truth["v"], truth["w"], X, F, SPEC.thickness_mm
    )
    assert E[:, 3].max() == pytest.approx(0.5 * clean[:, 3].max(), abs=0.02)  # clipped
    assert np.sum(np.abs(E[:, 4] - clean[:, 4]) > 1.0) == 5  # spikes
    nan = np.isnan(E[:, 2])
    assert 3 <= nan.sum() <= 12 and not np.isnan(np.delete(E, 2, axis=1)).any()


def test_record_file_in_the_lab_format(tmp_path):
    t = np.arange(0, 1, 1 / 100)
    E = np.column_stack([np.linspace(-1, 1, 100), np.full(100, 12.34567)])
    E[10, 1] = np.nan
    vr.write_record(tmp_path / "T9.csv.gz", "T9", 100.0, t, E, [0, 4])
    comments, header, rows = read_raw(tmp_path / "T9.csv.gz")
    assert comments == ["# test_id: T9", "# sampling_rate_hz: 100", "# units: s, mm"]
    assert header == "time_s,ch0,ch4"
    assert rows[0] == "0.0000,-1.000,12.346" and rows[10].endswith(",") and len(rows) == 100
    vr.write_record(tmp_path / "T8.csv.gz", "T8", 400.0, t, E, [0, 4], unreadable=True)
    with pytest.raises((EOFError, OSError)):
        read_raw(tmp_path / "T8.csv.gz")


def test_expected_verdicts():
    v = vl.expected_verdict
    b = 113.0
    assert v([], LAYOUT, b, 0.0, 0.3)[0] == "valid"
    assert v([vr.Fault("dead", 1)], LAYOUT, b, 0.0, 0.3)[0] == "valid"  # backup
    assert v([vr.Fault("stuck", 4)], LAYOUT, b, 0.0, 0.3)[0] == "valid"  # v = 0
    assert v([vr.Fault("spikes", 0), vr.Fault("gaps", 1)], LAYOUT, b, 0, 0)[0] == "valid"
    assert v([vr.Fault("dead", 0), vr.Fault("clipped", 2)], LAYOUT, b, 0.0, 0.3)[0] == "instrument_malfunction"
    assert v([], LAYOUT, b, 0.2, 0.3)[0] == "disturbed_initial_conditions"
    assert v([], LAYOUT, b, 0.05, 2.0)[0] == "residual_out_of_plumb"
    assert v([vr.Fault("unreadable"), vr.Fault("dead", 0), vr.Fault("dead", 1)], LAYOUT, b, 0.5, 3)[0] == "unreadable"
    # Channel 5 sits on the face: losing it and one side channel is no malfunction.
    one = vr.usual_layout("S", 1420, 800, 113, True)
    assert v([vr.Fault("dead", 5), vr.Fault("dead", 0)], one, b, 0.0, 0.0)[0] == "valid"


@pytest.mark.parametrize("kind,top", [("rotation", 2.5), ("sliding", -3.0)])
def test_residual_out_of_plumb_is_seen_at_the_top(kind, top):
    t, theta, impacts = free_motion()
    tt, E, truth = vr.record_from_motion(
        t, theta, 400.0, LAYOUT, SPEC, impacts=impacts, residual_top_mm=top, residual_kind=kind, t_rest=5.0, rng=6
    )
    assert truth["residual_top_mm"] == pytest.approx(abs(top), abs=0.05)
    sol = solve(E[-400:], [1, 1, 0, 1, 1])
    seen = vr.top_offset_mm(
        sol["theta"], sol["phi"], sol["v"], sol["w"], SPEC.length_mm, SPEC.height_mm, SPEC.thickness_mm
    )
    assert np.median(seen) == pytest.approx(abs(top), abs=0.05)


def test_seed_reproducibility(tmp_path):
    t, theta, impacts = free_motion()
    runs = [vr.record_from_motion(t, theta, 400.0, LAYOUT, SPEC, impacts=impacts, rng=s)[1] for s in (7, 7, 8)]
    assert np.array_equal(runs[0], runs[1], equal_nan=True)
    assert not np.array_equal(runs[0], runs[2])


@needs_sim
def test_simulated_test_truth():
    test = vl.VirtualTest("V1", "1a", release_ratio=0.2)
    t, E, truth = vl.simulate_virtual_test(test, SPEC, LAYOUT, rng=9)
    alpha = wall.slenderness_angle(1.09, 0.113)
    assert truth["alpha_rock"] == pytest.approx(0.91 * alpha)
    assert truth["theta0"] == pytest.approx(0.995 * 0.91 * alpha)
    p = wall.frequency_parameter(wall.half_diagonal(1.09, 0.113))
    assert abs(truth["thetadot0"]) == pytest.approx(0.2 * wall.overturning_velocity(alpha, p))
    assert truth["expected_reason"] == "disturbed_initial_conditions"
    # The release velocity is in the readings: right after the release.
    sol = solve(E, [1, 1, 0, 1, 1])
    i = int(round(truth["t_release"] * 400))
    rate = np.polyfit(t[i : i + 8] - t[i], sol["theta"][i : i + 8], 2)[1]
    assert rate == pytest.approx(truth["thetadot0"], rel=0.1)


@needs_sim
def test_virtual_campaign_default_plan(tmp_path):
    t0 = time.perf_counter()
    truth = vl.write_campaign(tmp_path / "camp", vl.default_plan(12, seed=3), seed=3)
    elapsed = time.perf_counter() - t0
    assert elapsed < 20.0
    camp = tmp_path / "camp"
    for name, cols in [
        ("specimens.csv", ["specimen", "wall", "unit", "length_mm", "height_mm", "thickness_mm", "unit_weight_kN_m3"]),
        (
            "setups.csv",
            ["setup", "channel", "wall_x_mm", "wall_y_mm", "wall_z_mm", "frame_x_mm", "frame_y_mm", "frame_z_mm"],
        ),
        ("tests.csv", ["test_id", "specimen", "boundary", "contact_depth_mm", "direction", "setup", "file", "note"]),
    ]:
        assert pd.read_csv(camp / name).columns.tolist() == cols
    tests = pd.read_csv(camp / "tests.csv", dtype=str, keep_default_na=False)
    assert set(tests.boundary) == {"two-sided", "one-sided"}
    assert set(truth.expected_reason) == {
        "valid",
        "instrument_malfunction",
        "disturbed_initial_conditions",
        "residual_out_of_plumb",
        "unreadable",
    }
    assert (truth.fs == 100).any()
    assert not truth.overturned.any()
    two = truth[truth.boundary == "two-sided"]
    assert np.allclose(two.e_true / two.e_analytic, 0.95, atol=0.01)
    assert (truth[truth.boundary == "one-sided"].e_true < 0).all()
    # Every readable file parses as the spec says, and starts held near theta0.
    setups = pd.read_csv(camp / "setups.csv")
    for row in tests.itertuples():
        tr = truth.set_index("test_id").loc[row.test_id]
        if tr.expected_reason == "unreadable":
            continue
        comments, header, rows = read_raw(camp / row.file)
        assert comments[1] == f"# sampling_rate_hz: {tr.fs:g}"
        rec = pd.read_csv(camp / row.file, comment="#")
        assert np.allclose(np.diff(rec.time_s), 1 / tr.fs, atol=1e-4)
        g = setups[setups.setup == row.setup]
        z1 = float(g[g.channel == 1].wall_z_mm.iloc[0])
        if "ch1 dead" not in str(tr.faults):
            assert rec.ch1.iloc[0] / z1 == pytest.approx(tr.theta0, rel=0.1)


def test_a_virtual_test_of_an_unknown_specimen_is_refused_by_name(tmp_path):
    with pytest.raises(ValueError, match=r"specimens '2z' not in the specimens table \(known: 1a"):
        vl.write_campaign(tmp_path / "c", [vl.VirtualTest("V1", "2z")])
    assert not list((tmp_path / "c" / "tests").iterdir())


def test_a_release_the_dry_friction_holds_is_refused():
    """A wall its friction holds at the release never rocks: the virtual lab says so instead of
    writing a test whose truth (valid, rocking) the record contradicts."""
    specimen = {"height_mm": 1500.0, "thickness_mm": 150.0}
    mu = 0.03 * wall.slenderness_angle(1.5, 0.15)
    test = vl.VirtualTest("H001", theta0_ratio=0.99, model={"mu": mu})
    with pytest.raises(ValueError, match="H001.*held there by the dry friction"):
        vl.simulate_virtual_test(test, specimen, None, rng=0, t_end=5.0)
