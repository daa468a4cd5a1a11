"""Rotation and inertial records (rocklab.lab.records, .rotation, .inertial, .instrument): read at the same
door as the transducers', reduced to the same motion, judged by the same rules, against the virtual lab's
truth (rocklab.lab.virtual_instruments, rocklab.lab.accuracy)."""

import gzip
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from rocklab.lab import inertial, instrument, rotation
from rocklab.lab import virtual_lab as vl
from rocklab.lab.accuracy import impact_errors, instrument_accuracy
from rocklab.lab.campaign import open_campaign
from rocklab.lab.motion import extract_motion, motion_from_dataset, noise_level, stored_motion
from rocklab.lab.records import InertialRecord, RotationRecord, read_any_record
from rocklab.lab.reduction import qc_table, reduce_test, reduce_tests
from rocklab.lab.validity import Verdict
from rocklab.lab.virtual_instruments import InertialEffects, RotationEffects

SPEC = vl.DEFAULT_SPECIMENS.set_index("specimen").loc["1a"]


@pytest.fixture(scope="module")
def mixed(tmp_path_factory):
    """The same walls recorded by each instrument, at the labs' rates, with faulty records among them."""
    out = tmp_path_factory.mktemp("mixed")
    plan = [
        vl.VirtualTest("X1", specimen="1a", fs=400.0),
        vl.VirtualTest("X2", specimen="5c", fs=100.0, boundary="one-sided", contact_depth_mm=120.0),
        *(vl.VirtualTest(f"R{fs}", specimen="1a", fs=float(fs), instrument="rotation") for fs in (100, 240, 500)),
        vl.VirtualTest(
            "R1s", specimen="5c", fs=240.0, instrument="rotation", boundary="one-sided", contact_depth_mm=120
        ),
        vl.VirtualTest("Rxy", specimen="2a", fs=240.0, instrument="rotation", rotation=RotationEffects(sliding=True)),
        *(vl.VirtualTest(f"I{fs}", specimen="1a", fs=float(fs), instrument="inertial") for fs in (200, 1000, 2000)),
        vl.VirtualTest(
            "I1s", specimen="5c", fs=1000.0, instrument="inertial", boundary="one-sided", contact_depth_mm=120
        ),
        vl.VirtualTest("Rdead", fs=240.0, instrument="rotation", faults=[vl.Fault("dead")]),
        vl.VirtualTest("Iclip", fs=1000.0, instrument="inertial", faults=[vl.Fault("clipped", level=0.4)]),
        vl.VirtualTest("Ikick", fs=1000.0, instrument="inertial", release_ratio=0.2),
        vl.VirtualTest("Rtilt", fs=240.0, instrument="rotation", residual_top_mm=3.0),
        vl.VirtualTest("Itilt", fs=1000.0, instrument="inertial", residual_top_mm=3.0),
    ]
    truth = vl.write_campaign(out, plan, seed=3)
    return out, truth.set_index("test_id"), dict(reduce_tests(open_campaign(out), [t.test_id for t in plan]))


def test_every_kind_is_read_and_judged_as_the_truth_says(mixed):
    out, truth, reduced = mixed
    for test_id, ds in reduced.items():
        assert ds.attrs["instrument"] == ("transducers" if test_id[0] == "X" else truth.instrument[test_id])
        assert ds.attrs["reject_reason"] == truth.expected_reason[test_id].replace("valid", ""), (test_id, ds.attrs)
    qc = qc_table(reduced.values(), open_campaign(out)).set_index("test_id")
    assert qc.loc["Rdead", "channels_dead"] == "theta_rad"
    assert qc.loc["Iclip", "channels_clipped"] == "gyro_x_rad_s"
    assert (qc.loc[["R100", "R240", "R500"], "samples_bridged"] > 0).all()
    assert qc.loc["Rxy", "in_plane_lost"] == 0 and qc.loc["R240", "in_plane_lost"] == 1
    assert qc.loc[["I200", "I1000", "I2000"], "theta_error_bound_rad"].notna().all()


@pytest.mark.parametrize("test_id", ["R100", "R240", "R500", "R1s", "Rxy", "I200", "I1000", "I2000", "I1s"])
def test_each_instrument_gives_the_motion_and_restitution_of_the_wall(mixed, test_id):
    _, truth, reduced = mixed
    m = motion_from_dataset(stored_motion(reduced[test_id]))
    assert m.theta0 == pytest.approx(truth.theta0[test_id], abs=5e-4)
    if truth.boundary[test_id] == "one-sided":
        # a one-sided wall of the virtual lab rebounds a few times, ever smaller: the first is the one to check
        assert m.impacts.e_velocity[0] == pytest.approx(truth.e_first[test_id], abs=0.01)
        return
    assert len(m.impacts) >= 10
    # the median e over the impacts, as the dissipation takes it; a gyroscope at 200 Hz smooths the impacts
    tol = 0.015 if test_id == "I200" else 0.01
    assert np.nanmedian(m.impacts.e_velocity) == pytest.approx(truth.e_true[test_id], abs=tol)


def test_per_impact_restitution_within_0005_of_the_truth_at_240_and_1000_hz():
    rotation_240 = instrument_accuracy("rotation", 240.0, n_tests=2, seed=5)
    inertial_1000 = instrument_accuracy("inertial", 1000.0, n_tests=2, seed=5)
    for acc in (rotation_240, inertial_1000):
        assert acc["n_impacts"] >= 40
        assert abs(acc["e_error_median"]) <= 0.005
    # from the rate's steps (0.0025 here); the flight fits of the integrated rate gave 0.016
    assert inertial_1000["e_abs_error_median"] <= 0.005
    # fitted up to the impact over the whole flight (0.0017 here); the transducers' fits gave 0.0036
    assert rotation_240["e_abs_error_median"] <= 0.0025
    assert inertial_1000["bound_held"] == 2


def test_only_a_rotation_record_takes_the_rotation_fits(mixed):
    """A transducer or inertial record keeps the transducers' fits (0.06 s of ringing left out, 0.6/p);
    a rotation record's take-off is fitted from 2.5 samples after the impact (rocklab.lab.rotation.flight_fits)."""
    _, _, reduced = mixed

    def plain(ds):
        a = ds.attrs
        return extract_motion(ds.time.values, ds.theta.values, a["sampling_rate_hz"], a["boundary"], a["p"])

    for test_id in ("X1", "I1000"):
        assert (
            motion_from_dataset(stored_motion(reduced[test_id])).peaks.tolist()
            == plain(reduced[test_id]).peaks.tolist()
        )
    ds = reduced["R240"]
    fitted = motion_from_dataset(stored_motion(ds)).impacts
    assert fitted.thetadot_after.tolist() != plain(ds).impacts.thetadot_after.tolist()
    assert rotation.flight_fits(240.0)["ring_guard_s"] == pytest.approx(2.5 / 240.0)


def test_impact_errors_match_impacts_by_time():
    truth = pd.DataFrame({"t": [1.0, 2.0, 3.0], "e": [0.9, 0.8, 0.7]})
    found = pd.DataFrame({"t_s": [1.001, 2.5, 2.999], "e_velocity": [0.91, 0.5, np.nan]})
    assert impact_errors(found, truth) == pytest.approx([0.01])


# rotation records


def test_a_bridge_in_flight_is_close_and_a_lost_impact_is_not_measured():
    fs = 240.0
    t = np.arange(0, 3, 1 / fs)
    theta = 0.05 * np.abs(np.cos(2.0 * t)) * np.sign(np.cos(2.0 * t))
    lost = np.zeros(t.size, bool)
    apex = np.argmin(np.abs(t - np.pi / 2.0))  # cos(2t) = -1: mid-flight
    lost[apex - 10 : apex + 10] = True
    crossing = np.argmin(np.abs(t - np.pi / 4.0))  # cos(2t) = 0: the vertical
    lost[crossing - 3 : crossing + 3] = True
    bridged = rotation.bridge(t, np.where(lost, np.nan, theta), lost)
    assert np.abs(bridged - theta)[apex - 10 : apex + 10].max() < 1e-4
    assert rotation.at_vertical(bridged, lost, 1e-5) == [(crossing - 3, crossing + 3)]
    seen = rotation.unseen_impacts([t[crossing], t[apex]], [t[crossing], t[apex] + 0.5], t, lost)
    assert seen.tolist() == [True, True]
    assert not rotation.unseen_impacts([0.2], [0.2], t, lost).any()


def test_an_occlusion_over_an_impact_is_flagged_not_invented(tmp_path):
    test = vl.VirtualTest("R", fs=240.0, instrument="rotation", rotation=RotationEffects(occlusions=0))
    truth = vl.write_campaign(tmp_path, [test], seed=1)
    ds = reduce_test(open_campaign(tmp_path), "R")
    m = motion_from_dataset(stored_motion(ds))
    k = 2
    t0, t1 = m.impacts.t_s[k], m.impacts.t_after_s[k]
    ds["theta_lost"][:] = 0
    ds["theta_lost"][(ds.time.values > t0 - 0.02) & (ds.time.values < t1 + 0.02)] = 1
    lost = stored_motion(ds)
    assert np.isnan(lost.e_velocity.values[k]) and np.isfinite(np.delete(lost.e_velocity.values, k)).sum() > 10
    assert truth.expected_valid.all()


def test_the_noise_of_a_rotation_record_is_estimated_from_it(tmp_path):
    test = vl.VirtualTest("R", fs=500.0, instrument="rotation", rotation=RotationEffects(noise_rad=5e-5))
    vl.write_campaign(tmp_path, [test], seed=2)
    ds = reduce_test(open_campaign(tmp_path), "R")
    assert ds.attrs["theta_noise_rad"] == pytest.approx(5e-5, rel=0.25)


def test_a_lost_stretch_too_long_to_bridge_loses_the_instrument(tmp_path):
    rec = RotationRecord(np.arange(0, 10, 0.01), {"theta": np.cos(np.arange(0, 10, 0.01)) * 0.1}, 100.0, {}, "", "x")
    rec.dof["theta"][300:340] = np.nan
    m = rotation.rotation_motion(rec, 0.08, noise_level)
    assert "lost for 0.40 s from 3.00 s" in m.malfunction
    rec.dof["theta"][300:320] = 0.0
    assert rotation.rotation_motion(rec, 0.08, noise_level).malfunction is None


# inertial records


def test_static_tilt_is_the_closed_form_of_a_wall_at_rest():
    theta = np.linspace(-0.2, 0.2, 9)
    assert inertial.static_tilt(-9.81 * np.sin(theta), 9.81 * np.cos(theta)) == pytest.approx(theta, abs=1e-15)


def test_a_constant_bias_is_removed_exactly_by_the_closure_between_the_rests():
    fs = 1000.0
    t = np.arange(0, 8, 1 / fs)
    theta = 0.08 * np.exp(-((t - 4.0) ** 2)) * np.sin(6 * t) + 0.07 * (t < 1) * (1 - t)  # held, rocks, rests
    rate = np.gradient(theta, t) + 3e-4
    got, bias, _ = inertial.integrated_rotation(t, rate, theta + 2e-3, fs)
    assert bias == pytest.approx(3e-4, rel=1e-3)
    assert np.abs(got - (theta + 2e-3)).max() < 2e-5  # the tilt's offset stays: the vertical_offset's to remove


def test_force_spikes_fix_the_vertical():
    fs = 1000.0
    t = np.arange(0, 4, 1 / fs)
    spikes = np.array([1.0, 1.8, 2.5, 3.1])
    theta = 4e-4 + 0.01 * np.sin(np.pi * (t - 1.0) / 0.8)
    offset, sigma = inertial.vertical_offset(t, theta, spikes[:1], fs)
    assert np.isnan(offset) and np.isnan(sigma)
    offset, _ = inertial.vertical_offset(t, theta, spikes + 0.5 / fs, fs)
    assert offset == pytest.approx(4e-4, abs=2e-4)


def test_the_stated_bound_holds_on_the_virtual_lab(mixed):
    _, truth, reduced = mixed
    for test_id in ("I200", "I1000", "I2000", "I1s"):
        a = reduced[test_id].attrs
        # the closure's noise: the rate's random walk and the tilts' noise over the ~15 s between the rests
        assert a["gyro_bias_rad_s"] == pytest.approx(truth.gyro_bias_rad_s[test_id], abs=1e-4)
        assert 0 < a["theta_error_bound_rad"] < 2e-3
        assert a["force_spikes"] >= (3 if truth.boundary[test_id] == "one-sided" else 10)


def test_signal_status():
    fs = 1000.0
    x = np.sin(np.arange(0, 5, 1 / fs) * 5) + np.random.default_rng(0).normal(0, 1e-3, 5000)
    assert instrument.signal_status(x, fs, 1.0) == "ok"
    assert instrument.signal_status(0.05 * x, fs, 1.0) == "dead"
    assert instrument.signal_status(np.clip(x, -0.5, 0.5), fs, 1.0) == "clipped"
    assert instrument.signal_status(np.full(5, np.nan), fs, 1.0) == "dead"


# bad records


def _rewrite(path, edit):
    text = gzip.decompress(path.read_bytes()).decode()
    path.write_bytes(gzip.compress(edit(text).encode(), mtime=0))


BAD = {
    "rotation without test_id": ("R", lambda s: s.replace("# test_id: R\n", ""), ":1: missing '# test_id:'"),
    "rotation in degrees": ("R", lambda s: s.replace("units: s, rad", "units: s, deg"), "units 's, deg'"),
    "rotation row of another kind": ("R", lambda s: s.replace("theta_rad", "theta"), "header row must be time_s,theta"),
    "inertial without sensor": ("I", lambda s: s.replace("# sensor_mm", "# sensor"), "missing '# sensor_mm:'"),
    "inertial in g": ("I", lambda s: s.replace("m/s2", "g"), "units 's, rad/s, g'"),
    "inertial rate all empty": (
        "I",
        lambda s: (
            "\n".join(
                ",".join([f[0], "", *f[2:]]) if f[0][:1].isdigit() else ln
                for ln, f in ((ln, ln.split(",")) for ln in s.splitlines())
            )
            + "\n"
        ),
        ":6: column gyro_x_rad_s: every sample is empty",
    ),
    "inertial sensor off the wall": (
        "I",
        lambda s: s.replace("# sensor_mm: 710, 0, 872", "# sensor_mm: 710, 300, 872"),
        ":1: sensor_mm 710, 300, 872 is outside the wall",
    ),
    "unknown kind": ("R", lambda s: s.replace("record: rotation", "record: laser"), "record 'laser' is not one of"),
}


@pytest.mark.parametrize("case", BAD)
def test_a_bad_record_is_refused_with_its_file_line_and_problem_and_the_rest_goes_on(tmp_path, case):
    which, edit, message = BAD[case]
    plan = [vl.VirtualTest("R", fs=100.0, instrument="rotation"), vl.VirtualTest("I", fs=200.0, instrument="inertial")]
    vl.write_campaign(tmp_path, plan, seed=0)
    _rewrite(tmp_path / "tests" / f"{which}.csv.gz", edit)
    reduced = dict(reduce_tests(open_campaign(tmp_path), ["R", "I"]))
    bad, good = reduced[which].attrs, reduced["I" if which == "R" else "R"].attrs
    assert bad["reject_reason"] == Verdict.UNREADABLE
    assert f"tests/{which}.csv.gz" in bad["reject_detail"] and message in bad["reject_detail"]
    assert good["valid"] == 1


def test_a_transducer_record_needs_a_setup_and_no_setup_needs_setups_csv(tmp_path):
    plan = [vl.VirtualTest("R", fs=100.0, instrument="rotation"), vl.VirtualTest("X", fs=100.0)]
    vl.write_campaign(tmp_path, plan, seed=0)
    log = pd.read_csv(tmp_path / "tests.csv", dtype=str, keep_default_na=False)
    log.assign(setup="").to_csv(tmp_path / "tests.csv", index=False)
    (tmp_path / "setups.csv").unlink()
    reduced = dict(reduce_tests(open_campaign(tmp_path), ["R", "X"]))
    assert reduced["R"].attrs["valid"] == 1
    assert "a transducer record, but tests.csv gives the test no setup" in reduced["X"].attrs["reject_detail"]


def test_the_readers_give_each_kind(mixed):
    out, _, _ = mixed
    assert isinstance(read_any_record(out / "tests" / "R240.csv.gz", "R240"), RotationRecord)
    rec = read_any_record(out / "tests" / "I1000.csv.gz", "I1000")
    assert isinstance(rec, InertialRecord) and rec.fs == 1000.0
    assert rec.sensor_mm.tolist() == pytest.approx([SPEC.length_mm / 2, 0.0, 0.8 * SPEC.height_mm], abs=0.5)
    assert replace(InertialEffects(), sensor=(0, 1, 0.5)).sensor == (0, 1, 0.5)


def test_fig6_draws_the_rotation_of_a_test_no_transducer_recorded(mixed):
    from rocklab.plots.kinematics import sample_record

    fig = sample_record(mixed[2]["I1000"])
    assert fig.axes[0].get_ylabel() == "θ [rad]" and "inertial" in fig.axes[0].lines[0].get_label()
    assert sample_record(mixed[2]["X1"]).axes[0].get_ylabel() == "Δl [mm]"
