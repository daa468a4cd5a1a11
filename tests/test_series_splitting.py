"""Sample splitting of a long series (rocklab.diagnosis.splitting): causes chosen on some tests, estimated
on the others; below the cap, the diagnosis unsplit."""

import pytest
from test_diagnosis import H, sticking, virtual_series

from rocklab import diagnosis as D
from rocklab.diagnosis.result import CampaignDiagnosis
from rocklab.diagnosis.splitting import SPLIT_CAP, split_series
from rocklab.physics import impact as I


def test_a_series_above_the_cap_is_split_into_two_disjoint_halves_spread_over_it():
    tests = [f"t{i:03d}" for i in range(23)]
    chosen, rest = split_series(tests, 7)
    assert len(chosen) == 7 and len(rest) == 16
    assert not set(chosen) & set(rest) and sorted(chosen + rest) == tests
    # spread from the first test to the last, each half in series order, the same halves every time
    assert chosen[0] == tests[0] and chosen[-1] == tests[-1]
    assert chosen == sorted(chosen) and rest == sorted(rest)
    assert split_series(tests, 7) == (chosen, rest)


def test_a_series_at_or_below_the_cap_is_not_split():
    tests = list(range(5))
    assert split_series(tests, 5) == (tests, tests)
    assert split_series(tests, 9) == (tests, tests)
    # the longest series whose results must stay as they were: the scale bench's 614-test campaign
    assert SPLIT_CAP >= 93


@pytest.fixture(scope="module")
def lossy():
    """Eight virtual tests of a two-sided wall losing 7 % of its restitution, at 100 Hz."""
    return virtual_series("loss", "two-sided", {"impact": I.Scaled(H(), 0.93)}, n=8, seed=1, fs=100.0)


def test_below_the_cap_the_diagnosis_is_the_unsplit_one(lossy):
    unsplit = D.diagnose_series(lossy, key="loss", n_boot=10, n_history=0)
    at_cap = D.diagnose_series(lossy, key="loss", n_boot=10, n_history=0, split_cap=len(lossy))
    assert at_cap.to_dict() == unsplit.to_dict()
    assert unsplit.n_tests_selection is None and "n_tests_selection" not in unsplit.to_dict()
    assert unsplit.findings[0].n_tests == 8


def test_above_the_cap_the_causes_are_chosen_on_some_tests_and_estimated_on_the_others(lossy, tmp_path):
    unsplit = D.diagnose_series(lossy, key="loss", n_boot=10, n_history=0)
    e = D.diagnose_series(lossy, key="loss", n_boot=10, n_history=0, split_cap=4)
    assert e.n_tests == 8 and (e.n_tests_selection, e.n_tests_estimation) == (4, 4)
    assert e.verdict == unsplit.verdict == ["restitution_scale"]
    f = e.findings[0]
    # estimated on the four tests the selection left: its own estimate, its interval on them, the truth in it
    assert f.n_tests == 4 and f.params["c"] != unsplit.findings[0].params["c"]
    lo, hi = f.ci95["c"]
    assert lo <= f.params["c"] <= hi and lo <= 0.93 <= hi
    # the file says so, through its schema and back
    CampaignDiagnosis([e]).to_json(tmp_path / "d.json")
    (back,) = CampaignDiagnosis.from_json(tmp_path / "d.json").entries
    assert (back.n_tests_selection, back.n_tests_estimation) == (4, 4)


def test_a_cause_estimated_after_selection_is_estimated_on_the_tests_that_did_not_choose_the_model():
    """A wall that sticks on slow landings: the stop (a cause estimated after the selection) is looked for
    where the selection's tests leave it, and named and sized on the others."""
    recs = virtual_series("stop", "two-sided", sticking(0.15, 0.95), n=8, seed=3)
    e = D.diagnose_series(recs, key="stop", n_boot=10, n_history=0, split_cap=4)
    assert e.verdict == ["restitution_scale", "stop_threshold"] and e.n_tests_estimation == 4
    scale, stop = e.findings
    assert scale.n_tests == 4 and stop.n_tests <= 4
    lo, hi = stop.ci95["v_stop_over_vr"]
    assert lo <= 0.15 <= hi
