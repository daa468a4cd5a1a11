"""Closed forms of one flight (rocklab.physics.flight) against the simulators and Housner's closed form."""

from __future__ import annotations

import numpy as np
import pytest

from rocklab.physics.flight import apex, excursion_time, quarter_period, quarter_period_linear, transit_time
from rocklab.simulation.reference import simulate_free
from rocklab.simulation.rocking_model import RockingModel

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


def test_an_excursion_is_its_way_in_and_its_way_out_and_nan_stays_nan():
    """The compiled quadrature: the excursion's time the sum of its two transits (each the
    array form's: Gauss-Legendre on 24 nodes), a turning point twice the transit to it, a stack's
    padding (NaN) NaN, no depth no time, the shapes broadcast."""
    u = np.array([[0.002, 0.0, np.nan], [0.004, 0.001, 0.003]])
    v_in, v_out = np.array([[0.3, 0.2, 0.1], [0.25, np.nan, 0.2]]), np.array([[0.2, 0.1, 0.05], [0.2, 0.1, 0.15]])
    a, p = np.array([[ALPHA], [0.1]]), np.array([[P], [2.0]])
    t = excursion_time(v_in, v_out, u, a, p)
    assert t.shape == (2, 3)
    assert np.array_equal(t, transit_time(v_in, u, a, p) + transit_time(v_out, u, a, p), equal_nan=True)
    assert np.isnan(t[0, 2]) and np.isnan(t[1, 1]) and t[0, 1] == 0.0
    # to its turning point and back at the same speed: twice the quarter period of its flight
    v = 0.05
    d = apex(0.5 * v**2, ALPHA, P)
    assert excursion_time(v, v, d, ALPHA, P) == pytest.approx(2.0 * quarter_period(d, ALPHA, P), rel=1e-4)


def test_quarter_period_linear_against_housner_and_the_linear_simulator():
    r = np.array([0.5, 0.9, 0.999])
    assert np.allclose(quarter_period_linear(r), housner(r), rtol=1e-12)
    # released with a speed towards the vertical: the linear simulator's first impact
    alpha, w = 0.1, 0.05
    h = simulate_free(RockingModel(alpha=alpha, p=P, form="linear"), 0.99 * alpha, thetadot0=-w * P * alpha, t_end=5.0)
    assert quarter_period_linear(0.99, w) == pytest.approx(P * h.impacts.t.iloc[0], rel=1e-6)
    assert quarter_period_linear(0.99, w) < quarter_period_linear(0.99)
    assert np.isnan(quarter_period_linear(1.2))


@pytest.mark.parametrize("c", [0.0, 1e-9, -3.0, 25.0])
@pytest.mark.parametrize("A", [1e-6, 0.02, 0.149])
def test_the_work_of_the_losses_is_its_integral(A, c):
    from scipy.integrate import quad

    from rocklab.physics.flight import _exponential_moments

    sin_m, cos_m, one = _exponential_moments(A, ALPHA, c)
    for got, f in [
        (sin_m, lambda s: np.sin(ALPHA - s) * np.exp(c * s)),
        (cos_m, lambda s: np.cos(ALPHA - s) * np.exp(c * s)),
        (one, lambda s: np.exp(c * s)),
    ]:
        assert got == pytest.approx(quad(f, 0.0, A, epsabs=0.0, epsrel=1e-13)[0], rel=1e-11)


def test_the_apex_after_losses_is_that_of_each_flight_alone_and_nan_stays_nan():
    from rocklab.physics.flight import apex_after, takeoff_speed

    A = np.array([[0.01, 0.05, np.nan], [0.1, 0.0, np.nan]]) * np.ones((2, 3))
    a, p = np.array([[ALPHA], [0.9 * ALPHA]]), np.array([[P], [1.1 * P]])
    loss = {"zeta": 0.02, "mu": 0.01 * ALPHA, "kappa": 0.5 / ALPHA, "k": 0.2}
    v = takeoff_speed(A, a, p, **loss)
    stacked = apex_after(v, a, p, **loss)
    alone = np.array([[apex_after(v[i, j], a[i, 0], p[i, 0], **loss) for j in range(3)] for i in range(2)])
    np.testing.assert_array_equal(np.isnan(stacked), np.isnan(A))
    np.testing.assert_allclose(stacked, alone, rtol=1e-12, atol=0.0)
    # the balance solved: the apex each take-off speed was made for
    np.testing.assert_allclose(stacked[np.isfinite(A)], A[np.isfinite(A)], rtol=1e-9, atol=1e-15)


def test_flat_is_broadcast_arrays_raveled_bit_for_bit():
    """The closed forms' broadcast (flight._flat): numpy's broadcast_arrays then ravel, the same
    shape and bits, each flat array contiguous, whatever the inputs' shapes, strides and kinds."""
    from rocklab.physics.flight import _flat

    full = np.arange(12.0).reshape(3, 4) / 7.0
    for xs in (
        (full, full[:, :1], 2.0),
        (full[:, ::2], np.array([[np.nan], [-0.0], [1.0]]), np.float64(3.0)),
        (0.5, 1, np.array(2.0)),
        (full.T, full[:, 0], [1.0, 2.0, 3.0]),
    ):
        shape, flat = _flat(*xs)
        ref = np.broadcast_arrays(*(np.asarray(x, float) for x in xs))
        assert shape == ref[0].shape
        for x, y in zip(flat, ref):
            assert x.flags.c_contiguous and x.dtype == np.float64
            assert x.tobytes() == y.ravel().tobytes()
