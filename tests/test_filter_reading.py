"""How the derivative filter reads a flight with losses (rocklab.diagnosis.flight_filter.filter_reading).

The independent check is the chain itself: exact simulations of walls with a
dry friction, a viscous loss or drag, their rotation read by
:func:`rocklab.lab.motion.extract_motion`, each flight's measured duration
and speeds against the simulator's.  The first-order model must give the
chain's error flight by flight, where the model of a constant share of the
window it replaces missed by a third on a stocky wall's short flights.
"""

import numpy as np
import pytest

from rocklab.diagnosis.flight_filter import LOSSES, filter_reading
from rocklab.lab.motion import extract_motion
from rocklab.physics import impact as I
from rocklab.simulation.reference import simulate_free
from rocklab.simulation.rocking_model import RockingModel

WALLS = {"stocky": (0.492, 0.123), "paper": (1.1, 0.12)}
#: What the chain misreads of a lossless flight (sampling, interpolation of the instants) [-].
LOSSLESS = 2e-3


def chain_and_model(h, b, boundary, loss, fs=400.0):
    """Per flight: measured / true - 1 of its duration, take-off and landing speed, and the model's."""
    kw = dict(loss)
    if boundary == "two-sided":
        kw["impact"] = I.Scaled(I.HousnerTwoSided(), 0.95)
    m = RockingModel.from_wall(h, b, boundary=boundary, **kw)
    hist = simulate_free(m, 0.9 * m.alpha, 0.0, t_end=20.0, fs=fs)
    theta = np.nan_to_num(hist.theta) + 1e-7 * np.random.default_rng(0).standard_normal(hist.theta.size)
    imp = extract_motion(hist.t, theta, fs, boundary, m.p).impacts
    true = hist.impacts[hist.impacts["kind"] == "base"]
    t, va, vb = true["t"].to_numpy(), true["thetadot_after"].abs().to_numpy(), true["thetadot_before"].abs().to_numpy()
    rows = []
    for k in range(min(len(imp), len(true), 9) - 1):
        T = t[k + 1] - t[k]
        r = filter_reading(T, 0.5 * (va[k] + vb[k + 1]), m.p, fs) @ np.array([loss.get(n, 0.0) for n in LOSSES])
        measured = (
            (imp.t_s.iloc[k + 1] - imp.t_after_s.iloc[k]) / T - 1.0,
            abs(imp.thetadot_after.iloc[k]) / va[k] - 1.0,
            abs(imp.thetadot_before.iloc[k + 1]) / vb[k + 1] - 1.0,
        )
        rows.append((*measured, r[0] / T, r[1], r[2]))
    return np.array(rows)


@pytest.mark.parametrize("wall", WALLS)
@pytest.mark.parametrize("loss", [{"mu": 0.0049}, {"zeta": 0.02}, {"kappa": 0.5}], ids=str)
def test_the_filter_reads_a_lossy_flight_as_the_first_order_model_says(wall, loss):
    rows = chain_and_model(*WALLS[wall], "two-sided", loss)
    assert len(rows) >= 6
    measured, model = rows[:, :3], rows[:, 3:]
    # the losses' share, flight by flight, to a fifth of the effect beside what the chain misreads without them
    np.testing.assert_array_less(np.abs(measured - model), 0.2 * np.abs(model) + LOSSLESS)
    # and they are what the chain reads: the largest well beyond that misreading
    assert np.abs(model).max() > 2 * LOSSLESS


def test_dry_friction_lengthens_the_short_flights_of_a_stocky_wall():
    """The case that misnamed a dry friction as a lower angle: short flights read about 0.9 % long."""
    rows = chain_and_model(*WALLS["stocky"], "one-sided", {"mu": 0.0049}, fs=200.0)
    assert rows[0, 0] == pytest.approx(rows[0, 3], abs=2e-3) and 0.006 < rows[0, 3] < 0.012


def test_limits_of_the_reading():
    p, fs, v = 3.7, 400.0, 0.1
    # a long flight: dry friction is a constant moment in each half, which the fitted curve holds
    long = filter_reading(1.5, v, p, fs)[:, LOSSES.index("mu")]
    short = filter_reading(0.15, v, p, fs)[:, LOSSES.index("mu")]
    assert np.all(np.abs(long) < 1e-3 * np.abs(short).max())
    # the fall from the release has no apex in its window: no friction read, no take-off
    fall = filter_reading(0.4, v, p, fs, from_rest=True)
    assert np.all(fall[:2] == 0.0) and abs(fall[2, LOSSES.index("mu")]) < 1e-3 * np.abs(short).max()
    # a viscous loss reads the take-off low and the landing high, the flight long
    z = filter_reading(0.3, v, p, fs)[:, LOSSES.index("zeta")]
    assert z[0] > 0 and z[1] < 0 < z[2]


def test_the_figure_curve_of_a_rotation_record_reads_with_its_own_fits():
    """A loss curve drawn where no flight was measured (the figures) takes the record's fits, not the transducers'."""
    from rocklab.diagnosis.causes import flight_damping
    from rocklab.lab.motion import instrument_fits
    from rocklab.physics.flight import takeoff_speed

    alpha, p, fs = 0.1, 3.7, 240.0
    A = np.linspace(0.1, 0.9, 5) * alpha
    v = takeoff_speed(A, alpha, p)
    default = flight_damping.filter_reading(A, alpha, p, v, zeta=0.01, fs=fs)
    film = flight_damping.filter_reading(A, alpha, p, v, zeta=0.01, fs=fs, fits=instrument_fits("rotation", fs))
    assert flight_damping.filter_reading(A, alpha, p, v, zeta=0.01, fs=fs, fits=instrument_fits("transducers", fs)) == (
        pytest.approx(default)
    )
    # the rotation record's wider windows read a viscous loss otherwise
    assert np.all(np.isfinite(film)) and np.max(np.abs(film - default)) > 1e-3 * np.max(np.abs(default))
