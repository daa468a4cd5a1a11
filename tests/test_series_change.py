"""Changes within a series (issue 42, item 4): a parameter that changes over the tests is named, where and by
how much, beside the law; a series of one wall state names none.

The engine (:mod:`rocklab.diagnosis.estimation.change`) on a problem with a known answer and tests that
vary as a lab's do (a level of their own: residuals correlated within a test), many series at a time; then
the diagnosis of virtual-lab series whose rocking edge is crushed part-way, wears gradually, or stays.
"""

import numpy as np
import pytest
from test_diagnosis import H, virtual_series

from rocklab.diagnosis.estimation import fit
from rocklab.diagnosis.estimation.change import LEVEL, changes_over_tests
from rocklab.diagnosis.estimation.problem import Problem
from rocklab.diagnosis.parameters import Param
from rocklab.diagnosis.result import CampaignDiagnosis, ChangeKind, SeriesChange
from rocklab.diagnosis.series import diagnose_series


class _Cause:
    def __init__(self, name, params):
        self.name, self.params, self.replaces = name, params, ()


class LevelProblem(Problem):
    """Log ratios of 15 readings per test around a level m_i: m + tau (a test's own level) + noise, m_i = m
    everywhere (null), m + jump after test ``split``, or m + slope (n - 1/2) (n from 0 to 1)."""

    def __init__(self, n_tests=10, m=0.1, tau=0.02, noise=0.01, jump=0.0, split=5, slope=0.0, seed=0):
        rng = np.random.default_rng(seed)
        place = np.arange(n_tests) / (n_tests - 1)
        self.truth = m + jump * (np.arange(n_tests) >= split) + slope * (place - 0.5)
        level = self.truth + rng.normal(0.0, tau, n_tests)
        self.y = level[:, None] + rng.normal(0.0, noise, (n_tests, 15))
        self.n_tests = n_tests
        self.causes = (_Cause("level", (Param("m", -1.0, 1.0, 0.0, 0.005),)),)

    def subset(self, idx):
        return np.asarray(idx)

    def residuals(self, sub, ext, values):
        return {"g": values.get("m", 0.0) - self.y[sub]}

    def noise(self, sub):
        return {"g": np.full(self.y[sub].shape, 0.01)}


def _changes(problem, n_permutations=199, seed=0):
    f = fit(problem, np.arange(problem.n_tests), ("level",))
    ids = [f"t{i}" for i in range(problem.n_tests)]
    return changes_over_tests(problem, {"level": f}, test_ids=ids, n_permutations=n_permutations, seed=seed)[0]


def test_a_series_of_one_state_names_no_change_at_the_level_though_its_tests_vary():
    """The per-test levels make the residuals of a test alike: the deviance drop of a split is far above its
    chi-square (the information criterion alone would name a change in most series); the permutation of
    whole tests holds the level: false alarms at most 5 % family-wise, over 100 series."""
    found = [_changes(LevelProblem(seed=s)) for s in range(100)]
    alarms = sum(c.kind is not ChangeKind.NONE for c in found)
    bic_alone = sum(min(c.dbic_change_point, c.dbic_gradual) < -10 for c in found)
    assert bic_alone > 50, bic_alone
    # 5 % of 100 series and the binomial noise of a hundred (its 95 % quantile: 9)
    assert alarms <= 9, alarms
    p = np.array([c.p_change_point for c in found])
    # the permutation p-values are uniform under the null: about half below 0.5
    assert 0.35 < np.mean(p < 0.5) < 0.65


@pytest.mark.parametrize("split", [3, 5, 7])
def test_a_planted_step_is_named_at_its_place_with_its_size(split):
    hits = []
    for seed in range(10):
        c = _changes(LevelProblem(jump=0.08, split=split, seed=seed))
        hits.append(c)
    named = [c for c in hits if c.kind is ChangeKind.CHANGE_POINT]
    assert len(named) >= 8, [c.kind for c in hits]
    for c in named:
        assert abs(c.where_index - split) <= 1 and c.where_test == f"t{c.where_index}"
    # the interval of the jump holds it, but for the odd one of 95 %
    held = [c.ci95_size[0] <= 0.08 <= c.ci95_size[1] for c in named if c.where_index == split]
    assert np.mean(held) >= 0.8, held


def test_a_planted_drift_is_named_gradual_with_its_size():
    found = [_changes(LevelProblem(slope=0.12, seed=s)) for s in range(10)]
    gradual = [c for c in found if c.kind is ChangeKind.GRADUAL]
    assert len(gradual) >= 8, [c.kind for c in found]
    assert np.mean([c.ci95_size[0] <= 0.12 <= c.ci95_size[1] for c in gradual]) >= 0.8
    assert all(c.where_index is None for c in gradual)


def test_too_few_tests_to_split_says_so():
    (c,) = [_changes(LevelProblem(n_tests=3))]
    assert c.kind is ChangeKind.NONE and "needs 4 tests" in c.note


def test_tests_too_few_to_reach_the_level_say_so_and_name_nothing():
    """Four tests have 24 orders: the rarest, an order or its reverse, is 1 in 12, above the level."""
    c = _changes(LevelProblem(n_tests=4, jump=0.2, split=2))
    assert c.kind is ChangeKind.NONE and "cannot carry a change" in c.note
    assert _changes(LevelProblem(n_tests=6)).note is None


def test_the_level_is_shared_by_every_parameter_and_both_kinds():
    c = _changes(LevelProblem(seed=1))
    assert c.level == pytest.approx(LEVEL / 2) and c.n_permutations == 199


# the diagnosis of virtual-lab series (10 tests of the slender two-sided wall)


def _rocking_edge(ratio):
    return virtual_series("s", "two-sided", {"impact": H()}, alpha_ratio=ratio, n=10, seed=0)


def _roundtrip(entry, tmp_path):
    CampaignDiagnosis([entry]).to_json(tmp_path / "d.json")
    return CampaignDiagnosis.from_json(tmp_path / "d.json").series[0]


def test_a_corner_crushed_part_way_is_named_where_and_how_much(tmp_path):
    """alpha_r/alpha 1.0 on tests 0-4, 0.9 from test 5 on: the held-out test turns the instability angle
    down (its fit predicts neither half), nothing is named; the change is, and the series is flagged."""
    entry = diagnose_series(_rocking_edge(lambda i: 1.0 if i < 5 else 0.9), key="s")
    (c,) = [c for c in entry.changes if c.parameter == "alpha_r_over_alpha"]
    assert c.kind is ChangeKind.CHANGE_POINT and abs(c.where_index - 5) <= 1
    assert c.ci95_before[0] <= 1.0 <= c.ci95_before[1] and c.ci95_after[0] <= 0.9 <= c.ci95_after[1]
    assert c.ci95_size[0] <= -0.1 <= c.ci95_size[1]
    # the verdict is no one wall state: flagged, its change in the structure left
    assert entry.unexplained and any(st.where == "instability_angle" for st in entry.residual_structure)
    assert entry.changed == [c]
    back = _roundtrip(entry, tmp_path)
    assert back.changes[0].kind is ChangeKind.CHANGE_POINT and back.changes[0].to_dict() == c.to_dict()


def test_a_rocking_edge_worn_test_after_test_is_named_gradual_and_its_law_kept():
    entry = diagnose_series(_rocking_edge(lambda i: 1.0 - 0.1 * i / 9), key="s")
    assert "instability_angle" in entry.verdict
    (c,) = [c for c in entry.changes if c.parameter == "alpha_r_over_alpha"]
    assert c.kind is ChangeKind.GRADUAL and c.ci95_size[0] <= -0.1 <= c.ci95_size[1]
    assert entry.finding("instability_angle").changes_within == ["alpha_r_over_alpha"]


def test_a_rocking_edge_that_stays_names_no_change():
    entry = diagnose_series(_rocking_edge(0.9), key="s")
    assert entry.verdict == ["instability_angle"]
    assert [c.kind for c in entry.changes] == [ChangeKind.NONE] and entry.changed == []
    assert entry.finding("instability_angle").changes_within is None


def test_a_change_reads_back_its_kind_as_the_enum():
    c = SeriesChange.from_dict({"parameter": "c", "kind": "change point"})
    assert c.kind is ChangeKind.CHANGE_POINT and c.to_dict()["kind"] == "change point"


def test_a_series_of_more_tests_than_a_float_counts_orders_of_is_tested():
    """171! overflows a float: a series of 200 tests (a large campaign's) was reported not finished."""
    c = _changes(LevelProblem(n_tests=200, jump=0.08, split=120), n_permutations=19)
    assert c.kind is ChangeKind.CHANGE_POINT and abs(c.where_index - 120) <= 2


def test_the_steps_drops_by_prefix_sums_are_those_of_the_steps_indicators():
    """Every split of every order from sums over the tests in rank order equals the closed form of each
    step's explicit 0/1 column (the indicators cost tests^2 per order)."""
    from rocklab.diagnosis.estimation.change import _drops, _step_drops

    rng = np.random.default_rng(3)
    n, k, splits = 12, 3, list(range(2, 11))
    A = rng.normal(size=(n, 15, k))
    y = rng.normal(size=(n, 15))
    AtA, Aty = np.einsum("nri,nrj->nij", A, A), np.einsum("nri,nr->ni", A, y)
    ranks = np.array([rng.permutation(n) for _ in range(7)])
    steps = (ranks[:, None, :] >= np.array(splits)[:, None]).astype(float)
    in_order = (np.arange(n) >= np.array(splits)[:, None]).astype(float)
    for j in range(k):
        np.testing.assert_allclose(_step_drops(AtA, Aty, ranks, splits, j), _drops(AtA, Aty, steps, j), rtol=1e-10)
        np.testing.assert_allclose(
            _step_drops(AtA, Aty, np.arange(n), splits, j), _drops(AtA, Aty, in_order, j), rtol=1e-10
        )
