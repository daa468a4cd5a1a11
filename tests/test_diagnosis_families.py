"""The generalised families of the diagnosis (issue 12): their physics' one home and what feeds them.

An instability angle that depends on the amplitude, the flight of apex A
on a(A) = alpha_r (1 - k) + k A (:func:`rocklab.physics.flight.flight_angle`):
each closed form against an independent computation (a root search, the
event-driven simulator), and the refusals where it has no meaning.  The
test log's columns, which a drift may follow, from tests.csv to the
diagnosis.  The diagnosis' scenarios are in tests/test_diagnosis.py.
"""

import numpy as np
import pytest
from scipy.optimize import brentq

from rocklab.diagnosis import extended as dx
from rocklab.physics import flight, restitution
from rocklab.physics import impact as I
from rocklab.simulation.reference import simulate_free, simulate_ground
from rocklab.simulation.rocking_model import RockingModel

A_S, P = 0.08, 3.3


@pytest.mark.parametrize("k", [0.4, -0.3])
def test_the_apex_solves_the_energy_balance_on_its_own_angle(k):
    v = np.array([0.02, 0.1, 0.18, 0.3])
    A = flight.apex_after(v, A_S, P, 0.0, k=k)
    for vi, Ai in zip(v, A):
        E = 0.5 * vi**2
        if E >= flight.potential(A_S, A_S, P):
            assert Ai == A_S  # it overturns, as on the rigid hinge
            continue
        root = brentq(lambda x, E=E: flight.potential(x, flight.flight_angle(x, A_S, k), P) - E, 0.0, A_S, xtol=1e-15)
        assert Ai == pytest.approx(root, rel=1e-10)
    # back down the same flight: the landing speed is the take-off speed
    np.testing.assert_allclose(flight.landing_speed(A[:3], A_S, P, 0.0, k=k), v[:3], rtol=1e-10)
    # released at the instability angle the flight rocks on it; k = 0 is the rigid hinge
    assert flight.flight_angle(A_S, A_S, k) == A_S
    assert flight.flight_angle(0.0, A_S, k) == pytest.approx(A_S * (1 - k))
    assert flight.apex_after(0.1, A_S, P, 0.0, k=0.0) == flight.apex(0.005, A_S, P)


@pytest.mark.parametrize("k", [0.3, -0.3])
def test_the_simulator_and_the_free_run_share_the_flights(k):
    """The exact simulator's impacts against the diagnosis' flight-by-flight free run."""
    model = RockingModel(
        alpha=A_S / 0.9, p=P, impact=I.Scaled(I.HousnerTwoSided(), 0.95), alpha_rock=A_S, hinge_rounding=k
    )
    h = simulate_free(model, 0.85 * A_S, 0.0, t_end=4.0, fs=400)
    imp = h.impacts
    t, peaks, v_after = imp.t.to_numpy(), imp.theta_peak_before.to_numpy(), np.abs(imp.thetadot_after.to_numpy())
    assert len(t) >= 3
    A = flight.apex_after(v_after[:-1], A_S, P, 0.0, k=k)
    np.testing.assert_allclose(A, peaks[1:], rtol=1e-9)
    T = 2 * flight.quarter_period(A, flight.flight_angle(A, A_S, k), P)
    np.testing.assert_allclose(T, np.diff(t), rtol=1e-8)
    # the fall from the release rocks on the angle of the release rotation
    a0 = flight.flight_angle(0.85 * A_S, A_S, k)
    assert t[0] == pytest.approx(flight.quarter_period(0.85 * A_S, a0, P), rel=1e-8)
    # the diagnosis' model of it builds the same simulator model
    ext, values = ("instability_amplitude",), {"alpha_r_over_alpha": 0.9, "rounding": k}
    mp = dx.model_params([_wall()], ext, values).row(0)
    assert mp.flight(0.5 * A_S, 1) == pytest.approx(flight.flight_angle(0.5 * A_S, A_S, k))
    sim = dx.rocking_model(_wall(), ext, values)
    assert sim.alpha_pos == pytest.approx(A_S) and sim.hinge_rounding == k


def _wall():
    from rocklab.seismic.calibrated import MapWall

    return MapWall(A_S / 0.9, P, "two-sided")


def test_ground_motion_refuses_it_and_the_maps_carry_its_constant_member(caplog):
    model = RockingModel(alpha=0.1, p=P, hinge_rounding=0.2)
    with pytest.raises(ValueError, match="under ground motion"):
        simulate_ground(model, np.zeros(10), 0.01)
    with pytest.raises(NotImplementedError, match="depends on the amplitude"):
        model.numba_params()
    with pytest.raises(ValueError, match="hinge_rounding must be"):
        RockingModel(alpha=0.1, p=P, hinge_rounding=1.0)
    from rocklab.seismic.calibrated import calibrated_model, model_names

    diagnosis = [
        {
            "scope": "boundary",
            "boundary": "two-sided",
            "verdict": ["instability_amplitude", "restitution_speed", "restitution_scale"],
            "findings": [
                {"effect": "instability_amplitude", "params": {"alpha_r_over_alpha": 0.9, "rounding": 0.2}},
                {"effect": "restitution_speed", "params": {f"g{j}": 0.9 for j in range(4)}},
                {"effect": "restitution_scale", "params": {"c": 0.95}},
            ],
        }
    ]
    # the maps' wall: the angle of the flights that overturn it, the flexible law left off, each said in the log
    with caplog.at_level("WARNING", logger="rocklab.seismic.calibrated"):
        assert model_names(diagnosis) == ["2s-calibrated", "2s-calibrated-no-alpha", "2s-calibrated-no-escale"]
    assert "instability_amplitude is carried on the maps' wall by instability_angle" in caplog.text
    assert "restitution_speed is left off the maps' wall" in caplog.text
    model = calibrated_model(diagnosis, "2s-calibrated", 0.1, 1.0)
    assert model.alpha_pos == pytest.approx(0.09) and model.hinge_rounding == 0.0
    assert model.numba_law()[0, 0] == pytest.approx(0.95 * restitution.two_sided(0.1))


def test_the_test_log_reaches_the_diagnosis(tmp_path):
    """Columns of tests.csv beyond the lab's own reach the diagnosis as numbers (a date in days), each
    test's place in the series' range: what a drift may follow (tests/test_diagnosis.py hides one)."""
    from rocklab.diagnosis.evidence import in_series_order, measured_test, records_by_series
    from rocklab.lab import virtual_lab as vl
    from rocklab.lab import virtual_record as vr
    from rocklab.lab.campaign import open_campaign
    from rocklab.lab.reduction import reduce_test

    logs = [
        {"date": "2024-03-01T10:00", "temperature_C": "21.5", "operator": "AB"},
        {"date": "2024-03-03T10:00", "temperature_C": "19.0", "operator": "CD"},
        {"date": "2024-03-02T22:00", "temperature_C": "", "operator": "AB"},
    ]
    plan = [vl.VirtualTest(f"T{i}", "1a", effects=vr.Effects.off(), log=log) for i, log in enumerate(logs)]
    vl.write_campaign(tmp_path, plan, t_end=3.0)
    campaign = open_campaign(tmp_path)
    datasets = [reduce_test(campaign, f"T{i}") for i in range(3)]
    assert datasets[0].attrs["log_temperature_C"] == 21.5 and "log_operator" not in datasets[0].attrs
    assert "log_temperature_C" not in datasets[2].attrs  # empty: left out
    assert datasets[1].attrs["log_date"] - datasets[0].attrs["log_date"] == pytest.approx(2.0)
    (records,) = records_by_series(datasets).values()
    tests = in_series_order([measured_test(r) for r in records])
    # only what every test has is a column; each test's place in its range
    assert [t.log for t in tests] == [{"date": 0.0}, {"date": 1.0}, {"date": pytest.approx(1.5 / 2)}]


def test_a_law_of_the_impact_speed_on_three_tests_is_not_read_as_eq17():
    """Three tests leave no structure in the residuals of Eq. 17 (bench/discovery.py, design 1, cell 121)
    where the information criterion is decisive: the family in its listed member's place opens the search."""
    from rocklab import diagnosis as D
    from rocklab.lab import virtual_lab as vl
    from rocklab.physics.law import KNOTS

    knots = 0.9 + 0.1 * KNOTS
    model = {"impact": I.SpeedLaw(I.HousnerTwoSided(), knots)}
    wall = vl.DEFAULT_SPECIMENS.set_index("specimen").loc["1a"]
    records = vl.series_records("speed", wall, "two-sided", model, n=3, fs=400.0, seed=121, t_end=400.0)
    entry = D.diagnose_records(records, "speed", n_boot=40, n_history=0, seed=0)
    assert entry.verdict == ["restitution_speed"]
    assert entry.listed_verdict == ["restitution_amplitude"]
    (finding,) = entry.findings
    for j, g in enumerate(knots):
        lo, hi = finding.ci95[f"g{j}"]
        assert lo <= g <= hi
