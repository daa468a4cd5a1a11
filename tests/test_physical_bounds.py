"""No fitted law creates energy, one convention beyond the fitted speeds (issue 24, item 5).

Every cause of the catalogue, at every corner of its bounds, through the
diagnosis' one-step model: no take-off faster than the landing, no apex
above the lossless one; the simulator's laws against the engines' flat form;
the law of the impact speed continued past its last knot as Eq. 17 is.
"""

import itertools
from types import SimpleNamespace

import numpy as np
import pytest

from rocklab.diagnosis import catalogue
from rocklab.diagnosis.extended import model_params
from rocklab.diagnosis.wall_model import impact_speeds, simulator
from rocklab.physics import impact as I
from rocklab.physics import law, restitution
from rocklab.physics.flight import apex_after
from rocklab.physics.wall import overturning_velocity
from rocklab.simulation import engine
from rocklab.simulation.batch import free_batch
from rocklab.simulation.rocking_model import RockingModel

ALPHA, P = 0.12, 3.4


def _tests(boundary):
    return [SimpleNamespace(alpha=ALPHA, p=P, boundary=boundary, order=o, log={}) for o in (0.0, 1.0)]


def _corners(cause):
    """Every parameter at its lower or upper bound (all combinations, at most 16)."""
    bounds = [(q.lower, q.upper) for q in cause.params]
    for combo in itertools.islice(itertools.product(*bounds), 16):
        yield dict(zip((q.name for q in cause.params), combo))


@pytest.mark.parametrize("boundary", ["two-sided", "one-sided"])
def test_no_cause_at_its_bounds_makes_an_impact_or_a_flight_create_energy(boundary):
    tests = _tests(boundary)
    v = np.linspace(0.0, 2.0, 41)[None, :] * overturning_velocity(ALPHA, P)
    v = np.repeat(v, len(tests), axis=0)
    side = np.ones_like(v)
    for cause in catalogue.for_boundary(boundary, families=True):
        for values in _corners(cause):
            mp = model_params(tests, (cause.name,), values)
            v_out = impact_speeds(v, side, mp, timed=False)[0]
            assert np.all(v_out <= v * (1 + 1e-12)), (cause.name, values)
            assert np.all(v_out >= 0.0), (cause.name, values)
            a = mp.hinge(side)
            lossless = apex_after(v_out, a, mp.p[:, None], k=mp.rounding[:, None])
            lossy = apex_after(v_out, a, mp.p[:, None], **mp.flight_keywords(v_out))
            assert np.all(lossy <= lossless * (1 + 1e-9) + 1e-15), (cause.name, values)


def test_a_scale_beyond_one_over_e_is_bounded_alike_in_every_form():
    v = np.linspace(0.1, 2.0, 7)
    e_an = float(restitution.two_sided(ALPHA))
    for c in (0.9, 1.5 / e_an):
        scaled = I.Scaled(I.HousnerTwoSided(), c)
        e = scaled.coefficient(v, 1, ALPHA, P)
        e0, a, b = scaled.flat(ALPHA)[0]
        np.testing.assert_allclose(e, e0 * I.amplitude_factor(e0, a, b, v, ALPHA, P))
        np.testing.assert_allclose(e, min(c * e_an, 1.0))


def _engine_against_reference(model, speeds):
    """Largest |e_engine - e_reference| over the impact rows of ``model`` at landings ``speeds`` [thetadot_r]."""
    rows, prm = model.numba_law(), model.numba_params()
    laws = ((model.base_law, 1), (model.base_law, -1), (model.transverse_law, -1))
    worst = 0.0
    for row, (impact_law, side) in enumerate(laws):
        v = speeds * model.thetadot_r
        ref = np.broadcast_to(impact_law.coefficient(v, side, model.alpha, model.p), v.shape)
        eng = np.array([engine._coefficient(rows, row, x, prm) for x in v])
        assert np.all(np.abs(eng) <= 1.0), (row, eng)
        worst = max(worst, float(np.max(np.abs(eng - ref))))
    return worst


@pytest.mark.parametrize("boundary", ["two-sided", "one-sided"])
def test_the_engine_gives_every_cause_at_its_bounds_the_reference_s_e(boundary):
    """Issue 40, item 7: every cause the engine can simulate, at every corner of its bounds (a
    restitution scale up to 2 included), has in the numba engine the e of the reference's law at
    every landing speed, within 1e-12: the engine never lets a scale past 1/|e| create energy."""
    tests = _tests(boundary)[:1]
    speeds = np.linspace(0.0, 2.0, 41)
    checked = 0
    for cause in catalogue.for_boundary(boundary, families=True):
        for values in _corners(cause):
            try:
                model = simulator(model_params(tests, (cause.name,), values).row(0))
                model.numba_params(), model.numba_law()
            except NotImplementedError:
                continue  # a law the engine has no form of is refused, not mis-simulated
            assert _engine_against_reference(model, speeds) < 1e-12, (cause.name, values)
            checked += 1
    assert checked >= 15


@pytest.mark.parametrize(
    "law",
    [
        I.Scaled(I.HousnerTwoSided(), 1.2),
        I.AmplitudeLaw(I.Scaled(I.HousnerTwoSided(), 1.2), 1.0, 0.1),
        I.Sided(I.Scaled(I.HousnerTwoSided(), 1.2), I.Scaled(I.HousnerTwoSided(), 0.8)),
        I.Constant(1.3),
        I.Sticking(I.Scaled(I.OneSided(), 2.0), 0.1),
    ],
    ids=["scaled", "amplitude-of-scaled", "sided", "constant", "sticking"],
)
def test_a_law_past_one_over_e_is_bounded_in_the_engine_as_in_the_reference(law):
    """The review's case: 1.2 e_an,2s at alpha 0.2 is e = 1 in the reference, not 1.129; a free
    rocking history then keeps its speed through every impact, never gains it."""
    boundary = "one-sided" if isinstance(law, I.Sticking) else "two-sided"
    model = RockingModel(alpha=0.2, p=P, form="linear", boundary=boundary, impact=law)
    assert _engine_against_reference(model, np.linspace(0.0, 2.0, 41)) < 1e-12
    ds = free_batch(model, 0.5 * model.alpha, t_end=5.0, max_impacts=4)
    ratio = np.abs(ds.thetadot_after[0] / ds.thetadot_before[0]).values
    assert np.all(ratio[np.isfinite(ratio)] <= 1.0 + 1e-12)


def test_a_per_history_e_scale_is_bounded_as_a_scaled_law():
    model = RockingModel(alpha=0.2, p=P, form="linear")
    ds = free_batch(model, 0.5 * model.alpha, e_scale=[1.2, 0.9], t_end=5.0, max_impacts=2)
    ratio = (ds.thetadot_after / ds.thetadot_before).values[:, 0]
    np.testing.assert_allclose(ratio, [1.0, 0.9 * restitution.two_sided(0.2)], rtol=1e-12)


def test_eq_17_is_continued_past_the_fitted_speeds_to_a_stop_never_a_pass_through():
    law17 = I.AmplitudeLaw(I.OneSided())
    a, b = restitution.AMPLITUDE_LAW_ONE_SIDED
    x_stop = np.sqrt(a / b)  # where the parabola reaches e = 0, past every free-rocking impact
    vr = overturning_velocity(ALPHA, P)
    e = law17.coefficient(np.array([0.5, 1.0, 0.99 * x_stop, 1.01 * x_stop, 3.0]) * vr, 1, ALPHA, P)
    assert x_stop > 1.0 and np.all(e[:3] < 0) and np.all(e[3:] == 0.0)


def test_the_law_of_the_impact_speed_continues_its_last_segment():
    g = np.array([0.7, 0.9, 1.0, 1.05])
    x = np.array([0.0, 0.2, 0.5, 1.0, 1.3, 2.0])
    y = law.hats(x) @ g
    np.testing.assert_allclose(y[:4], np.interp(x[:4], law.KNOTS, g))
    slope = (g[3] - g[2]) / (law.KNOTS[3] - law.KNOTS[2])
    np.testing.assert_allclose(y[4:], g[3] + slope * (x[4:] - 1.0))
    # a partition of unity: a constant law stays constant at every speed
    np.testing.assert_allclose(law.hats(x).sum(axis=-1), 1.0)


def test_the_loss_of_housner_s_e_keeps_e_within_zero_and_one():
    e_an = np.array([0.9, -0.6])
    assert np.all(np.abs(law.HousnerLoss(0.0, -0.2).restitution(e_an)) == 1.0)
    np.testing.assert_allclose(law.HousnerLoss(3.0, 0.2).restitution(e_an), [0.5, 0.0])
    np.testing.assert_allclose(law.HousnerLoss(0.5, 0.01).restitution(e_an), [0.94, -0.79])
