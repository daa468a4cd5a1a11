"""Four-degree-of-freedom wall kinematics (Sect. 2.2, Eqs. 3-8)."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import least_squares

from rocklab.lab.kinematics import (
    normalised_peaks,
    simplified_channel,
    solve_wall_motion,
    theta_simplified,
    transducer_elongation,
    wall_motion_dataset,
)

CAMPAIGN = Path(__file__).resolve().parents[1] / "raw" / "campaign"

# Usual layout of specimen 1b, one-sided setup (spec; setups.csv S-1b-1s-*).
B = 113.0
WALL = np.array([[-710, 0, 280], [-710, 0, 680], [710, 0, 280], [710, 0, 680], [710, 0, 480], [0, 56.5, 400]], float)
FRAME = np.array(
    [[-710, -180, 280], [-710, -210, 680], [710, -185, 280], [710, -205, 680], [860, 0, 480], [0, 216.5, 400]], float
)


def rocking_motion(n=4000, amp=0.12):
    """A decaying rocking history crossing theta = 0 many times, with
    twist and sliding, including samples exactly at theta = 0."""
    t = np.linspace(0.0, 4.0, n)
    theta = amp * np.exp(-0.5 * t) * np.cos(2 * np.pi * 1.3 * t)
    theta[::500] = 0.0
    phi = 4e-3 * np.sin(2 * np.pi * 0.7 * t + 0.3)
    v = 2.5 * np.sin(2 * np.pi * 0.4 * t)
    w = -3.0 + 1.5 * np.cos(2 * np.pi * 0.9 * t)
    return theta, phi, v, w


def test_vertical_wall_reads_zero():
    e = transducer_elongation([0.0], [0.0], [0.0], [0.0], WALL, FRAME, B)
    assert np.allclose(e, 0.0, atol=1e-12)


def test_pure_rocking_closed_form():
    # A point at (x, 0, z) rotating about the edge (0, +-b/2, 0): circle of
    # radius sqrt(z^2 + b^2/4) about the edge, read by a transducer along y.
    th = np.array([0.08, -0.05])
    e = transducer_elongation(th, 0 * th, 0 * th, 0 * th, WALL[1:2], FRAME[1:2], B)[:, 0]
    z, fy = 680.0, -210.0
    for k, t in enumerate(th):
        ey = np.sign(t) * B / 2
        y = ey + (0 - ey) * np.cos(t) + z * np.sin(t)
        zz = -(0 - ey) * np.sin(t) + z * np.cos(t)
        assert e[k] == pytest.approx(np.hypot(y - fy, zz - z) - 210.0, abs=1e-12)
    assert e[0] > 0 > e[1]


def test_sign_convention_channel5_pushed_reads_negative():
    e = transducer_elongation([0.05], [0.0], [0.0], [0.0], WALL, FRAME, B)[0]
    assert e[5] < 0 and e[1] > 0 and e[0] > 0


def test_jacobian_matches_finite_differences():
    from rocklab.lab.kinematics import _pose

    rng = np.random.default_rng(1)
    q = np.column_stack(
        [rng.uniform(-0.1, 0.1, 50), rng.uniform(-0.01, 0.01, 50), rng.uniform(-5, 5, 50), rng.uniform(-5, 5, 50)]
    )
    q[np.abs(q[:, 0]) < 1e-3, 0] = 0.02  # away from the kink
    L, J = _pose(*q.T, WALL, FRAME, B, True)
    for a, h in enumerate([1e-7, 1e-7, 1e-5, 1e-5]):
        qp, qm = q.copy(), q.copy()
        qp[:, a] += h
        qm[:, a] -= h
        fd = (_pose(*qp.T, WALL, FRAME, B, False)[0] - _pose(*qm.T, WALL, FRAME, B, False)[0]) / (2 * h)
        assert np.allclose(J[a], fd, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("channels", [[0, 1, 3, 4], [0, 1, 2, 3, 4], [0, 1, 2, 3, 4, 5]])
def test_round_trip_exact_readings(channels):
    theta, phi, v, w = rocking_motion()
    e = transducer_elongation(theta, phi, v, w, WALL[channels], FRAME[channels], B)
    sol = solve_wall_motion(e, WALL[channels], FRAME[channels], B)
    assert sol["converged"].all()
    assert np.max(np.abs(sol["theta"] - theta)) < 1e-9
    assert np.max(np.abs(sol["phi"] - phi)) < 1e-9
    assert np.max(np.abs(sol["v"] - v)) < 1e-6
    assert np.max(np.abs(sol["w"] - w)) < 1e-6
    assert np.all(sol["n_channels"] == len(channels))
    assert np.nanmax(sol["residual_rms"]) < 1e-9


def test_round_trip_with_v_fixed():
    theta, phi, _, w = rocking_motion()
    v = np.zeros_like(theta)
    ch = [0, 1, 3]
    e = transducer_elongation(theta, phi, v, w, WALL[ch], FRAME[ch], B)
    sol = solve_wall_motion(e, WALL[ch], FRAME[ch], B, solve_v=False)
    assert sol["converged"].all()
    assert np.all(sol["v"] == 0.0)
    assert np.max(np.abs(sol["theta"] - theta)) < 1e-9
    assert np.max(np.abs(sol["phi"] - phi)) < 1e-9
    # Without a channel along x, v is unobservable: the full solve fails cleanly.
    bad = solve_wall_motion(e, WALL[ch], FRAME[ch], B)
    assert not bad["converged"].any()


def test_unusual_layout_round_trip():
    # Oblique and inclined transducers, frame on both sides, one vertical.
    wall = np.array([[-600, -40, 150], [-500, 56.5, 900], [650, 0, 500], [300, -56.5, 700], [700, 20, 300]], float)
    frame = np.array([[-650, -250, 100], [-450, 300, 950], [700, -190, 620], [350, -260, 650], [880, 40, 280]], float)
    theta, phi, v, w = rocking_motion(n=1500)
    e = transducer_elongation(theta, phi, v, w, wall, frame, B)
    sol = solve_wall_motion(e, wall, frame, B)
    assert sol["converged"].all()
    assert np.max(np.abs(sol["theta"] - theta)) < 1e-9


def test_lost_samples_and_weights():
    theta, phi, v, w = rocking_motion(n=800)
    e = transducer_elongation(theta, phi, v, w, WALL[:5], FRAME[:5], B)
    e[100:150, 1] = np.nan  # a gap: four channels left, still exact
    e[200, [0, 1]] = np.nan  # two lost: three channels for four unknowns
    wts = np.ones((800, 5))
    wts[300:310, 2] = 0
    wts[300:310, 3] = 0  # only 0, 1, 4 left: unsolvable
    e[400:410, 3] = 1e3  # garbage, excluded by weight
    wts[400:410, 3] = 0
    sol = solve_wall_motion(e, WALL[:5], FRAME[:5], B, weights=wts)
    good = np.ones(800, bool)
    good[[200, *range(300, 310)]] = False
    assert np.all(sol["n_channels"][100:150] == 4)
    assert np.max(np.abs(sol["theta"][good] - theta[good])) < 1e-9
    assert not sol["converged"][~good].any()
    assert np.isnan(sol["theta"][~good]).all()


def test_least_squares_matches_scipy_per_step():
    rng = np.random.default_rng(7)
    theta, phi, v, w = rocking_motion(n=60)
    ch = [0, 1, 2, 3, 4, 5]
    e = transducer_elongation(theta, phi, v, w, WALL[ch], FRAME[ch], B)
    e += rng.normal(0, 0.05, e.shape)
    sol = solve_wall_motion(e, WALL[ch], FRAME[ch], B)
    for k in range(len(theta)):

        def res(q, k=k):
            return transducer_elongation(*q[:, None], WALL[ch], FRAME[ch], B)[0] - e[k]

        q0 = [sol["theta"][k] + 1e-3, 0, 0, 0]
        ref = least_squares(res, q0, xtol=1e-15, ftol=1e-15, gtol=1e-15).x
        assert sol["theta"][k] == pytest.approx(ref[0], abs=1e-9)
        assert sol["w"][k] == pytest.approx(ref[3], abs=1e-6)
        rms = np.sqrt(np.mean(res(ref) ** 2))
        assert sol["residual_rms"][k] == pytest.approx(rms, rel=1e-6, abs=1e-12)


def test_eq8_close_to_full_solution_for_pure_rocking():
    # Fig. 9a: for slender walls Eq. 8 and the four-dof solution superimpose.
    theta = np.linspace(-0.12, 0.12, 241)
    z = np.zeros_like(theta)
    e = transducer_elongation(theta, z, z, z, WALL, FRAME, B)
    ch, h = simplified_channel(WALL, FRAME, [0, 1, 3, 4])
    assert ch == 1 and h == -680.0 * -1
    t8 = theta_simplified(e[:, ch], h)
    assert np.max(np.abs(t8 - theta)) < 0.01 * 0.12
    # Channel 5 (frame on +y): negative signed height, same sign of theta.
    ch5, h5 = simplified_channel(WALL, FRAME, [5])
    assert ch5 == 5 and h5 < 0
    assert np.all(np.sign(theta_simplified(e[theta != 0, 5], h5)) == np.sign(theta[theta != 0]))


def test_dataset_and_normalised_peaks():
    theta, phi, v, w = rocking_motion(n=400)
    e = transducer_elongation(theta, phi, v, w, WALL, FRAME, B)
    t = np.arange(400) / 400.0
    ds = wall_motion_dataset(t, e, WALL, FRAME, B, alpha=0.14, channels=[0, 1, 3, 4])
    assert set(["theta", "phi", "v", "w", "residual_rms", "theta_eq8"]) <= set(ds)
    assert np.allclose(ds.theta, theta, atol=1e-9)
    # Eq. 8 ignores the sliding w (up to 4.5 mm over h = 680 mm here).
    assert ds.attrs["theta_eq8_max_abs_diff"] < 0.02
    assert ds.attrs["peak_theta"] == pytest.approx(np.max(np.abs(theta)) / 0.14)
    pk = normalised_peaks(theta, phi, v, w, 0.14, B)
    assert pk["w"] == pytest.approx(np.max(np.abs(w)) / B)


@pytest.mark.skipif(not CAMPAIGN.exists(), reason="lab campaign not available")
def test_real_record_sign_and_fit():
    # T0001: pushed, held tilted at the start; channel 1 reads ~ +86.9 mm.
    setups = pd.read_csv(CAMPAIGN / "setups.csv")
    g = setups[setups.setup == "S-1a-2s"].set_index("channel").loc[[0, 1, 2, 3, 4]]
    wall = g[["wall_x_mm", "wall_y_mm", "wall_z_mm"]].to_numpy(float)
    frame = g[["frame_x_mm", "frame_y_mm", "frame_z_mm"]].to_numpy(float)
    rec = pd.read_csv(CAMPAIGN / "tests" / "T0001.csv.gz", comment="#")
    e = rec[["ch0", "ch1", "ch2", "ch3", "ch4"]].to_numpy(float)
    sol = solve_wall_motion(e, wall, frame, 113.0, weights=[1, 1, 0, 1, 1])
    assert sol["converged"].all()
    assert sol["theta"][0] == pytest.approx(0.094, abs=0.002)
    # With the backup channel in, the least-squares residual stays small
    # (mm-level only at isolated spikes), which checks the sign conventions.
    full = solve_wall_motion(e, wall, frame, 113.0)
    assert np.median(full["residual_rms"]) < 0.01
