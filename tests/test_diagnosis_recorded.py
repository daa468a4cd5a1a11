"""rocklab.diagnosis.recorded: virtual series through the lab's files and the workflow's reduction."""

import numpy as np

from rocklab.diagnosis.evidence import measured_test
from rocklab.diagnosis.recorded import recorded_series
from rocklab.physics import impact as I

#: A wall at rest within the record (a residual out-of-plumb otherwise rejects the test).
WALL = {"impact": I.Scaled(I.HousnerTwoSided(), 0.9)}


def test_each_instruments_series_reaches_the_diagnosis_with_its_impacts():
    for instrument, fs in (("rotation", 200.0), ("inertial", 1000.0), ("transducers", 400.0)):
        recs, rejected = recorded_series("s", "1a", "two-sided", WALL, instrument=instrument, n=2, fs=fs, t_end=30.0)
        assert rejected == [] and [r["test_id"] for r in recs] == ["s-0", "s-1"]
        assert {r["instrument"] for r in recs} == {instrument} and {r["fs"] for r in recs} == {fs}
        # the motion the workflow stores, not one extracted again
        assert all(r["motion"] is not None and measured_test(r).n_impacts >= 5 for r in recs)
        assert all(np.isclose(r["theta"].max(), r["alpha"] * 0.97, rtol=0.05) for r in recs)


def test_a_test_the_campaign_refuses_is_reported_not_lost():
    recs, rejected = recorded_series("a[b]", "1a", "two-sided", {"impact": I.HousnerTwoSided()}, n=1, t_end=10.0)
    assert recs == [] and rejected == ["a[b]-0: refused by the campaign: its id"]
