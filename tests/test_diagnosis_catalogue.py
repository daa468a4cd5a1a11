"""The catalogue is the one list of causes: a toy cause added there alone is found.

The toy is the worked example of docs/diagnosis-method.md: a speed lost at
every impact, v^+ = e v^- - d thetadot_r (a friction-like loss, which no
cause of the catalogue has: it grows as the impact speed falls).  It is
declared here as its module would be and registered with one line, the
catalogue's list; a virtual-lab campaign hides it and the diagnosis must
name it.
"""

from dataclasses import replace

import numpy as np
import pytest
from test_diagnosis import virtual_series

from rocklab import diagnosis as D
from rocklab.diagnosis import catalogue
from rocklab.diagnosis.causes import Cause
from rocklab.diagnosis.model import impact_speeds, per_test
from rocklab.diagnosis.parameters import Param
from rocklab.physics import impact as I
from rocklab.physics import restitution, wall

D_LOSS = Param("d", 0.0, 0.2, 0.0, practical=5e-4)


def _lose_speed(v_out, v, side, mp):
    vr = wall.overturning_velocity(per_test(mp.alpha, side), per_test(mp.p, side))
    return np.maximum(v_out - per_test(mp.extra["d"], side) * vr, 0.0)


def _apply(mp, v):
    return replace(
        mp, extra={**mp.extra, "d": v["d"] * np.ones_like(mp.alpha)}, impact_hooks=(*mp.impact_hooks, _lose_speed)
    )


SPEED_LOSS = Cause(name="speed_loss", law="v+ = e v- - d thetadot_r", params=(D_LOSS,), apply=_apply)


def speed_loss(d):
    """The simulator's impact: Housner's e less a speed d thetadot_r."""

    def e(thetadot, side, alpha, p):
        vr = wall.overturning_velocity(alpha, p)
        return max(restitution.two_sided(alpha) - d * vr / abs(thetadot), 0.0)

    return {"impact": I.Custom(e)}


@pytest.fixture
def with_toy(monkeypatch):
    # the one line of the worked example: the cause in the catalogue's list
    monkeypatch.setattr(catalogue, "CAUSES", [*catalogue.CAUSES, SPEED_LOSS])


def test_the_model_takes_the_toy_from_the_catalogue(with_toy):
    recs = virtual_series("toy", "two-sided", speed_loss(0.01), n=1)
    ts = D.measured_test(recs[0])
    v = np.array([0.5, 0.1]) * wall.overturning_velocity(ts.alpha, ts.p)
    base = D.model_params([ts])
    toy = D.model_params([ts], ("speed_loss",), {"d": 0.01})
    side = np.ones((1, 2))
    np.testing.assert_allclose(
        impact_speeds(v[None, :], side, toy)[0],
        impact_speeds(v[None, :], side, base)[0] - 0.01 * wall.overturning_velocity(ts.alpha, ts.p),
    )


@pytest.fixture(scope="module")
def hidden_loss():
    return virtual_series("toy", "two-sided", speed_loss(0.005), seed=3)


def test_without_the_toy_the_loss_is_left_unexplained(hidden_loss):
    e = D.diagnose_series(hidden_loss, key="toy", n_boot=10, n_history=0)
    assert "speed_loss" not in e["verdict"] and e["unexplained"]


def test_a_toy_cause_added_to_the_catalogue_is_named(with_toy, hidden_loss):
    d = 0.005
    e = D.diagnose_series(hidden_loss, key="toy", n_boot=10, n_history=0)
    assert e["verdict"] == ["speed_loss"] and not e["unexplained"], (e["verdict"], e["rejected"])
    f = next(f for f in e["findings"] if f["effect"] == "speed_loss")
    lo, hi = f["ci95"]["d"]
    assert lo - 0.1 * d <= d <= hi + 0.1 * d, (f["params"], (lo, hi))
    assert f["gain"]["deviance_per_obs"] > 0
