"""rocklab.lab.motion against exact free-rocking motions with known landmarks.

The truth is generated here, independently of rocklab: the exact nonlinear
rocking equation theta'' = -p^2 sin(alpha sgn(theta) - theta) integrated by
scipy's solve_ivp flight by flight, impacts thetadot+ = e thetadot-, then
transducer noise, 50 Hz hum and post-impact ringing are added.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from scipy.integrate import solve_ivp

from rocklab.io import write_netcdf
from rocklab.lab.flight_fit import local_fit, model_velocity, odd_samples
from rocklab.lab.motion import (
    MOTION_GROUP,
    SCALAR_FIELDS,
    centre_amplification,
    extract_motion,
    motion_from_dataset,
    motion_to_dataset,
    noise_level,
    read_motion,
    stored_motion,
)

P = 3.4  # rad/s, a 1.1-1.6 m wall
ALPHA = 0.075  # rad, effective instability angle of the dynamics (h/b ~ 13)


def free_rocking_record(
    *,
    alpha=ALPHA,
    p=P,
    e=0.93,
    theta0_frac=0.99,
    boundary="two-sided",
    fs=400.0,
    hold_s=1.0,
    duration=12.0,
    noise=1e-5,
    hum=2e-5,
    ring=3e-4,
    gap=0.0,
    e_base=0.9,
    sign=1,
    seed=0,
    min_peak=2e-6,
):
    """Exact free rocking released from rest at theta0 = theta0_frac * alpha.

    Two-sided: e > 0 at every base impact.  One-sided: e < 0 (rebound); with
    ``gap`` > 0 [rad] the wall swings past zero on the other hinge (base
    impact e_base), hits the transverse walls at -gap (coefficient
    e / e_base^2) and comes back through a second base impact (e_base).

    Returns t, theta, truth: release time, theta0, impacts (t arriving at
    zero, thetadot before, thetadot after leaving zero), signed peaks and
    their times.
    """
    rng = np.random.default_rng(seed)
    theta0 = theta0_frac * alpha
    e_tr = e / e_base**2

    def rhs(_, y, side):
        return [y[1], -(p**2) * np.sin(alpha * side - y[0])]

    def level(target, direction):
        def ev(_, y, side):
            return y[0] - target

        ev.terminal, ev.direction = True, direction
        return ev

    def top(_, y, side):
        return y[1]

    segs, impacts, peaks, peak_t, pending = [], [], [], [], None
    y, tcur, side = np.array([theta0, 0.0]), hold_s, 1.0
    while tcur < hold_s + duration:
        events = [level(0.0, -side)]
        if gap and side < 0:
            events.append(level(-gap, -1))
        top.direction = -side
        sol = solve_ivp(
            rhs,
            (tcur, hold_s + duration),
            y,
            args=(side,),
            events=events + [top],
            dense_output=True,
            rtol=1e-11,
            atol=1e-14,
            max_step=0.02,
        )
        segs.append(sol)
        for tt, yy in zip(sol.t_events[-1], sol.y_events[-1]):
            if tt > tcur + 1e-9:
                peaks.append(yy[0])
                peak_t.append(tt)
        hits = [(ev[0], k) for k, ev in enumerate(sol.t_events[:-1]) if len(ev)]
        if not hits:
            break
        ti, which = min(hits)
        v = sol.sol(ti)[1]
        if which == 1:  # transverse walls
            y = np.array([-gap, e_tr * v])
        elif boundary == "two-sided":
            impacts.append((ti, v, e * v))
            y, side = np.array([0.0, e * v]), -side
        elif not gap:
            impacts.append((ti, v, e * v))
            y = np.array([0.0, e * v])
        elif side > 0:  # base impact, into the gap
            pending = (ti, v)
            y, side = np.array([0.0, e_base * v]), -1.0
        else:  # base impact, back from the gap
            impacts.append((pending[0], pending[1], e_base * v))
            y, side = np.array([0.0, e_base * v]), 1.0
        tcur = ti
        if peaks and abs(peaks[-1]) < min_peak:
            break
    t = np.arange(0.0, hold_s + duration, 1.0 / fs)
    theta = np.full_like(t, theta0)
    for s in segs:
        m = (t >= s.t[0]) & (t <= s.t[-1])
        if m.any():
            theta[m] = s.sol(t[m])[0]
    theta[t > segs[-1].t[-1]] = 0.0
    for ti, v, _ in impacts:
        dt = t - ti
        m = dt > 0
        theta[m] += ring * abs(v) * np.exp(-dt[m] / 0.012) * np.cos(2 * np.pi * 30 * dt[m])
    theta += noise * rng.standard_normal(t.size)
    theta += hum * np.sin(2 * np.pi * 50.0 * t + rng.uniform(0, 2 * np.pi))
    truth = dict(
        t_release=hold_s,
        theta0=theta0,
        impacts=np.array(impacts, float),
        peaks=np.array(peaks),
        peak_t=np.array(peak_t),
        alpha=alpha,
        p=p,
        e=e,
    )
    return t, sign * theta, truth


@pytest.fixture(scope="module")
def two_sided():
    return free_rocking_record()


def test_noise_level_sees_noise_and_hum():
    t, th, _ = free_rocking_record(duration=4.0, noise=1e-5, hum=0.0)
    assert noise_level(th, 400.0) == pytest.approx(1e-5, rel=0.15)
    t, th, _ = free_rocking_record(duration=4.0, noise=1e-5, hum=2e-5)
    # rms of noise + hum: sqrt(1e-10 + 2e-10) = 1.7e-5
    assert 1.2e-5 < noise_level(th, 400.0) < 2.2e-5


def test_local_fit_is_exact_for_the_linearised_flight():
    """The hyperbolic basis reproduces alpha - C cosh(p (t - t0)) exactly."""
    t = np.arange(0, 0.5, 1 / 400)
    y = 0.08 - 0.03 * np.cosh(P * (t - 0.1))
    c = local_fit(t, y, 0.3, 0.0, 0.5, P, 400.0, hum_hz=())
    v_true = -0.03 * P * np.sinh(P * 0.2)
    assert model_velocity(c, 0.0, P) == pytest.approx(v_true, rel=1e-9)


def test_release_and_theta0(two_sided):
    t, th, truth = two_sided
    m = extract_motion(t, th, 400.0, "two-sided", P)
    assert m.sign == 1
    assert abs(m.theta0 - truth["theta0"]) / ALPHA < 1e-3
    assert m.t_release == pytest.approx(truth["t_release"], abs=0.03)


def test_impacts_velocities_and_peaks(two_sided):
    t, th, truth = two_sided
    m = extract_motion(t, th, 400.0, "two-sided", P)
    imp = truth["impacts"]
    n = len(m.impacts)
    assert n >= 15
    vb, va = imp[:n, 1], imp[:n, 2]
    # Within 1 % while the flight outlasts the ringing (|v| > 1/4 of the first
    # impact); later ones degrade gracefully (e_exp uses peaks, not velocities).
    big = np.abs(vb) > 0.25 * np.abs(vb[0])
    assert big.sum() >= 10
    assert np.allclose(m.impacts.t_s[big], imp[:n, 0][big], atol=2e-4)
    assert np.allclose(m.impacts.thetadot_before[big], vb[big], rtol=0.01)
    assert np.allclose(m.impacts.thetadot_after[big], va[big], rtol=0.01)
    assert np.allclose(m.peaks, np.abs(truth["peaks"][:n]), atol=3e-5)
    assert m.t_first_impact == pytest.approx(imp[0, 0], abs=1e-3)


def test_pull_direction_and_100hz():
    t, th, truth = free_rocking_record(sign=-1, fs=100.0, seed=3)
    m = extract_motion(t, th, 100.0, "two-sided", P)
    assert m.sign == -1
    assert abs(m.theta0 - truth["theta0"]) / ALPHA < 2e-3
    n = len(m.impacts)
    assert n >= 10
    assert np.allclose(m.peaks, np.abs(truth["peaks"][:n]), atol=5e-5)
    assert np.all(m.impacts.thetadot_before.iloc[:20:2] > 0)  # theta < 0 falls back up


def test_end_of_motion_is_where_peaks_reach_the_noise(two_sided):
    t, th, truth = two_sided
    m = extract_motion(t, th, 400.0, "two-sided", P)
    assert m.peaks.min() >= m.peak_threshold
    n = len(m.peaks)
    assert n < len(truth["peaks"])
    assert abs(truth["peaks"][n]) < 1.3 * m.peak_threshold
    assert m.t_end > m.impacts.t_s.iloc[-1]


def test_one_sided_rebounds():
    t, th, truth = free_rocking_record(boundary="one-sided", e=-0.5, theta0_frac=0.98, alpha=0.09, seed=1)
    m = extract_motion(t, th, 400.0, "one-sided", P)
    imp = truth["impacts"]
    n = len(m.impacts)
    assert n >= 3
    assert np.allclose(m.impacts.t_s, imp[:n, 0], atol=1e-4)
    assert np.allclose(m.impacts.e_velocity.iloc[:2], -0.5, atol=0.005)
    assert np.all(m.impacts.thetadot_before < 0) and np.all(m.impacts.thetadot_after > 0)
    assert np.allclose(m.peaks, np.abs(truth["peaks"][:n]), atol=3e-5)
    assert m.n_negative_excursions == 0


def test_one_sided_gap_excursions_are_merged_and_reported():
    gap = 0.004
    t, th, truth = free_rocking_record(boundary="one-sided", e=-0.35, theta0_frac=0.98, alpha=0.09, gap=gap, seed=2)
    m = extract_motion(t, th, 400.0, "one-sided", P)
    n = len(m.impacts)
    assert n >= 3
    pos = truth["peaks"][truth["peaks"] > 0]
    assert np.allclose(m.peaks, pos[:n], atol=3e-5)
    assert m.n_negative_excursions >= 2
    assert m.impacts.negative_excursion.iloc[0] == pytest.approx(gap, abs=3e-4)
    # composite velocity ratio across the excursion (|e| > |e_base^2 e_tr|:
    # the wall regains on the way back the potential energy lost in the gap)
    imp = truth["impacts"]
    assert m.impacts.e_velocity.iloc[0] == pytest.approx(imp[0, 2] / imp[0, 1], abs=0.005)


def test_rejects_unknown_boundary(two_sided):
    t, th, _ = two_sided
    with pytest.raises(ValueError):
        extract_motion(t, th, 400.0, "three-sided", P)


def test_centre_amplification_ratio_after_first_impact():
    side = np.r_[10.0, 5.0, -2.0, 1.0]
    assert centre_amplification(1.05 * side, side, 1) == pytest.approx(1.05)
    assert centre_amplification(np.r_[99.0, side[1:]], side, 1) == pytest.approx(1.0)


@pytest.mark.parametrize(
    "k_gap,hump,quiet",
    [
        (None, 0.0, False),  # stops dead after its last small flight
        (2, 0.0, False),  # stops dead coming back up from its 3rd swing into the gap
        (None, 6e-4, False),  # then drifts (settling askew): no curvature of a flight
        (0, 0.0, True),  # stops dead after the 1st impact: only a smoother overshoot
    ],
)
def test_a_wall_that_stops_dead_ends_on_its_last_flight(k_gap, hump, quiet):
    """One-sided wall that stops dead at theta = 0 and may then drift slowly:
    every flight is kept, no spurious final impact is added."""
    kw = dict(
        boundary="one-sided",
        e=-0.35,
        theta0_frac=0.98,
        alpha=0.09,
        gap=0.002,
        seed=6,
        min_peak=1e-3,
        **(dict(noise=5e-6, hum=0.0) if quiet else {}),
    )
    t, th, truth = free_rocking_record(**kw)
    _, clean, _ = free_rocking_record(**{**kw, "noise": 0.0, "hum": 0.0, "ring": 0.0})
    t_stop = t[np.flatnonzero(clean)[-1]]
    if k_gap is not None:
        up = np.flatnonzero((clean[:-1] < 0) & (clean[1:] >= 0))
        t_stop = t[up[k_gap] + 1]
        th = np.where(t < t_stop, th, th - clean)
    x = np.clip((t - t_stop - 0.05) / 2.0, 0.0, 1.0)
    th = th + hump * np.sin(np.pi * x) ** 2 * (1 - 0.5 * x)
    m = extract_motion(t, th, 400.0, "one-sided", P)
    kept = (truth["peaks"] > 0) & (truth["peak_t"] < t_stop)
    assert len(m.peaks) == kept.sum()
    assert np.allclose(m.peaks, truth["peaks"][kept], atol=3e-5)
    if kept.any():
        # the end is the impact (arrival at zero) after the last flight
        t_arrival = t[(t > truth["peak_t"][kept][-1]) & (clean <= 0)][0]
        assert m.t_end == pytest.approx(t_arrival, abs=0.01)


def test_a_stored_motion_reads_back_equal(two_sided, tmp_path):
    """The motion group of results/tests/<job>/<test_id>.nc: the Motion read back equals the one extracted."""
    t, th, _ = two_sided
    m = extract_motion(t, th, 400.0, "two-sided", P)
    write_netcdf(xr.Dataset(), tmp_path / "T1.nc", groups={MOTION_GROUP: motion_to_dataset(m, {"test_id": "T1"})})
    back = read_motion(tmp_path / "T1.nc")
    for name in SCALAR_FIELDS:
        assert getattr(back, name) == getattr(m, name) or (np.isnan(getattr(m, name)) and np.isnan(getattr(back, name)))
        assert type(getattr(back, name)) is type(getattr(m, name))
    pd.testing.assert_frame_equal(back.impacts, m.impacts)
    np.testing.assert_array_equal(back.peaks, m.peaks)
    assert len(m.impacts) >= 5


def test_a_motion_without_impacts_reads_back_equal(tmp_path):
    """A record that ends before its first impact stores typed, empty impacts."""
    t, th, truth = free_rocking_record(seed=4)
    n = int((truth["impacts"][0, 0] + 0.05) * 400)
    m = extract_motion(t[:n], th[:n], 400.0, "two-sided", P)
    assert m.impacts.empty
    write_netcdf(xr.Dataset(), tmp_path / "T2.nc", groups={MOTION_GROUP: motion_to_dataset(m)})
    back = read_motion(tmp_path / "T2.nc")
    pd.testing.assert_frame_equal(back.impacts, m.impacts)
    assert back.peaks.size == 0


def test_a_test_without_motion_stores_the_reason():
    ds = xr.Dataset(attrs={"test_id": "T3", "valid": 0, "reject_reason": "unreadable", "reject_detail": "truncated"})
    stored = stored_motion(ds)
    assert stored.attrs["test_id"] == "T3"
    with pytest.raises(ValueError, match="truncated"):
        motion_from_dataset(stored)


def test_an_apex_is_resolved_where_its_flight_spans_the_samples_of_its_fit():
    """The flight of apex A lasts 2 arccosh(1 / (1 - A/alpha)) / p (Housner), the exact rigid block's
    2 quarter_period to a per cent at these amplitudes; an apex is resolved from MIN_APEX_SAMPLES samples."""
    from rocklab.lab.motion import MIN_APEX_SAMPLES, apex_resolved
    from rocklab.physics.flight import quarter_period

    alpha, p, fs = 0.245, 5.39, 200.0
    edge = alpha * (1.0 - 1.0 / np.cosh(MIN_APEX_SAMPLES * p / (2.0 * fs)))
    assert apex_resolved(np.array([1.01 * edge, 0.0068 * alpha]), alpha, p, fs).all()
    assert not apex_resolved(np.array([0.99 * edge, 0.0006 * alpha]), alpha, p, fs).any()
    exact = 2.0 * quarter_period(np.array([edge]), np.array([alpha]), np.array([p]))[0] * fs
    assert exact == pytest.approx(MIN_APEX_SAMPLES, rel=0.01)
    assert not apex_resolved(np.array([np.nan]), alpha, p, fs).any()


def test_the_smoothing_of_a_mirrored_record_is_the_mirrored_smoothing():
    """extract_motion hands the release its smoothing of theta turned to the release side (sign * sm)
    instead of smoothing u = sign * theta again: the same bits only if the filter is odd to the last bit."""
    from scipy.signal import savgol_filter

    rng = np.random.default_rng(7)
    theta = np.cumsum(rng.normal(0, 1e-4, 3000)) + 0.01 * np.sin(np.arange(3000) / 40)
    for fs in (100.0, 400.0):
        win = odd_samples(0.025 * fs)
        assert savgol_filter(-theta, win, 2).tobytes() == (-savgol_filter(theta, win, 2)).tobytes()
