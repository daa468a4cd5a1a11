"""The restitution of an asymmetric planar rigid body (rocklab.physics.restitution.two_sided_asymmetric)
against a direct impulse calculation and against Eq. 1 in the symmetric limit."""

import numpy as np
import pytest

from rocklab.physics import impact, restitution


def _impulse(b_leave, b_land, h, k, m=2.7):
    """thetadot^+ / thetadot^- and T^+ / T^- of a planar body from its impulse equations, solved as a linear system.

    The body turns at thetadot^- = 1 about the edge it leaves, at (0, 0), its
    centre of mass at (-b_leave, h) and the edge it lands on at
    (-b_leave - b_land, 0).  Unknowns: the velocity of the centre of mass
    after the impact (u, v), thetadot^+ and the impulse (Px, Py) at the new
    edge.  Equations: linear momentum (2), angular momentum about the centre
    of mass (1), the new edge at rest after the impact (2, a plastic contact).
    """
    g = np.array([-b_leave, h])
    o_new = np.array([-b_leave - b_land, 0.0])
    w0 = 1.0
    v0 = w0 * np.array([-g[1], g[0]])  # omega x r about the old edge
    r = o_new - g  # new edge relative to the centre of mass
    # rows: m u - Px = m v0x; m v - Py = m v0y; I w - (r_x Py - r_y Px) = I w0;
    #       u - w r_y = 0; v + w r_x = 0
    inertia = m * k**2
    a = np.array(
        [
            [m, 0, 0, -1, 0],
            [0, m, 0, 0, -1],
            [0, 0, inertia, r[1], -r[0]],
            [1, 0, -r[1], 0, 0],
            [0, 1, r[0], 0, 0],
        ],
        float,
    )
    rhs = np.array([m * v0[0], m * v0[1], inertia * w0, 0.0, 0.0])
    u, v, w = np.linalg.solve(a, rhs)[:3]
    before = 0.5 * m * (v0 @ v0) + 0.5 * inertia * w0**2
    after = 0.5 * m * (u**2 + v**2) + 0.5 * inertia * w**2
    return w / w0, after / before


def _impulse_e(b_leave, b_land, h, k, m=2.7):
    return _impulse(b_leave, b_land, h, k, m)[0]


@pytest.mark.parametrize("b1, b2, h, k", [(0.02, 0.05, 0.3, 0.12), (0.05, 0.02, 0.3, 0.12), (0.1, 0.1, 0.5, 0.2)])
def test_the_kinetic_energy_kept_is_that_of_the_impulse_and_the_same_both_ways(b1, b2, h, k):
    """T+/T- from the impulse solution's velocities (translation and rotation); the two directions
    keep the same share though their e differ (docs/shake-table.md, issue 40 item 7)."""
    kept = restitution.energy_ratio_asymmetric(b1, b2, h, k)
    assert kept == pytest.approx(_impulse(b1, b2, h, k)[1], rel=1e-12)
    assert kept == pytest.approx(restitution.energy_ratio_asymmetric(b2, b1, h, k), rel=1e-14)
    assert 0.0 < kept < 1.0
    if b1 == b2:
        assert kept == pytest.approx(restitution.two_sided_asymmetric(b1, b2, h, k) ** 2, rel=1e-14)
    else:
        assert restitution.two_sided_asymmetric(b1, b2, h, k) != pytest.approx(
            restitution.two_sided_asymmetric(b2, b1, h, k), rel=1e-3
        )


@pytest.mark.parametrize("seed", range(5))
def test_asymmetric_e_is_the_impulse_calculation(seed):
    rng = np.random.default_rng(seed)
    b1, b2 = rng.uniform(0.01, 0.4, 2)
    h, k = rng.uniform(0.1, 1.0), rng.uniform(0.05, 0.5)
    assert restitution.two_sided_asymmetric(b1, b2, h, k) == pytest.approx(_impulse_e(b1, b2, h, k), rel=1e-12)


def test_symmetric_limit_is_eq_1():
    alpha = np.linspace(0.02, 0.6, 12)
    r, ratio = 0.8, 0.75  # a homogeneous rectangle: m R^2 / I_O = 3/4
    k = r * np.sqrt(1 / ratio - 1)  # I_O = m (k^2 + R^2)
    e = restitution.two_sided_asymmetric(r * np.sin(alpha), r * np.sin(alpha), r * np.cos(alpha), k)
    np.testing.assert_allclose(e, restitution.two_sided(alpha, ratio), rtol=1e-12)
    np.testing.assert_allclose(e, restitution.two_sided(alpha), rtol=1e-12)


def test_the_side_that_dissipates_is_the_far_edge_landed_on():
    """SP1's 3 mm footprint (geometry.json): 0.675 leaving +x (landing 208 mm out), 0.850 leaving -x (issue 25)."""
    m, h, bp, bm = 324.648, 0.294256, 0.0766569, 0.208044
    k = np.sqrt(47.0792 / m - (h**2 + bp**2))  # I_G from I_O of the +x edge
    assert restitution.two_sided_asymmetric(bp, bm, h, k) == pytest.approx(0.675, abs=1e-3)
    assert restitution.two_sided_asymmetric(bm, bp, h, k) == pytest.approx(0.850, abs=1e-3)
    # the product over a cycle (one impact each way) is not the symmetric e of either edge squared
    cycle = restitution.two_sided_asymmetric(bp, bm, h, k) * restitution.two_sided_asymmetric(bm, bp, h, k)
    assert cycle == pytest.approx(0.574, abs=1e-3)


def test_the_simulators_law_of_an_asymmetric_body_is_that_function_and_eq_1_when_symmetric():
    law = impact.AsymmetricBody(0.08, 0.2, 0.3, 0.22)
    e = law.flat(0.3)[:, 0]  # rows: leaving +1, leaving -1
    assert e[0] == restitution.two_sided_asymmetric(0.08, 0.2, 0.3, 0.22)
    assert e[1] == restitution.two_sided_asymmetric(0.2, 0.08, 0.3, 0.22)
    assert law.coefficient(-1.0, -1, 0.3, 4.0) == pytest.approx(e[1])
    r, alpha = np.hypot(0.1, 0.3), np.arctan2(0.1, 0.3)
    sym = impact.AsymmetricBody(0.1, 0.1, 0.3, 0.22).flat(alpha)[:, 0]
    housner = impact.HousnerTwoSided(r**2 / (0.22**2 + r**2)).flat(alpha)[:, 0]
    np.testing.assert_allclose(sym, housner, rtol=1e-12)
