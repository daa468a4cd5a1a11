"""A mechanism is one module: a new law in flight, declared here alone, is simulated, solved, fitted and mapped.

The toy is a moment that resists the wall only while it rises (|theta|
growing), m m g R with m [-] its ratio to the weight's moment, as mu of dry
friction, and none while it falls.  Its module is this file's first part:
its term of the equation of motion (:class:`rocklab.physics.law.FlightTerm`:
the deceleration m p^2 sign(thetadot) on the rise, its work m p^2 A over
the rise to the apex A and none over the fall), its law (a
:class:`rocklab.physics.law.Law` that sets the term on the model) and its
cause, registered with one line, the catalogue's list.  With no other
edit: the reference simulator and the numba engine integrate it alike, the
diagnosis' closed forms of a flight hold it, the diagnosis fits it on walls
simulated with it, and the maps of a calibrated wall carry it.
"""

from dataclasses import dataclass, replace

import numpy as np
import pytest

from rocklab import diagnosis as D
from rocklab.diagnosis import catalogue
from rocklab.diagnosis.causes import Cause
from rocklab.diagnosis.estimation import fit, parameter_intervals
from rocklab.diagnosis.evidence import MeasuredTest
from rocklab.diagnosis.parameters import Param
from rocklab.diagnosis.series_problem import WallProblem
from rocklab.physics import flight
from rocklab.physics.law import FlightTerm, Law
from rocklab.seismic import calibrated
from rocklab.seismic.calibrated import MapWall
from rocklab.seismic.maps import overturning_map
from rocklab.simulation.batch import free_batch, ground_batch
from rocklab.simulation.reference import simulate_free, simulate_ground

# --- the toy mechanism: its module ---------------------------------------------------------------


def _rise_deceleration(theta, thetadot, p, q, i):
    # |theta| grows where theta and thetadot share a sign, and as the wall leaves theta = 0
    if theta * thetadot >= 0.0:
        return q[i] * p * p * (1.0 if thetadot > 0.0 else (-1.0 if thetadot < 0.0 else 0.0))
    return 0.0


def _rise_work(A, a, p, rise, m):
    # a constant moment: its work m p^2 A over the rise whatever the path, none over the fall
    return p**2 * m * A if rise else 0.0 * A


def _rise_slope(A, a, p, m):
    return p**2 * m + 0.0 * A


RISE = FlightTerm("rise moment", ("m",), _rise_deceleration, smooth=False, work=_rise_work, work_slope=_rise_slope)


@dataclass(frozen=True)
class RiseMoment(Law):
    """A moment m m g R against the rise, none on the fall: m [-]."""

    m: float = 0.0

    def act_on(self, mp):
        return mp.with_term(RISE, self.m * np.ones_like(mp.alpha))


M = Param("m", 0.0, 0.05, 0.0, practical=1e-5)

RISING = Cause(
    name="rise_moment",
    law="a moment m m g R against the rise, none on the fall",
    params=(M,),
    laws=lambda v: (RiseMoment(v["m"]),),
    short="rise",
)

# --- the checks ----------------------------------------------------------------------------------

ALPHA, P, m_TRUE = 0.1, 3.4, 0.002
WALL = MapWall(ALPHA, P, "two-sided")


@pytest.fixture
def with_toy(monkeypatch):
    # the one registry line: the cause in the catalogue's list
    monkeypatch.setattr(catalogue, "CAUSES", [*catalogue.CAUSES, RISING])


def _model(m=m_TRUE):
    return D.rocking_model(WALL, ("rise_moment",), {"m": m})


def test_the_reference_and_the_engine_integrate_the_toy_alike_in_free_rocking(with_toy):
    model = _model()
    assert model.terms == ((RISE, (m_TRUE,)),)
    ref = simulate_free(model, 0.8 * ALPHA, 0.0, t_end=6.0).impacts
    n = len(ref)
    ds = free_batch(model, 0.8 * ALPHA, t_end=6.0, dt=1.0 / 400.0, substeps=8, max_impacts=n + 2)
    assert int(ds.n_impacts[0]) == n >= 6
    np.testing.assert_allclose(ds.t_impact[0, :n], ref.t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(ds.theta_peak[0, :n], ref.theta_peak_before, rtol=0, atol=1e-9)
    np.testing.assert_allclose(ds.thetadot_after[0, :n], ref.thetadot_after, rtol=0, atol=1e-9)
    # the toy matters far beyond that agreement
    bare = simulate_free(_model(0.0), 0.8 * ALPHA, 0.0, t_end=6.0).impacts
    assert np.max(np.abs(bare.theta_peak_before[1:n] - ref.theta_peak_before[1:n])) > 1e-3 * ALPHA
    # the linear form's closed form has the viscous loss alone: it refuses the toy, and says so
    with pytest.raises(NotImplementedError, match=r"viscous loss alone, not rise moment \(m = 0.002\)"):
        replace(model, form="linear").numba_params()


def _records():
    """A sine of 2 Hz, and a pulse that lifts the wall, then a level that pushes it out by less than the
    toy resists: the wall rises, turns and is held there (its rotation a constant) until the level ends."""
    t = np.arange(0.0, 4.0, 0.01)
    sine = np.where(t < 3.0, -1.3 * np.sin(2.0 * np.pi * 2.0 * t), 0.0)
    held = -np.interp(t, [0.0, 0.2, 0.25, 0.3, 1.5, 1.6], [0.0, 1.1, 1.1, 1.0, 1.0, 0.0])
    return {"sine": sine, "held": held}


@pytest.mark.parametrize("record", ["sine", "held"])
def test_the_reference_and_the_engine_integrate_the_toy_alike_under_ground_motion(with_toy, record):
    model, ag = _model(0.01), _records()[record]
    ref = simulate_ground(model, ag, 0.01, rtol=1e-12, atol=1e-14)
    n = len(ref.impacts)
    # the engine follows the wall to rest, the reference until it can no longer overturn: its impacts first
    ds = ground_batch(ag, 0.01, [model], substeps=8, max_impacts=n)
    assert int(ds.n_impacts[0]) >= n >= 10 and not ref.overturned and not bool(ds.overturned[0])
    np.testing.assert_allclose(ds.t_impact[0], ref.impacts.t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(ds.thetadot_after[0], ref.impacts.thetadot_after, rtol=0, atol=1e-9)
    if record == "held":
        still = ref.theta[(ref.t > 0.4) & (ref.t < 1.4)]
        assert np.ptp(still) == 0.0 and still[0] > 1e-5


def test_the_closed_forms_of_a_flight_hold_the_toy(with_toy):
    """Energy over a flight: 1/2 v_off^2 = P(A) + m p^2 A on the rise, 1/2 v_land^2 = P(A) on the fall."""
    h = simulate_free(_model(), 0.8 * ALPHA, 0.0, t_end=6.0)
    imp = h.impacts
    pk, vb, va = (np.abs(imp[c].to_numpy()) for c in ("theta_peak_before", "thetadot_before", "thetadot_after"))
    mp = D.model_params([WALL], ("rise_moment",), {"m": m_TRUE})
    loss = mp.row(0).flight_loss()
    np.testing.assert_allclose(flight.landing_speed(pk, ALPHA, P, **loss), vb, rtol=1e-8)
    np.testing.assert_allclose(flight.apex_after(va[:-1], ALPHA, P, **loss), pk[1:], rtol=1e-8)
    np.testing.assert_allclose(flight.takeoff_speed(pk[1:], ALPHA, P, **loss), va[:-1], rtol=1e-8)
    # the diagnosis' own step: a landing, the impact, the next flight's apex
    side = np.where(np.arange(len(vb) - 1) % 2, -1.0, 1.0)
    A, *_ = D.wall_model.next_flight(vb[None, :-1], side[None, :], mp)
    np.testing.assert_allclose(A[0], pk[1:], rtol=1e-8)


def _measured(i, theta0, m, rng):
    """The test a wall released at ``theta0`` gives, read off the reference's impacts (no filter), its apexes
    with a noise of 1e-4 of their size."""
    h = simulate_free(_model(m), theta0, 0.0, t_end=8.0, rtol=1e-12, atol=1e-14)
    imp = h.impacts.iloc[:12]
    n = len(imp) - 1
    t = imp.t.to_numpy(float)[:n]
    return MeasuredTest(
        test_id=f"T{i:04d}",
        alpha=ALPHA,
        p=P,
        boundary="two-sided",
        direction="push",
        side0=1,
        theta0=theta0,
        peaks=imp.theta_peak_before.to_numpy(float)[1:] * np.exp(1e-4 * rng.standard_normal(n)),
        v_before=np.abs(imp.thetadot_before.to_numpy(float)[:n]),
        v_after=np.abs(imp.thetadot_after.to_numpy(float)[:n]),
        t_before=t,
        t_after=t,
        depth=np.zeros(n),
        t_release=0.0,
        t_end=8.0,
        floor=1e-6,
        order=i / 4.0,
    )


def test_the_diagnosis_fits_the_toy_on_walls_simulated_with_it(with_toy):
    rng = np.random.default_rng(4)
    tests = [_measured(i, th * ALPHA, m_TRUE, rng) for i, th in enumerate((0.6, 0.7, 0.75, 0.8, 0.9))]
    problem = WallProblem(tests)
    assert "rise_moment" in problem.candidates()
    fitted = fit(problem, np.arange(len(tests)), ("rise_moment",))
    assert fitted.values["m"] == pytest.approx(m_TRUE, rel=1e-2)
    ci = parameter_intervals(problem, fitted)
    assert RISING.holds(ci, "m", m_TRUE), (fitted.values, ci)
    assert not RISING.holds(ci, "m", 0.0)


def test_the_maps_carry_the_toy(with_toy):
    entry = {
        "scope": "boundary",
        "boundary": "two-sided",
        "verdict": ["rise_moment"],
        "findings": [{"effect": "rise_moment", "params": {"m": 0.01}}],
    }
    assert calibrated.model_names([entry]) == ["2s-calibrated", "2s-calibrated-no-rise"]
    full = calibrated.calibrated_model([entry], "2s-calibrated", 0.1, 1.0, form="exact")
    assert full.terms == ((RISE, (0.01,)),)
    assert calibrated.calibrated_model([entry], "2s-calibrated-no-rise", 0.1, 1.0, form="exact").terms == ()
    t = np.arange(0.0, 2.0, 0.01)
    ag = np.where(t < 0.5, 4.0 * np.sin(2 * np.pi * t), 0.0)
    m = overturning_map(ag, 0.01, "2s-calibrated", n=3, diagnosis=[entry], form="exact", tail=2.0)
    assert m.overturned.dtype == bool and m.overturned.size == 9
    assert "rise_moment (m = 0.01)" in m.attrs["model_description"]
    with pytest.raises(NotImplementedError, match="linear form"):
        overturning_map(ag, 0.01, "2s-calibrated", n=3, diagnosis=[entry], tail=2.0)
