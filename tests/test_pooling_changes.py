"""Changes within a series reach the pool and the pages (issue 42, item 4).

A series whose parameter changes over its tests (a rocking edge crushed
part-way) has no one value of it: its estimate is a mean over the wall
states it went through. The boundary condition's pool counts it, its
standard error widened by the spread of its states, and says so; the
diagnosis' page, its docs summary and the docs' table name the change,
where and by how much. Hand-built series, as in tests/test_pooling_curse.py.
"""

import numpy as np
import pytest
from test_pooling_curse import CAUSE, NAME, named, pooled, series

from rocklab import diagnosis as D
from rocklab.diagnosis.diagnosis_summary import diagnosis_summary
from rocklab.diagnosis.pooling import state_spread
from rocklab.diagnosis.result import CampaignDiagnosis, ChangeKind, ChangingSeries, SeriesChange
from rocklab.report.tables import series_changes

WALLS = {k: k.upper() for k in "abcd"}


def step(before, after, where=5, n_tests=8):
    """A change point of zeta after test ``where`` of ``n_tests``, as changes_over_tests gives one."""
    d = after - before
    return SeriesChange(
        parameter=NAME,
        effect=CAUSE,
        kind=ChangeKind.CHANGE_POINT,
        n_tests=n_tests,
        where_index=where,
        where_test=f"T{where}",
        before=before,
        after=after,
        ci95_before=[before - 0.001, before + 0.001],
        ci95_after=[after - 0.001, after + 0.001],
        size=d,
        ci95_size=[d - 0.002, d + 0.002],
        p_change_point=0.001,
        p_gradual=0.01,
        level=0.005,
        n_permutations=399,
    )


def steady(zeta, n_tests=8):
    """A parameter tested and found not to change."""
    return SeriesChange(parameter=NAME, effect=CAUSE, kind=ChangeKind.NONE, n_tests=n_tests, level=0.005)


def walls(change=None):
    """Three walls at zeta 0.006 that agree within their errors, and a fourth at 0.0075 (its mean over
    a crushed and an intact state where ``change`` is given)."""
    out = [series(k, [named(0.006 + 1e-5 * i, half=0.0006)]) for i, k in enumerate("abc")]
    out.append(series("d", [named(0.0075, half=0.0006)]))
    for e in out:
        e.changes = [steady(e.findings[0].params[NAME])]
    if change is not None:
        out[3].changes = [change]
        out[3].findings[0].changes_within = [NAME]
    return out


def test_the_spread_of_a_series_states_is_that_of_its_tests_values():
    # a step of 0.004 after 5 of 8 tests: the tests' values are 5 before, 3 after
    c = step(0.006, 0.010, where=5, n_tests=8)
    states = np.array([0.006] * 5 + [0.010] * 3)
    assert state_spread(c) == pytest.approx(states.std())
    # a gradual change from the first of ten tests to the last, the tests evenly placed
    g = SeriesChange(
        parameter=NAME, effect=CAUSE, kind=ChangeKind.GRADUAL, n_tests=10, before=0.1, after=0.0, size=-0.1
    )
    assert state_spread(g) == pytest.approx(np.linspace(0.1, 0.0, 10).std())
    assert state_spread(steady(0.006)) == 0.0


def test_a_series_that_changes_is_counted_with_the_spread_of_its_states_and_listed():
    """The fourth wall's value is a mean over its states: it counts, but weighs less than as one state."""
    as_one_state = pooled(walls(), WALLS)
    c = step(0.005, 0.0115, where=5)
    f = pooled(walls(c), WALLS)
    # counted, not left out, and not at the null value
    assert not f.left_out and f.n_series == 4
    assert f.changes_within == [
        ChangingSeries(
            series="d",
            parameter=NAME,
            kind=ChangeKind.CHANGE_POINT,
            where_test="T5",
            before=0.005,
            after=0.0115,
            u_states=pytest.approx(state_spread(c)),
        )
    ]
    # its weight falls with the spread of its states: the pool moves toward the steady walls
    assert 0.006 < f.params[NAME] < as_one_state.params[NAME] - 1e-4
    # its departure from them is its change's, not the walls' scatter (its intact state, 0.005, is theirs):
    # the variance between walls falls, and the interval with it, still holding the steady walls' value
    assert np.diff(f.ci95[NAME])[0] < np.diff(as_one_state.ci95[NAME])[0]
    assert f.ci95[NAME][0] < 0.006 < f.ci95[NAME][1]
    assert "changing over their tests: series d (zeta 0.005 to 0.0115 from test T5 on" in f.evidence["pooled"]


def test_the_pool_moves_continuously_with_the_size_of_the_change():
    """A change too small to matter costs nothing: the pool is that of one state, where a series left out
    at the test's threshold would jump from full weight to none."""
    as_one_state = pooled(walls(), WALLS)
    tiny = pooled(walls(step(0.0075, 0.0075 + 1e-9)), WALLS)
    assert tiny.params[NAME] == pytest.approx(as_one_state.params[NAME], rel=1e-6)
    assert tiny.ci95[NAME] == pytest.approx(as_one_state.ci95[NAME], rel=1e-6)
    assert tiny.changes_within[0].u_states < 1e-9


def test_a_change_travels_through_the_file_typed(tmp_path):
    entries = walls(step(0.005, 0.0115))
    b = D.diagnose_boundary(entries, "one-sided", walls=WALLS)
    # the file is checked against its schema on the way out and in
    CampaignDiagnosis([*entries, b]).to_json(tmp_path / "d.json")
    back = CampaignDiagnosis.from_json(tmp_path / "d.json")
    moving = back.boundaries[0].findings[0].changes_within
    assert moving[0].kind is ChangeKind.CHANGE_POINT and moving[0].series == "d"
    assert back.series[3].changed[0].kind is ChangeKind.CHANGE_POINT


def test_the_pages_name_the_change_where_and_how_much():
    entries = walls(step(0.005, 0.0115))
    b = D.diagnose_boundary(entries, "one-sided", walls=WALLS)
    d = CampaignDiagnosis([*entries, b])
    md = D.diagnosis_markdown(d)
    assert "4 series tested for a change of their parameters over their tests (4 parameters): 1 shows one." in md
    assert "- series d, flight_damping: zeta changes from test T5 on, 0.005 to 0.0115" in md
    # beside the law, which stays named
    assert "Changes over the tests: flight_damping: zeta changes from test T5 on" in md
    assert "flight_damping, counted though changing over their tests: series d (zeta 0.005 to 0.0115" in md
    summary = diagnosis_summary(d)
    (row,) = summary["changes"]["changed"]
    assert (summary["changes"]["n_series"], summary["changes"]["n_parameters"]) == (4, 4)
    assert (row["series"], row["kind"], row["where_test"]) == ("d", "change point", "T5")
    assert row["size"] == pytest.approx(0.0065) and row["u_states"] == pytest.approx(state_spread(step(0.005, 0.0115)))
    table = series_changes({"diagnosis": summary})
    assert "| d | `flight_damping` | zeta | change point at test T5 | 0.005 → 0.0115 |" in table
    assert "counted, standard error widened by" in table


def test_a_campaign_of_one_wall_state_says_none():
    entries = walls()
    b = D.diagnose_boundary(entries, "one-sided", walls=WALLS)
    d = CampaignDiagnosis([*entries, b])
    assert "(4 parameters): none shows one." in D.diagnosis_markdown(d)
    assert not b.findings[0].changes_within and "changing" not in b.findings[0].evidence["pooled"]
    summary = diagnosis_summary(d)
    assert summary["changes"] == {"n_series": 4, "n_parameters": 4, "changed": []}
    assert series_changes({"diagnosis": summary}) == "None."
    # a summary written before the series were tested did not measure them
    del summary["changes"]
    assert series_changes({"diagnosis": summary}) == "not measured."
