"""The catalogue is the one list of causes: a toy cause added there alone is carried everywhere.

The toy is the worked example of docs/diagnosis-method.md: a chipped hinge,
whose impacts lose a fraction l of their e on leaving hinge +1,
e_+ = (1 - l) e_an, e_- = e_an.  It is declared here as its module would be,
its physics as a law of :mod:`rocklab.physics.law` (a restitution of scale
sqrt(1 - l) and asymmetry ln(1 - l)), and registered with one line, the
catalogue's list.  With no other edit the diagnosis names it in a
virtual-lab series that hides it, the exact simulator and the numba engine
carry it, and the maps of a calibrated wall switch it on and off by its
short name.
"""

import math

import numpy as np
import pytest
from test_diagnosis import virtual_series

from rocklab import diagnosis as D
from rocklab.diagnosis import catalogue
from rocklab.diagnosis.causes import Cause
from rocklab.diagnosis.parameters import Param
from rocklab.physics import impact as I
from rocklab.physics import restitution
from rocklab.physics.law import Restitution
from rocklab.seismic import calibrated
from rocklab.seismic.calibrated import MapWall
from rocklab.seismic.maps import overturning_map

L = Param("chip", 0.0, 0.5, 0.0, practical=0.002)


def _laws(v):
    return (Restitution(math.sqrt(1.0 - v["chip"]), math.log(1.0 - v["chip"])),)


CHIPPED = Cause(
    name="chipped_hinge",
    law="e_+ = (1 - l) e_an on leaving hinge +1",
    params=(L,),
    laws=_laws,
    boundaries=("two-sided",),
    short="chip",
)


@pytest.fixture
def with_toy(monkeypatch):
    # the one line of the worked example: the cause in the catalogue's list
    monkeypatch.setattr(catalogue, "CAUSES", [*catalogue.CAUSES, CHIPPED])


def chipped(loss):
    """The virtual lab's wall: Housner's e, less a fraction ``loss`` on leaving hinge +1."""
    return {"impact": I.Sided(I.Scaled(I.HousnerTwoSided(), 1.0 - loss), I.HousnerTwoSided())}


def test_the_toy_acts_before_the_causes_estimated_after_selection(with_toy):
    order = [c.name for c in catalogue.in_order()]
    assert order.index("chipped_hinge") < order.index("stop_threshold") == len(order) - 1


def test_the_simulator_and_the_engine_carry_the_toy(with_toy):
    wall = MapWall(0.2, 2.0, "two-sided")
    model = D.rocking_model(wall, ("chipped_hinge",), {"chip": 0.1})
    e_an = restitution.two_sided(0.2)
    assert model.base_law.coefficient(1.0, 1, 0.2, 2.0) == pytest.approx(0.9 * e_an, rel=1e-12)
    assert model.base_law.coefficient(1.0, -1, 0.2, 2.0) == pytest.approx(e_an, rel=1e-12)
    np.testing.assert_allclose(model.numba_law()[:2, 0], [0.9 * e_an, e_an], rtol=1e-12)
    # the diagnosis' closed forms: the take-off speed of an impact leaving each hinge
    mp = D.model_params([wall], ("chipped_hinge",), {"chip": 0.1})
    v = np.ones((1, 2))
    out = D.wall_model.impact_speeds(v, np.array([[1.0, -1.0]]), mp)[0]
    np.testing.assert_allclose(out[0], [0.9 * e_an, e_an], rtol=1e-12)


def test_the_maps_carry_the_toy_and_switch_it_off_by_its_short_name(with_toy):
    entry = {
        "scope": "boundary",
        "boundary": "two-sided",
        "verdict": ["chipped_hinge"],
        "findings": [{"effect": "chipped_hinge", "params": {"chip": 0.1}}],
    }
    assert calibrated.model_names([entry]) == ["2s-calibrated", "2s-calibrated-no-chip"]
    full = calibrated.calibrated_model([entry], "2s-calibrated", 0.1, 1.0)
    assert full.numba_law()[0, 0] == pytest.approx(0.9 * restitution.two_sided(0.1), rel=1e-12)
    t = np.arange(0.0, 2.0, 0.01)
    ag = np.where(t < 0.5, 3.0 * np.sin(2 * np.pi * t), 0.0)
    m = overturning_map(ag, 0.01, "2s-calibrated", n=3, diagnosis=[entry], tail=2.0)
    assert m.overturned.size == 9 and m.attrs["impact_e0"] == pytest.approx(0.9 * restitution.two_sided(0.1))
    assert "chipped_hinge (chip = 0.1)" in m.attrs["model_description"]


@pytest.fixture(scope="module")
def hidden_chip():
    return virtual_series("toy", "two-sided", chipped(0.05), seed=3, pull=True)


def test_without_the_toy_the_listed_causes_need_two_parameters(hidden_chip):
    e = D.diagnose_series(hidden_chip, key="toy", n_boot=10, n_history=0)
    assert e.verdict == ["restitution_scale", "hinge_asymmetry"], e.verdict


def test_a_toy_cause_added_to_the_catalogue_is_named(with_toy, hidden_chip):
    e = D.diagnose_series(hidden_chip, key="toy", n_boot=10, n_history=0)
    assert e.verdict == ["chipped_hinge"], (e.verdict, e.rejected)
    f = e.findings[0]
    lo, hi = f.ci95["chip"]
    assert lo - 1e-4 <= 0.05 <= hi + 1e-4, (f.params, (lo, hi))
    assert f.gain["deviance_per_obs"] > 0


@pytest.mark.parametrize("cause", catalogue.in_order(("temperature",)), ids=lambda c: c.name)
def test_a_cause_at_its_null_values_leaves_the_base_model(cause):
    walls = [MapWall(0.2, 2.0, b, order) for b, order in (("two-sided", 0.0), ("one-sided", 1.0))]
    base = D.wall_model.base_params(walls)
    null = D.wall_model.model_of(walls, cause.laws(cause.values({})))
    for name, value in vars(base).items():
        if isinstance(value, np.ndarray) and name not in ("gap_model", "e0"):
            np.testing.assert_allclose(getattr(null, name), value, rtol=1e-15, atol=0, err_msg=name)
    # a gap of zero swings through nothing: Eq. 2 twice and the transverse impact are Eq. 14
    v = np.full((2, 1), 1.0)
    np.testing.assert_allclose(
        D.wall_model.impact_speeds(v, np.ones((2, 1)), null)[0], D.wall_model.impact_speeds(v, np.ones((2, 1)), base)[0]
    )


def test_the_model_takes_only_the_laws_of_physics_law():
    with pytest.raises(TypeError, match="no law of rocklab.physics.law"):
        D.wall_model.base_params([MapWall(0.2, 2.0, "two-sided")]).under(I.Scaled(I.HousnerTwoSided(), 0.9))
