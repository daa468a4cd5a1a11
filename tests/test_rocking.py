"""Event-driven reference of the rocking wall against independent truths."""

import numpy as np
import pytest

from rocklab.physics import flight, impact, restitution, wall
from rocklab.simulation.reference import simulate_free, simulate_ground
from rocklab.simulation.rocking_model import RockingModel


def _energy_drift(model, h, mask):
    side = np.where(h.theta > 0, 1, -1)
    e = model.energy(h.theta, h.thetadot, side)[mask]
    return np.max(np.abs(e - e[0])) / e[0]


def test_block_energy_closed_forms():
    """flight.energy: the centre of mass lifted from theta = 0 (exact) and
    Housner's linearisation, at rest at the instability rotation (Eq. 16)."""
    a, p = 0.15, 2.2
    assert flight.energy(a, 0.0, a, p) == pytest.approx(p**2 * (1 - np.cos(a)), rel=1e-14)
    assert flight.energy(a, 0.0, a, p, linear=True) == pytest.approx(0.5 * p**2 * a**2, rel=1e-14)
    assert flight.energy(0.0, 0.3, a, p) == flight.energy(0.0, 0.3, a, p, linear=True) == pytest.approx(0.045)
    # the linear form is the exact one for a slender wall: relative error ~ a^2/6
    assert flight.potential(1e-4, 0.01, p) == pytest.approx(flight.potential_linear(1e-4, 0.01, p), rel=3e-5)
    assert wall.overturning_velocity(a, p) == pytest.approx(np.sqrt(2 * p**2 * (1 - np.cos(a))), rel=1e-14)


@pytest.mark.parametrize("form", ["exact", "linear"])
def test_energy_conserved_between_impacts(form):
    model = RockingModel(alpha=0.15, p=2.2, form=form)
    h = simulate_free(model, 0.12, t_end=3.0)
    t1 = h.impacts.t.iloc[0]
    assert _energy_drift(model, h, h.t < t1) < 1e-9


def test_energy_conserved_with_e_one():
    model = RockingModel(alpha=0.15, p=2.2, impact=impact.Constant(1.0))
    h = simulate_free(model, 0.12, t_end=12.0)
    assert len(h.impacts) >= 5
    assert _energy_drift(model, h, np.isfinite(h.theta)) < 1e-9


def test_a_viscous_loss_dissipates():
    model = RockingModel(alpha=0.15, p=2.2, impact=impact.Constant(1.0), zeta=0.02)
    h = simulate_free(model, 0.12, t_end=6.0)
    side = np.where(h.theta > 0, 1, -1)
    e = model.energy(h.theta, h.thetadot, side)
    assert np.all(np.diff(e) <= 1e-12) and e[-1] < 0.9 * e[0]


@pytest.mark.parametrize("r", [0.3, 0.7, 0.95])
def test_housner_quarter_period(r):
    """Linear form: p T_1/4 = arccosh(1/(1 - theta0/alpha)) (Housner 1963)."""
    alpha, p = 0.1, 2.0
    h = simulate_free(RockingModel(alpha=alpha, p=p, form="linear"), r * alpha, t_end=5.0)
    assert p * h.impacts.t.iloc[0] == pytest.approx(np.arccosh(1.0 / (1.0 - r)), rel=1e-9)


def test_exact_and_linear_converge_for_small_alpha():
    errs = []
    for alpha in (0.2, 0.1, 0.05):
        t = [
            simulate_free(RockingModel(alpha=alpha, p=2.0, form=f), 0.8 * alpha, t_end=4.0).impacts.t.iloc[0]
            for f in ("exact", "linear")
        ]
        errs.append(abs(t[0] - t[1]) / t[1])
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 1e-3
    # second order in alpha: halving alpha divides the difference by about 4
    assert 3.0 < errs[1] / errs[2] < 5.0


def test_eq11_and_eq10_recover_e():
    alpha = 0.1
    e = restitution.two_sided(alpha)
    h = simulate_free(RockingModel(alpha=alpha, p=2.5), 0.9 * alpha, t_end=20.0)
    peaks = h.impacts.theta_peak_before.to_numpy()
    n = np.arange(1, 6)
    np.testing.assert_allclose(restitution.experimental_pena(peaks[n], peaks[0], alpha, n), e, rtol=1e-7)
    hl = simulate_free(RockingModel(alpha=alpha, p=2.5, form="linear"), 0.9 * alpha, t_end=20.0)
    pl = hl.impacts.theta_peak_before.to_numpy()
    np.testing.assert_allclose(restitution.experimental_housner(pl[n], pl[0], alpha, n), e, rtol=1e-7)


def test_one_sided_rebound_is_eq14_and_gap_limit():
    alpha = 0.1
    e1s = restitution.one_sided(alpha)
    h0 = simulate_free(RockingModel(alpha=alpha, p=2.5, boundary="one-sided"), 0.8 * alpha, t_end=3.0)
    first = h0.impacts.iloc[0]
    assert first.thetadot_after / first.thetadot_before == pytest.approx(e1s, rel=1e-12)
    assert np.nanmin(h0.theta) >= 0.0
    for gap in (1e-4, 1e-6):
        hg = simulate_free(RockingModel(alpha=alpha, p=2.5, boundary="one-sided", gap=gap), 0.8 * alpha, t_end=3.0)
        kinds = list(hg.impacts.kind.iloc[:3])
        assert kinds == ["base", "transverse", "base"]
        net = hg.impacts.thetadot_after.iloc[2] / hg.impacts.thetadot_before.iloc[0]
        assert net == pytest.approx(e1s, rel=50 * gap / alpha)
        assert np.nanmin(hg.theta) >= -gap * (1 + 1e-9)


def test_zero_law_stops_at_first_impact():
    h = simulate_free(RockingModel(alpha=0.1, p=2.0, impact=impact.Zero()), 0.05, t_end=3.0)
    assert len(h.impacts) == 1 and h.t_rest == pytest.approx(h.impacts.t.iloc[0])
    assert np.all(h.theta[h.t > h.t_rest] == 0.0)


def test_rest_without_chattering():
    """Zeno sequence cut at the rest threshold: finitely many impacts."""
    h = simulate_free(RockingModel(alpha=0.1, p=3.0, impact=impact.Constant(0.6)), 0.08, t_end=10.0)
    assert h.t_rest is not None and 5 < len(h.impacts) < 60
    assert abs(h.impacts.thetadot_after.iloc[-2]) >= 1e-3 * wall.overturning_velocity(0.1, 3.0)


def test_impacts_separated_by_their_excursion():
    """After an impact the wall needs at least 2|thetadot+| / max|thetaddot| to
    come back to the edge; a root search that returned the segment's start
    once logged 29 base impacts at one instant (Pac164 x1.25, D x0.70)."""
    from rocklab.seismic.accelerograms import load_record
    from rocklab.seismic.walls import named_model

    tr = load_record("Pac164")
    model = named_model("2s-housner")  # the linearised Fig. 21 wall
    ag = 1.25 * tr.data
    h = simulate_ground(model, ag, 0.70 * tr.stats.delta, t_end=3.0)
    base = h.impacts[h.impacts.kind == "base"]
    # |thetaddot| near the edge is at most p^2 (alpha + |ag|/g), exact or linear
    bound = model.p**2 * (model.alpha + np.abs(ag).max() / wall.G)
    gaps = np.diff(base.t.to_numpy())
    assert len(base) > 20 and np.all(gaps >= 2.0 * np.abs(base.thetadot_after.to_numpy()[:-1]) / bound)


def test_a_record_without_its_apexes_is_the_same_motion():
    """apexes=False drops the search of each flight's apex (the impacts' peaks NaN), nothing of the motion."""
    m = RockingModel(alpha=0.2, p=2.0, mu=0.002, impact=impact.HousnerTwoSided())
    located, record = (simulate_free(m, 0.15, t_end=3.0, rtol=1e-9, atol=1e-12, apexes=x) for x in (True, False))
    assert np.array_equal(located.theta, record.theta, equal_nan=True)
    assert np.array_equal(located.impacts.t, record.impacts.t)
    assert located.impacts.theta_peak_before.notna().all() and record.impacts.theta_peak_before.isna().all()


@pytest.mark.parametrize("ratio", [0.97, 0.99, 1.0, 1.01])
def test_a_release_the_dry_friction_holds_stays_there(ratio):
    """Released from rest where sin(alpha - |theta0|) <= mu, the wall is held: no impact, at rest from
    the release, in the reference integrator and in the compiled engine alike (the reference chattered
    there for ever); just outside that zone both rock with the same impacts."""
    from rocklab.simulation.batch import free_batch

    alpha, mu = 0.1, 0.03 * 0.1
    m = RockingModel(alpha=alpha, p=2.0, mu=mu, impact=impact.HousnerTwoSided())
    assert np.sin(alpha * (1.0 - ratio)) <= mu < np.sin(0.04 * alpha)
    held = simulate_free(m, ratio * alpha, t_end=3.0)
    assert held.t_rest == 0.0 and held.impacts.empty and np.all(held.theta == ratio * alpha)
    assert int(free_batch(m, ratio * alpha, t_end=3.0).n_impacts[0]) == 0
    rocks = simulate_free(m, 0.96 * alpha, t_end=3.0)
    assert len(rocks.impacts) == int(free_batch(m, 0.96 * alpha, t_end=3.0).n_impacts[0]) > 0


def test_free_overturning():
    model = RockingModel(alpha=0.1, p=2.0)
    assert simulate_free(model, 0.101, t_end=10.0).overturned
    assert not simulate_free(model, 0.099, t_end=10.0).overturned


def test_onset_at_interpolated_threshold():
    """Rocking starts when -ag crosses g tan(alpha), linearly interpolated."""
    alpha, dt = 0.1, 0.1
    thr = wall.G * np.tan(alpha)
    ag = -np.linspace(0.0, 2.0 * thr, 11)  # crosses -thr at t = 0.5 s
    h = simulate_ground(RockingModel(alpha=alpha, p=2.0), ag, dt, fs=1000.0)
    moving = h.t[np.abs(h.theta) > 0]
    assert moving[0] == pytest.approx(0.5, abs=1.1e-3) and np.all(h.theta[h.t > 0.5 + 1e-9] > 0)
    # same sign: positive ag pushes theta negative
    h2 = simulate_ground(RockingModel(alpha=alpha, p=2.0), -ag, dt, fs=1000.0)
    assert np.nanmin(h2.theta) < 0 <= -np.nanmax(h2.theta) + 1e-15
    # one-sided walls never start inwards
    h3 = simulate_ground(RockingModel(alpha=alpha, p=2.0, boundary="one-sided"), -ag, dt, fs=1000.0)
    assert np.all(h3.theta == 0.0)


def test_pulse_overturns_and_xarray():
    alpha, p = 0.1, 2.0
    dt = 0.01
    t = np.arange(0, 2.0, dt)
    pulse = -3.0 * wall.G * np.tan(alpha) * np.sin(np.pi * t / 1.0) * (t < 1.0)
    h = simulate_ground(RockingModel(alpha=alpha, p=p), pulse, dt)
    assert h.overturned and h.t_overturn > 0
    small = simulate_ground(RockingModel(alpha=alpha, p=p), 0.5 * pulse, dt)
    assert not small.overturned
    ds = small.to_xarray()
    assert ds.theta.attrs["units"] == "rad" and ds.time.attrs["units"] == "s"
    assert ds.attrs["overturned"] == 0 and ds.sizes["time"] == len(small.t)


def test_from_wall_uses_wall_constants():
    m = RockingModel.from_wall(1.63, 0.113, boundary="one-sided")
    assert m.alpha == pytest.approx(np.arctan(0.113 / 1.63))
    assert m.p == pytest.approx(wall.frequency_parameter(wall.half_diagonal(1.63, 0.113)))
    assert isinstance(m.base_law, impact.OneSided)
