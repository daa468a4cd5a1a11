"""Batch engine (numba) against the event-driven reference of rocklab.simulation.rocking_model."""

import numpy as np
import pytest

from rocklab.physics import restitution, wall
from rocklab.simulation import engine
from rocklab.simulation.batch import free_batch, ground_batch, overturning_batch
from rocklab.simulation.reference import simulate_free, simulate_ground
from rocklab.simulation.rocking_model import RockingModel

ALPHA, P = 0.1, float(wall.frequency_parameter(3.0))


def _record(n=1200, dt=0.01, seed=3):
    """Deterministic broadband pulse-like record [m/s^2]."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt
    f = rng.uniform(0.3, 3.0, 12)
    ph = rng.uniform(0, 2 * np.pi, 12)
    env = (t / 2.0) * np.exp(1 - t / 2.0)
    return 1.5 * env * np.sin(2 * np.pi * f[:, None] * t + ph[:, None]).sum(0) / 3.0, dt


def test_free_batch_linear_is_exact():
    model = RockingModel(alpha=ALPHA, p=P, form="linear")
    ref = simulate_free(model, 0.8 * ALPHA, t_end=15.0).impacts
    ds = free_batch(model, [0.8 * ALPHA], t_end=15.0, dt=0.01, max_impacts=len(ref))
    assert int(ds.n_impacts[0]) == len(ref) >= 5
    np.testing.assert_allclose(ds.t_impact[0], ref.t, rtol=1e-10)
    np.testing.assert_allclose(ds.theta_peak[0], ref.theta_peak_before, rtol=1e-9)
    np.testing.assert_allclose(ds.thetadot_after[0], ref.thetadot_after, rtol=1e-9)


def test_free_batch_exact_converges_to_reference():
    model = RockingModel(alpha=ALPHA, p=P)
    ref = simulate_free(model, 0.8 * ALPHA, t_end=10.0).impacts.t.to_numpy()[:4]
    errs = [
        np.max(
            np.abs(
                free_batch(model, 0.8 * ALPHA, t_end=10.0, dt=dt, substeps=1, max_impacts=4).t_impact[0].values - ref
            )
        )
        for dt in (0.04, 0.02, 0.01)
    ]
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 1e-7
    assert errs[0] / errs[1] > 8  # RK4: fourth order


@pytest.mark.parametrize("loss", [{"mu": 0.002}, {"kappa": 3.0}, {"zeta": 0.01, "mu": 0.001, "kappa": 1.0}])
def test_the_exact_form_has_dry_friction_and_drag_as_the_reference(loss):
    """The losses in flight beyond the viscous one, as their laws declare them: dry friction jumps at
    every turn, where the engine starts a new step (to 1e-9 of the reference, not the 1e-5 of a step
    over the jump)."""
    model = RockingModel(alpha=ALPHA, p=P, **loss)
    ref = simulate_free(model, 0.8 * ALPHA, t_end=10.0).impacts
    n = len(ref)
    ds = free_batch(model, 0.8 * ALPHA, t_end=10.0, dt=0.01, substeps=16, max_impacts=n)
    assert int(ds.n_impacts[0]) == n >= 5
    np.testing.assert_allclose(ds.t_impact[0], ref.t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(ds.theta_peak[0], ref.theta_peak_before, rtol=0, atol=1e-9)


def test_free_batch_recovers_e_with_eq11():
    """Eq. 11 applied to simulated peaks returns the e used (per history)."""
    model = RockingModel(alpha=ALPHA, p=P)
    scales = np.array([0.85, 0.95, 1.0])
    ds = free_batch(model, np.full(3, 0.9 * ALPHA), e_scale=scales, t_end=30.0, dt=0.005, substeps=2, max_impacts=6)
    pk = ds.theta_peak.values
    n = np.arange(1, 6)
    e = restitution.experimental_pena(pk[:, n], pk[:, :1], ALPHA, n)
    np.testing.assert_allclose(e, np.broadcast_to((scales * restitution.two_sided(ALPHA))[:, None], e.shape), rtol=1e-6)


def test_free_batch_one_sided_and_gap():
    e1s = restitution.one_sided(ALPHA)
    one = RockingModel(alpha=ALPHA, p=P, boundary="one-sided", form="linear")
    ds = free_batch(one, 0.7 * ALPHA, t_end=5.0, max_impacts=3)
    assert float(ds.thetadot_after[0, 0] / ds.thetadot_before[0, 0]) == pytest.approx(e1s, rel=1e-12)
    gap = RockingModel(alpha=ALPHA, p=P, boundary="one-sided", form="linear", gap=1e-6)
    dg = free_batch(gap, 0.7 * ALPHA, t_end=5.0, dt=1e-3, max_impacts=3)
    net = float(dg.thetadot_after[0, 2] / dg.thetadot_before[0, 0])
    assert net == pytest.approx(e1s, rel=1e-3)


def test_overturning_batch_matches_reference():
    ag, dt = _record()
    model = RockingModel(alpha=ALPHA, p=P, form="linear")
    amps = np.array([0.6, 1.0, 1.4, 1.8, 2.4])
    durs = np.array([0.7, 1.0, 1.3])
    over, mr = overturning_batch(ag, dt, model, amps, durs, return_max=True)
    assert over.any() and not over.all()
    for i, a in enumerate(amps):
        for j, d in enumerate(durs):
            ref = simulate_ground(model, a * ag, dt * d)
            assert ref.overturned == over[i, j], (a, d)


def test_ground_batch_linear_impacts_match_reference():
    ag, dt = _record()
    model = RockingModel(alpha=ALPHA, p=P, form="linear")
    ref = simulate_ground(model, 0.4 * ag, dt)
    assert not ref.overturned and len(ref.impacts) > 3
    ds = ground_batch(ag, dt, [model], amplitude_scale=0.4, max_impacts=len(ref.impacts))
    k = min(len(ref.impacts), 10)
    np.testing.assert_allclose(ds.t_impact[0, :k], ref.impacts.t[:k], atol=1e-7)
    np.testing.assert_allclose(ds.thetadot_before[0, :k], ref.impacts.thetadot_before[:k], rtol=1e-5, atol=1e-9)


def test_exact_form_batch_converges_under_ground_motion():
    ag, dt = _record()
    model = RockingModel(alpha=ALPHA, p=P)
    ref = simulate_ground(model, 0.8 * ag, dt).impacts.t.to_numpy()[:3]
    errs = [
        np.max(
            np.abs(
                ground_batch(ag, dt, [model], amplitude_scale=0.8, substeps=m, max_impacts=3).t_impact[0].values - ref
            )
        )
        for m in (1, 2, 4)
    ]
    assert errs[0] > errs[2] and errs[2] < 1e-5


@pytest.mark.parametrize("gap", [0.005, 0.02])
def test_impact_inside_one_coarse_step_is_found(gap):
    """A grazing transverse impact (one-sided wall with a gap) starts and ends
    inside one 0.2 s step, both step ends inside the gap: the turning point
    beyond -gap must be found as an event.  Without that check the batch
    missed the impact at 4.85 s (gap 0.02) and drifted by 0.9 s."""
    model = RockingModel(alpha=ALPHA, p=P, form="linear", boundary="one-sided", gap=gap)
    ref = simulate_free(model, 0.8 * ALPHA, t_end=10.0).impacts
    ds = free_batch(model, 0.8 * ALPHA, dt=0.2, t_end=10.0, max_impacts=len(ref) + 5)
    assert int(ds.n_impacts[0]) == len(ref) and (ref.kind == "transverse").sum() >= 3
    np.testing.assert_allclose(ds.t_impact[0, : len(ref)], ref.t, atol=1e-8)


def _sine_pulse(amplitude, dt=0.01):
    """One period of a 1 s sine [m/s^2], ending on zero."""
    return amplitude * np.sin(2 * np.pi * np.arange(101) * dt), dt


def _padded(ag, dt, seconds=20.0):
    """``ag`` followed by ``seconds`` of zeros: the free motion inside the record."""
    return np.concatenate([ag, np.zeros(round(seconds / dt))])


@pytest.mark.parametrize("form", ["linear", "exact"])
def test_wall_past_alpha_when_the_record_ends_overturns(form):
    """A 1 s sine pulse of 6-7 m/s^2 leaves the wall at 1.8-2.4 alpha with less
    than the critical energy: beyond the potential maximum it cannot climb back
    and falls (2.8-3.4 s on the padded record).  The engine and the reference
    once stopped following it there and reported it standing."""
    model = RockingModel(alpha=ALPHA, p=P, form=form)
    ag, dt = _sine_pulse(1.0)
    amps = np.array([6.0, 7.0])
    over = overturning_batch(ag, dt, model, amps, [1.0], substeps=4)[:, 0]
    ds = ground_batch(ag, dt, [model] * len(amps), amplitude_scale=amps, substeps=4)
    for a, o, o_ground, t_ground in zip(amps, over, ds.overturned.values, ds.t_overturn.values):
        padded = simulate_ground(model, _padded(a * ag, dt), dt)
        assert padded.overturned and padded.t_overturn > 2.5, a
        unpadded = simulate_ground(model, a * ag, dt).overturned
        assert (bool(o), bool(o_ground), unpadded) == (True, True, True), a
        assert t_ground == pytest.approx(padded.t_overturn, rel=1e-4), a


def test_ground_batch_covers_the_free_motion_after_the_record():
    """After a 1.5 m/s^2 sine pulse the wall rocks freely for 88 s: ``ground_batch``
    follows it to rest and counts its impacts and peaks as the reference on the
    padded record does (it once stopped with the record: 1 impact)."""
    model = RockingModel(alpha=ALPHA, p=P, form="linear")
    ag, dt = _sine_pulse(1.5)
    ref = simulate_ground(model, _padded(ag, dt, 100.0), dt)
    assert not ref.overturned and ref.t_rest is not None and len(ref.impacts) > 100
    ds = ground_batch(ag, dt, [model], max_impacts=len(ref.impacts) + 5)
    assert int(ds.n_impacts[0]) == len(ref.impacts)
    np.testing.assert_allclose(ds.t_impact[0, : len(ref.impacts)], ref.impacts.t, atol=1e-6)
    # the reference samples theta every dt: its peak lies a few (p dt)^2 below the true one
    sampled = np.nanmax(np.abs(ref.theta)) / ALPHA
    assert sampled <= float(ds.max_ratio[0]) < sampled * (1 + 2 * (P * dt) ** 2)


def test_onset_on_the_first_sample():
    """A record whose first sample alone exceeds the onset threshold starts the
    wall rocking at t = 0 (the engine once skipped the first sample: 0 impacts)."""
    model = RockingModel(alpha=ALPHA, p=P, form="linear")
    ag, dt = np.zeros(50), 0.01
    ag[0] = -60.0
    ref = simulate_ground(model, _padded(ag, dt, 60.0), dt)
    assert ref.t_rest is not None and len(ref.impacts) > 100
    ds = ground_batch(ag, dt, [model], max_impacts=len(ref.impacts) + 5)
    assert int(ds.n_impacts[0]) == len(ref.impacts)
    np.testing.assert_allclose(ds.t_impact[0, : len(ref.impacts)], ref.impacts.t, atol=1e-6)


def test_onset_on_one_sample_anywhere_in_a_quiet_record():
    """A wall at rest skips blocks of samples at once (engine._block_range):
    a single sample past the onset threshold g alpha, either way, starts it
    wherever it lies in a block, NaN samples before it or not.  The response
    to a spike at sample j is the one to a spike at sample 1 delayed by
    (j - 1) dt."""
    model = RockingModel(alpha=ALPHA, p=P, form="linear")
    dt, n = 0.01, 80
    for spike in (-20.0, 20.0):
        runs = []
        for j in range(1, 50):
            ag = np.zeros(n)
            ag[j] = spike
            ag[: max(j - 2, 0) : 3] = np.nan
            runs.append(ground_batch(ag, dt, [model], max_impacts=5))
        first = runs[0]
        assert int(first.n_impacts[0]) >= 5
        for j, ds in enumerate(runs, start=1):
            assert int(ds.n_impacts[0]) == int(first.n_impacts[0])
            np.testing.assert_allclose(ds.t_impact[0] - (j - 1) * dt, first.t_impact[0], atol=1e-9)


def test_block_range_of_a_record():
    ag = np.random.default_rng(1).normal(size=37)
    ag[[3, 20, 21]] = np.nan
    blocks = np.pad(ag, (0, -ag.size % engine._BLOCK), constant_values=np.nan).reshape(-1, engine._BLOCK)
    np.testing.assert_array_equal(engine._block_range(ag), [np.nanmin(blocks, axis=1), np.nanmax(blocks, axis=1)])


def test_excursion_inside_one_solver_step_is_an_impact():
    """Pacoima Dam at A_S/A = 0.84, D_S/D = 0.715, Housner's wall: after its 37th
    impact the wall crosses its edge and turns back inside one solver step of the
    reference, which once missed that impact (solve_ivp tests the sign at the
    step ends) and let the wall rock on past its edge on the wrong hinge; the
    engine then disagreed with it on 14 cells of the map (issue 13).  The
    crossing is checked against an independent fine-step integration."""
    from scipy.integrate import solve_ivp

    from rocklab.seismic.accelerograms import load_record

    tr = load_record("Pac164")
    ag, dt = 0.84 * tr.data, 0.715 * tr.stats.delta
    model = RockingModel(alpha=ALPHA, p=P, form="linear")
    ref = simulate_ground(model, ag, dt).impacts
    ds = ground_batch(ag, dt, [model], max_impacts=60)
    n = min(len(ref), 45)
    np.testing.assert_allclose(ds.t_impact[0, :n], ref.t[:n], atol=1e-7)
    t0, v0 = ref.t[36], ref.thetadot_after[36]
    t_rec = np.arange(len(ag) + 1) * dt
    a_rec = np.append(ag, 0.0)
    s = np.sign(v0)

    def rhs(t, y):
        return [y[1], P**2 * (y[0] - s * ALPHA - np.interp(t, t_rec, a_rec) / wall.G)]

    def edge(t, y):
        return y[0] if t > t0 + 1e-9 else s

    edge.terminal, edge.direction = True, -s
    fine = solve_ivp(rhs, (t0, t0 + 0.5), [0.0, v0], rtol=1e-12, atol=1e-16, max_step=1e-5, events=edge)
    assert ref.t[37] == pytest.approx(fine.t_events[0][0], abs=1e-8)
    assert ref.t[37] - t0 < 0.01


def _calibrated_walls():
    """Walls with every feature of a calibrated wall (rocklab.seismic.calibrated):
    alpha_r < alpha, amplitude-dependent e, a stopping threshold; one-sided with
    a gap, the threshold on the outer hinge's landings only."""
    from rocklab.physics import impact

    two = RockingModel(
        alpha=ALPHA,
        p=P,
        form="linear",
        alpha_rock=0.9 * ALPHA,
        impact=impact.Sticking(impact.AmplitudeLaw(impact.HousnerTwoSided(), 0.96, 0.03), 0.11),
    )
    base = impact.HousnerTwoSided()
    one = RockingModel(
        alpha=ALPHA,
        p=P,
        form="linear",
        boundary="one-sided",
        gap=0.01 * ALPHA,
        alpha_rock=0.74 * ALPHA,
        impact=impact.Sided(impact.Sticking(base, 0.2), base),
        transverse_impact=impact.AmplitudeLaw(impact.Transverse(), 1.22, 0.54),
    )
    return {"two-sided": two, "one-sided": one}


@pytest.mark.parametrize("boundary", ["two-sided", "one-sided"])
def test_sticking_law_in_the_engine_matches_the_reference(boundary):
    """The engine's sticking threshold (fourth law column): free rocking and a
    record give the reference's impacts, the last one a landing slower than
    v_stick thetadot_r followed by rest; without it the walls rock on."""
    model = _calibrated_walls()[boundary]
    v_stick = model.numba_law()[0, 3]
    assert v_stick > 0.1
    ref = simulate_free(model, 0.95 * model.alpha_pos, t_end=30.0)
    assert ref.t_rest is not None and len(ref.impacts) >= 3
    last = ref.impacts.iloc[-1]
    assert last.kind == "base" and abs(last.thetadot_before) < v_stick * model.thetadot_r
    assert last.thetadot_after == 0.0
    ds = free_batch(model, 0.95 * model.alpha_pos, t_end=30.0, dt=0.01, max_impacts=len(ref.impacts) + 5)
    assert int(ds.n_impacts[0]) == len(ref.impacts)
    np.testing.assert_allclose(ds.t_impact[0, : len(ref.impacts)], ref.impacts.t.to_numpy(float), atol=1e-7)
    after = ref.impacts.thetadot_after.to_numpy(float)
    np.testing.assert_allclose(ds.thetadot_after[0, : len(ref.impacts)], after, atol=1e-9)
    loose = free_batch(model, 0.95 * model.alpha_pos, t_end=30.0, dt=0.01, law=model.numba_law()[:, :3])
    assert int(loose.n_impacts[0]) > len(ref.impacts) + 10
    ag, dt = _record()
    for scale in (0.3, 0.6):
        ref = simulate_ground(model, _padded(scale * ag, dt, 30.0), dt)
        ds = ground_batch(ag, dt, [model], amplitude_scale=scale, max_impacts=len(ref.impacts) + 5)
        assert bool(ds.overturned[0]) == ref.overturned
        if not ref.overturned:
            assert int(ds.n_impacts[0]) == len(ref.impacts)
        n = min(int(ds.n_impacts[0]), len(ref.impacts))
        np.testing.assert_allclose(ds.t_impact[0, :n], ref.impacts.t.to_numpy(float)[:n], atol=1e-6)


def test_compile_kernels_covers_the_library_calls():
    """``make venv`` compiles the kernels with compile_kernels: the calls of a
    map job and of the batch front ends then need no other signature."""
    from rocklab.seismic.accelerograms import load_record
    from rocklab.seismic.maps import overturning_map
    from rocklab.simulation.batch import compile_kernels

    compile_kernels()
    compiled = set(engine.batch_kernel.signatures)
    assert compiled
    ag, dt = _record(n=300)
    model = RockingModel(alpha=ALPHA, p=P, boundary="one-sided", gap=1e-4)
    overturning_map(load_record("Pac164"), model="1s-eq17", n=2, polarity=-1)
    overturning_batch(list(ag), dt, model, 1.0, [0.9, 1.1], return_max=True)
    ground_batch(ag.astype(np.float32), dt, [model] * 2, amplitude_scale=[1.0, 2.0], max_impacts=3)
    free_batch(model, [0.05, 0.06], law=np.ones((2, 3, 3)), e_scale=0.9, t_end=1.0)
    assert set(engine.batch_kernel.signatures) == compiled
