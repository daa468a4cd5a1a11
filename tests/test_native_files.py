"""The native files of the instruments (issue 43): TDMS, C3D and video read as the lab's instruments write them.

Each reader is tested on a small file written by the real library (npTDMS,
c3d, OpenCV) from a known motion (:mod:`rocklab.lab.virtual_native`), and
on the bad files of ``docs/raw-format.md``: each refused naming the file
and the problem, while the rest of a campaign is reduced.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rocklab.lab.campaign import open_campaign
from rocklab.lab.native_files import (
    c3d_record,
    check_setup_channels,
    native_reader,
    read_test_file,
    tdms_record,
    video_record,
)
from rocklab.lab.raw_format import RawFormatError
from rocklab.lab.records import Record, RotationRecord
from rocklab.lab.reduction import qc_row, reduce_test
from rocklab.lab.video_tracking import find_markers, theta_from_markers, track_video
from rocklab.lab.virtual_lab import VirtualTest, write_campaign
from rocklab.lab.virtual_native import (
    MarkerEffects,
    VideoEffects,
    image_points,
    write_c3d,
    write_tdms,
    write_video,
)

SPEC = {"length_mm": 1420.0, "height_mm": 1090.0, "thickness_mm": 113.0}
#: A small film: a test's video in a few kilobytes.
TINY = VideoEffects(height_px=120, width_px=90, marker_px=7.0, occlusions=0)


def motion(n, fs, amp=0.06):
    """A rocking-like theta [rad] on n samples at fs: crosses zero, changes sign."""
    t = np.arange(n) / fs
    return t, amp * np.cos(2 * np.pi * 0.8 * t) * np.exp(-t / 3)


# --- TDMS -----------------------------------------------------------------


def test_a_tdms_file_reads_as_the_transducer_record_it_holds(tmp_path):
    t = 0.5 + np.arange(800) / 400.0
    readings = np.random.default_rng(0).normal(0, 1, (800, 5))
    readings[100:104, 2] = np.nan
    path = tmp_path / "T.tdms"
    write_tdms(path, t, readings, [0, 1, 2, 3, 4])
    rec = read_test_file(path, "T")
    assert isinstance(rec, Record)
    assert rec.channels == [0, 1, 2, 3, 4] and rec.fs == pytest.approx(400.0)
    np.testing.assert_allclose(rec.time, t, atol=1e-9)
    np.testing.assert_array_equal(np.isnan(rec.readings), np.isnan(readings))
    np.testing.assert_allclose(rec.readings[~np.isnan(readings)], readings[~np.isnan(readings)])
    assert rec.header["test_id"] == "T" and len(rec.sha256) == 64


def test_bad_tdms_files_are_refused_naming_the_file_and_what_is_missing(tmp_path):
    from nptdms import ChannelObject, TdmsWriter

    t = np.arange(100) / 100.0
    data = np.zeros((100, 2))
    cases = {}
    text = tmp_path / "text.tdms"
    text.write_text("time_s,ch0\n0,1\n")
    cases[text] = "not a TDMS file"
    cut = tmp_path / "cut.tdms"
    write_tdms(cut, t, data, [0, 1], unreadable=True)
    cases[cut] = "truncated"
    for name, group, props, why in [
        ("group", "other", {"wf_increment": 0.01}, "no group 'displacements'"),
        ("incr", "displacements", {"unit_string": "mm"}, "has no wf_increment"),
        ("unit", "displacements", {"wf_increment": 0.01, "unit_string": "in"}, "read in mm"),
    ]:
        path = tmp_path / f"{name}.tdms"
        with TdmsWriter(str(path)) as w:
            w.write_segment([ChannelObject(group, "ch0", np.zeros(10), properties=props)])
        cases[path] = why
    for path, why in cases.items():
        with pytest.raises(RawFormatError, match=why) as err:
            tdms_record(path)
        assert err.value.path == str(path)


def test_a_tdms_file_without_a_channel_of_its_setup_is_refused(tmp_path):
    t = np.arange(50) / 100.0
    path = tmp_path / "T.tdms"
    write_tdms(path, t, np.zeros((50, 4)), [0, 1, 3, 4])
    rec = tdms_record(path)
    with pytest.raises(RawFormatError, match="no channel ch2 of the setup"):
        check_setup_channels(rec, [0, 1, 2, 3, 4])
    check_setup_channels(rec, [0, 1, 3, 4])


# --- C3D ------------------------------------------------------------------


def test_theta_from_a_c3d_file_is_the_wall_markers_angle_with_lost_frames_empty(tmp_path):
    fs = 200.0
    _, theta = motion(600, fs)
    w = np.linspace(0, 2.0, 600)  # sliding moves both markers: not theta
    path = tmp_path / "C.c3d"
    write_c3d(path, fs, theta, 0 * theta, 0 * theta, w, SPEC, MarkerEffects(noise_mm=0.0, occlusions=3), rng=1)
    rec = read_test_file(path, "C")
    assert isinstance(rec, RotationRecord) and rec.fs == pytest.approx(fs)
    lost = np.isnan(rec.dof["theta"])
    assert 3 <= lost.sum() < 60
    # float32 coordinates of points a metre apart: 1e-7 rad
    np.testing.assert_allclose(rec.dof["theta"][~lost], theta[~lost], atol=2e-6)


def test_c3d_files_without_the_wall_markers_or_cut_are_refused(tmp_path):
    import c3d

    writer = c3d.Writer(point_rate=100.0, analog_rate=100.0)
    points = np.zeros((2, 5), np.float32)
    writer.add_frames([(points, np.zeros((0, 0), np.float32))] * 5)
    writer.set_point_labels(["WALL_LO", "KNEE"])
    path = tmp_path / "labels.c3d"
    with path.open("wb") as fh, pytest.warns(UserWarning):
        writer.write(fh)
    with pytest.raises(RawFormatError, match="no marker WALL_HI"):
        c3d_record(path)
    cut = tmp_path / "cut.c3d"
    _, theta = motion(400, 100.0)
    write_c3d(cut, 100.0, theta, 0 * theta, 0 * theta, 0 * theta, SPEC, rng=0, unreadable=True)
    with pytest.raises(RawFormatError, match="cut.c3d"):
        c3d_record(cut)
    junk = tmp_path / "junk.c3d"
    junk.write_bytes(b"\x00" * 100)
    with pytest.raises(RawFormatError, match="not a C3D file"):
        c3d_record(junk)
    garbled = tmp_path / "garbled.c3d"
    garbled.write_bytes(b"\x02\x50" + b"\xff" * 600)
    with pytest.raises(RawFormatError, match="garbled.c3d"):
        c3d_record(garbled)


# --- video ----------------------------------------------------------------


def test_markers_are_found_to_a_tenth_of_a_pixel():
    from rocklab.lab.virtual_native import _disc

    frame = np.full((60, 60), 20.0, np.float32)
    truth = np.array([[15.3, 12.7], [40.55, 20.2], [22.1, 48.9], [47.8, 45.35]])
    for c in truth:
        _disc(frame, c, 3.5, 200.0)
    found, areas = find_markers(np.round(frame).astype(np.uint8))
    order = np.argsort(found[:, 1] * 100 + found[:, 0])
    assert len(found) == 4 and (areas > 20).all()
    np.testing.assert_allclose(found[order], truth[np.argsort(truth[:, 1] * 100 + truth[:, 0])], atol=0.1)


def test_theta_between_the_lines_needs_no_level_camera():
    post = np.array([[0.0, 100.0], [0.0, 0.0]])
    for roll in (0.0, 0.1, -0.3):
        for theta in (-0.1, 0.0, 0.05):
            wall = np.array([[50.0, 100.0], [50.0 + 100 * np.sin(theta), 100.0 - 100 * np.cos(theta)]])
            pts = np.concatenate([wall, post])
            c, s = np.cos(roll), np.sin(roll)
            rolled = pts @ np.array([[c, s], [-s, c]])
            assert theta_from_markers(rolled[None])[0] == pytest.approx(theta, abs=1e-12)


@pytest.mark.parametrize("ext", [".mp4", ".avi", ".mov"])
def test_a_filmed_test_gives_theta_at_its_frame_rate(tmp_path, ext):
    fs = 60.0
    _, theta = motion(90, fs)
    path = tmp_path / f"M{ext}"
    effects = VideoEffects(height_px=120, width_px=90, marker_px=7.0, tilt_deg=4.0, occlusions=1, extension=ext)
    hidden = write_video(path, fs, theta, 0 * theta, SPEC, effects, rng=2)
    rec = video_record(path, "M")
    assert rec.fs == pytest.approx(fs) and rec.time.size == theta.size
    lost = np.isnan(rec.dof["theta"])
    np.testing.assert_array_equal(lost, hidden.any(axis=1))
    assert rec.attrs["frames_tracked"] == int((~lost).sum())
    # a 7-pixel marker, 70 pixels apart: a few milliradians at this size and blur
    err = rec.dof["theta"][~lost] - theta[~lost]
    assert np.median(np.abs(err)) < 3e-3 and np.abs(err).max() < 1e-2


def test_the_tracking_noise_is_theta_scatter_at_rest(tmp_path):
    fs = 30.0
    theta = np.r_[np.linspace(0.05, 0.0, 20), np.zeros(40)]
    path = tmp_path / "rest.mp4"
    write_video(path, fs, theta, 0 * theta, SPEC, VideoEffects(occlusions=0, noise=3.0), rng=3)
    tr = track_video(path)
    rest = tr.theta[-30:]
    assert 0 < tr.noise_rad < 2e-3
    assert tr.noise_rad == pytest.approx(1.4826 * np.median(np.abs(rest - np.median(rest))))


def _film(path, fs, centres, size=(80, 80)):
    """A film of discs at given positions per frame (frames, k, 2) [pixels]."""
    import cv2

    from rocklab.lab.virtual_native import _disc

    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), fs, size[::-1], False)
    for frame_centres in centres:
        frame = np.full(size, 20.0, np.float32)
        for c in frame_centres:
            _disc(frame, c, 3.5, 200.0)
        writer.write(np.round(frame).astype(np.uint8))
    writer.release()


def test_bad_films_are_refused_naming_the_file_and_the_problem(tmp_path, monkeypatch):
    import cv2

    n = 20
    still = np.array([[10.0, 20.0], [10.0, 60.0]])
    moving = np.stack([np.array([[40.0 + k, 20.0], [40.0 + k, 60.0]]) for k in range(n)])
    three = tmp_path / "three.avi"
    _film(three, 30.0, [np.r_[still, m[:1]] for m in moving])
    crossing = tmp_path / "cross.avi"
    # the wall's upper marker runs into the post's
    _film(crossing, 30.0, [np.r_[still, [[40.0, 60.0], [40.0 - 1.6 * k, 20.0]]] for k in range(n)])
    five = tmp_path / "five.avi"
    _film(five, 30.0, [np.r_[still, m, [[70.0, 40.0]]] for m in moving])
    junk = tmp_path / "junk.mp4"
    junk.write_bytes(b"not a film" * 50)
    for path, why in [
        (three, "fewer than four markers found"),
        (crossing, "two markers meet"),
        (five, "no frame shows exactly four markers"),
        (junk, "not a video that can be decoded"),
    ]:
        with pytest.raises(RawFormatError, match=why) as err:
            video_record(path)
        assert err.value.path == str(path)
    good = tmp_path / "good.avi"
    _film(good, 30.0, [np.r_[still, m] for m in moving])
    assert video_record(good).attrs["frames_tracked"] == n

    opened = cv2.VideoCapture

    class NoRate:
        """A container that gives no frame rate (FFmpeg reads 0), the rest as OpenCV reads it."""

        def __init__(self, name):
            self.cap = opened(name)

        def get(self, prop):
            return 0.0 if prop == cv2.CAP_PROP_FPS else self.cap.get(prop)

        def __getattr__(self, name):
            return getattr(self.cap, name)

    monkeypatch.setattr(cv2, "VideoCapture", NoRate)
    with pytest.raises(RawFormatError, match="no frame rate"):
        video_record(good)


def test_the_camera_sees_the_wall_top_move_right_as_theta_grows():
    wall = np.array([[0.0, 0.9 * SPEC["height_mm"]], [100.0, 0.9 * SPEC["height_mm"]]])
    px = image_points(wall, SPEC, VideoEffects(tilt_deg=0.0))
    assert px[1, 0] > px[0, 0] and px[1, 1] == pytest.approx(px[0, 1])


def test_native_readers_are_chosen_by_extension_in_any_case():
    assert native_reader("tests/a.TDMS") is tdms_record
    assert native_reader("a.C3d") is c3d_record
    assert all(native_reader(f"a{e}") is video_record for e in (".mp4", ".AVI", ".mov"))
    assert native_reader("tests/a.csv.gz") is None and native_reader("a.csv") is None


# --- campaigns ------------------------------------------------------------


@pytest.fixture(scope="module")
def mixed(tmp_path_factory):
    """A tiny campaign of every kind of file, text and native, reduced."""
    out = tmp_path_factory.mktemp("mixed")
    plan = [
        VirtualTest("TXT", specimen="1a"),
        VirtualTest("TDM", specimen="2a", instrument="tdms"),
        VirtualTest("C3D", specimen="3b", fs=200.0, instrument="c3d"),
        VirtualTest("VID", specimen="1a", fs=60.0, instrument="video", video=TINY),
        VirtualTest("BAD", specimen="1a", instrument="c3d", faults=[]),
        VirtualTest("CUT", specimen="5c", instrument="tdms"),
    ]
    truth = write_campaign(out, plan, seed=4)
    tests = pd.read_csv(out / "tests.csv", keep_default_na=False)
    # a name that leaves the campaign folder, and a truncated file: refused, the rest reduced
    tests.loc[tests.test_id == "BAD", "file"] = "../outside.c3d"
    (out / "tests" / "CUT.tdms").write_bytes((out / "tests" / "CUT.tdms").read_bytes()[:500])
    tests.to_csv(out / "tests.csv", index=False)
    campaign = open_campaign(out)
    rows = {tid: qc_row(reduce_test(campaign, tid)) for tid in ["TXT", "TDM", "C3D", "VID", "BAD", "CUT"]}
    return truth, rows


def test_a_mixed_campaign_of_text_and_native_files_reduces_with_every_test_valid(mixed):
    truth, rows = mixed
    for tid in ("TXT", "TDM", "C3D", "VID"):
        assert rows[tid]["valid"], (tid, rows[tid]["reject_detail"])
    assert rows["TDM"]["instrument"] == "transducers" and rows["C3D"]["instrument"] == "rotation"
    assert rows["VID"]["frames_tracked"] > 0.95 * truth.set_index("test_id").t_rest["VID"] * 60
    assert 0 < rows["VID"]["tracking_noise_rad"] < 1e-3
    assert rows["C3D"]["samples_bridged"] > 0


def test_a_bad_native_file_is_unreadable_with_its_reason_and_the_rest_runs(mixed):
    _, rows = mixed
    assert rows["BAD"]["reject_reason"] == "unreadable" and "leaves the campaign folder" in rows["BAD"]["reject_detail"]
    assert rows["CUT"]["reject_reason"] == "unreadable" and "CUT.tdms" in rows["CUT"]["reject_detail"]


# --- rocklab track --------------------------------------------------------


def test_rocklab_track_writes_the_rotation_record_and_the_figure(tmp_path, capsys):
    from rocklab.cli import main
    from rocklab.lab.records import read_any_record

    fs = 60.0
    _, theta = motion(60, fs)
    video = tmp_path / "wall.mp4"
    write_video(video, fs, theta, 0 * theta, SPEC, TINY, rng=5)
    out, fig = tmp_path / "wall.csv.gz", tmp_path / "wall.png"
    assert main(["track", str(video), "-o", str(out), "--figure", str(fig), "--test-id", "W1"]) == 0
    rec = read_any_record(out, "W1")
    assert isinstance(rec, RotationRecord) and rec.fs == pytest.approx(fs)
    np.testing.assert_allclose(rec.dof["theta"], theta, atol=1e-2)
    assert rec.header["source"].startswith("rocklab track wall.mp4: 60 of 60 frames tracked")
    assert fig.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "60 tracked" in capsys.readouterr().out


def test_rocklab_track_refuses_a_film_without_four_markers_in_one_line(tmp_path, capsys):
    from rocklab.cli import main

    video = tmp_path / "three.avi"
    _film(video, 30.0, [np.array([[10.0, 20.0], [10.0, 60.0], [40.0 + k, 20.0]]) for k in range(10)])
    assert main(["track", str(video)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("rocklab track: ") and "three.avi: fewer than four markers found" in err
    assert "\n" not in err and not (tmp_path / "three.rotation.csv.gz").exists()


# --- accuracy -------------------------------------------------------------


def test_the_smallest_resolved_impact_is_the_slowest_found_within_005():
    from rocklab.lab.accuracy import smallest_resolved

    truth = pd.DataFrame({"t": [1.0, 2.0, 3.0, 4.0], "e": [0.9] * 4, "thetadot_before": [0.4, -0.3, 0.2, -0.1]})
    found = pd.DataFrame({"t_s": [1.001, 2.0, 3.002, 4.0], "e_velocity": [0.91, 0.94, 0.80, np.nan]})
    # the impact at 3 s is off by 0.1, the one at 4 s has no velocities
    assert smallest_resolved(found, truth) == pytest.approx(0.3)
    assert np.isnan(smallest_resolved(found.iloc[2:], truth))


def test_lab_points_are_the_rigid_body_map_the_transducers_read():
    from rocklab.lab.kinematics import lab_points, transducer_elongation

    X = np.array([[710.0, 0.0, 300.0], [-710.0, 56.0, 1000.0]])
    F = np.array([[710.0, -200.0, 300.0], [-710.0, -180.0, 1000.0]])
    th, ph = np.array([0.05, -0.03, 0.0]), np.array([0.001, -0.002, 0.0])
    v, w = np.array([0.1, 0.2, 0.0]), np.array([0.3, -0.1, 0.0])
    P = lab_points(th, ph, v, w, X, 113.0)
    E = np.linalg.norm(P - F, axis=2) - np.linalg.norm(X - F, axis=1)
    np.testing.assert_allclose(E, transducer_elongation(th, ph, v, w, X, F, 113.0), atol=1e-9)
    np.testing.assert_allclose(P[2], X)
    # theta about the active edge y = +b/2: the top moves towards +y, the edge stays
    edge = lab_points([0.1], [0.0], [0.0], [0.0], [[0.0, 56.5, 0.0], [0.0, 0.0, 1000.0]], 113.0)[0]
    np.testing.assert_allclose(edge[0], [0.0, 56.5, 0.0], atol=1e-12)
    assert edge[1, 1] > 90.0
