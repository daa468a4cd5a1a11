"""Impact laws against the closed forms of rocklab.physics.restitution (Eqs. 2, 12-14, 17)."""

import numpy as np
import pytest

from rocklab.physics import impact, restitution, wall

ALPHA, P = 0.12, 2.5


def test_housner_and_one_sided_equal_paper_coefficients():
    assert impact.HousnerTwoSided().coefficient(-0.3, 1, ALPHA, P) == pytest.approx(restitution.two_sided(ALPHA))
    assert impact.OneSided().coefficient(-0.3, 1, ALPHA, P) == pytest.approx(restitution.one_sided(ALPHA))
    assert impact.Transverse().coefficient(-0.3, -1, ALPHA, P) == pytest.approx(restitution.transverse(ALPHA))
    # Eq. 14 is a rebound, Eq. 2 a pass-through
    assert impact.OneSided().coefficient(0.1, 1, ALPHA, P) < 0 < impact.HousnerTwoSided().coefficient(0.1, 1, ALPHA, P)


def test_scaled_zero_and_sided():
    e2 = restitution.two_sided(ALPHA)
    assert impact.Scaled(impact.HousnerTwoSided(), 0.95).coefficient(1.0, 1, ALPHA, P) == pytest.approx(0.95 * e2)
    assert impact.Zero().coefficient(1.0, -1, ALPHA, P) == 0.0
    law = impact.Sided(impact.Constant(0.9), impact.Constant(0.8))
    assert law.coefficient(1.0, 1, ALPHA, P) == 0.9
    assert law.coefficient(1.0, -1, ALPHA, P) == 0.8
    np.testing.assert_allclose(law.flat(ALPHA), [[0.9, 1, 0], [0.8, 1, 0]])


def test_amplitude_law_is_eq17_and_clipped():
    vr = wall.overturning_velocity(ALPHA, P)
    law = impact.AmplitudeLaw(impact.OneSided(), 1.18, 0.473)
    ratio = 0.7
    expected = restitution.one_sided(ALPHA) * restitution.ratio_velocity_law(ratio)
    assert law.coefficient(-ratio * vr, 1, ALPHA, P) == pytest.approx(expected)
    # very fast impacts: the bracket is clipped at 0, the sign never flips
    assert law.coefficient(10 * vr, 1, ALPHA, P) == 0.0
    # |e| never exceeds 1
    big = impact.AmplitudeLaw(impact.Constant(0.9), 2.0, 0.0)
    assert big.coefficient(0.0, 1, ALPHA, P) == pytest.approx(1.0)
    np.testing.assert_allclose(law.flat(ALPHA)[0], [restitution.one_sided(ALPHA), 1.18, 0.473])
    with pytest.raises(NotImplementedError):
        impact.AmplitudeLaw(law, 1.0, 0.1).flat(ALPHA)


def test_custom_law_has_no_flat_form():
    law = impact.Custom(lambda v, side, alpha, p: 0.5 if side > 0 else 0.6)
    assert law.coefficient(1.0, -1, ALPHA, P) == 0.6
    with pytest.raises(NotImplementedError):
        law.flat(ALPHA)


def test_sticking_law_stops_slow_landings_only():
    vr = float(wall.overturning_velocity(ALPHA, P))
    law = impact.Sticking(impact.HousnerTwoSided(), 0.1)
    e = law.coefficient(np.array([-0.099, 0.101, -0.5]) * vr, 1, ALPHA, P)
    np.testing.assert_allclose(e, [0.0, restitution.two_sided(ALPHA), restitution.two_sided(ALPHA)])
    with pytest.raises(NotImplementedError):
        law.flat(ALPHA)
