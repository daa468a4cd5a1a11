"""Closed forms of one flight (rocklab.physics.flight) against the simulators and Housner's closed form."""

from __future__ import annotations

import numpy as np
import pytest

from rocklab.physics.flight import apex, quarter_period, quarter_period_linear, transit_time
from rocklab.simulation.model import RockingModel
from rocklab.simulation.reference import simulate_free

ALPHA, P = 0.15, 3.2


def housner(r):
    """Housner's (1963) p T_1/4 = arccosh(1 / (1 - theta0/alpha)) from rest, small alpha."""
    return np.arccosh(1.0 / (1.0 - np.asarray(r, float)))


def test_quarter_period_and_gap_transit_exact():
    h = simulate_free(RockingModel(alpha=ALPHA, p=P), 0.9 * ALPHA, 0.0, t_end=2.0, fs=400)
    assert quarter_period(0.9 * ALPHA, ALPHA, P) == pytest.approx(h.impacts.t.iloc[0], rel=1e-6)
    assert P * quarter_period(0.9 * 0.01, 0.01, P) == pytest.approx(housner(0.9), rel=1e-4)
    # turning inside the gap: twice the time to the turning point
    v = 0.05
    d = apex(0.5 * v**2, ALPHA, P)
    assert transit_time(v, d, ALPHA, P) == pytest.approx(quarter_period(d, ALPHA, P), rel=1e-4)


def test_quarter_period_linear_against_housner_and_the_linear_simulator():
    r = np.array([0.5, 0.9, 0.999])
    assert np.allclose(quarter_period_linear(r), housner(r), rtol=1e-12)
    # released with a speed towards the vertical: the linear simulator's first impact
    alpha, w = 0.1, 0.05
    h = simulate_free(RockingModel(alpha=alpha, p=P, form="linear"), 0.99 * alpha, thetadot0=-w * P * alpha, t_end=5.0)
    assert quarter_period_linear(0.99, w) == pytest.approx(P * h.impacts.t.iloc[0], rel=1e-6)
    assert quarter_period_linear(0.99, w) < quarter_period_linear(0.99)
    assert np.isnan(quarter_period_linear(1.2))
