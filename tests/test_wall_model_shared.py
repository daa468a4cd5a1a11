"""The wall model's short cuts give the long way's numbers, bit for bit (issue 44).

What the walls alone give (:meth:`ModelParams.of_walls`) is made once a base and shared with
the models its laws make, never stale for a model of other walls; an impact through a gap is the
same impact whether or not every impact of the stack is one; ``timed=False`` is the timed
take-off speed.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from rocklab.diagnosis.wall_model import base_params, impact_speeds, model_of, stacked
from rocklab.physics import restitution
from rocklab.physics.law import Amplitude, Gap, Restitution
from rocklab.physics.wall import overturning_velocity
from rocklab.seismic.calibrated import MapWall

LAWS = (Restitution(0.9, asymmetry=0.2), Amplitude(1.1, 0.3), Gap(0.4))


def walls(*boundaries):
    return [MapWall(0.12 + 0.03 * i, 2.0 + 0.5 * i, b) for i, b in enumerate(boundaries)]


def bits(x):
    x = np.asarray(x, float)
    return x.shape, x.tobytes()


def test_what_the_walls_give_is_made_once_a_base_and_follows_alpha_and_p():
    base = base_params(walls("one-sided", "two-sided"))
    made = base.of_walls()
    assert model_of([], LAWS, base).of_walls()["v_r"] is made["v_r"]
    assert bits(made["v_r"]) == bits(overturning_velocity(base.alpha, base.p))
    assert bits(made["e_2s"]) == bits(restitution.two_sided(base.alpha))
    assert bits(made["e_tr"]) == bits(restitution.transverse(base.alpha))
    # a model of other walls makes its own, and leaves the base's right
    other = replace(base, alpha=2.0 * base.alpha)
    assert bits(other.of_walls()["v_r"]) == bits(overturning_velocity(2.0 * base.alpha, base.p))
    assert bits(base.of_walls()["v_r"]) == bits(overturning_velocity(base.alpha, base.p))
    two = stacked([base, base])
    assert bits(two.of_walls()["v_r"]) == bits(np.tile(made["v_r"], 2))
    assert two.of_walls() is not base.of_walls() and base.row(1).of_walls() is not base.of_walls()
    assert base.row(1).of_walls()["v_r"] == pytest.approx(made["v_r"][1], rel=1e-15)


def test_an_impact_through_the_gap_is_the_same_in_a_stack_of_them_alone():
    """A one-sided wall's row of a stack with a two-sided wall (some impacts through the gap) against
    the stack of that wall alone (every impact through it): the same five arrays, bit for bit."""
    tests = walls("two-sided", "one-sided")
    mixed, alone = model_of(tests, LAWS), model_of(tests[1:], LAWS)
    v = np.array([[0.05, 0.2, 0.4, np.nan], [0.03, 0.1, 0.3, np.nan]])
    side = np.ones_like(v)
    both, one = impact_speeds(v, side, mixed), impact_speeds(v[1:], side[1:], alone)
    assert alone.gap_model.all() and not mixed.gap_model.all()
    for x, y in zip(both, one):
        assert bits(x[1:]) == bits(y)
    assert np.all(one[2][:, :3] > 0)


def test_untimed_impacts_give_the_timed_take_off_speed():
    for boundaries in (("one-sided", "one-sided"), ("two-sided", "one-sided"), ("two-sided",)):
        mp = model_of(walls(*boundaries), LAWS)
        v = np.linspace(0.01, 0.5, 4 * len(boundaries)).reshape(len(boundaries), 4)
        side = np.where(np.arange(4) % 2, -1.0, 1.0) + 0 * v
        timed, untimed = impact_speeds(v, side, mp), impact_speeds(v, side, mp, timed=False)
        assert bits(untimed[0]) == bits(timed[0])
        assert all(bits(x) == bits(np.zeros(v.shape)) for x in untimed[1:])
