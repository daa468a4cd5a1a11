"""A boundary condition's parameters, pooled over its walls, hold the error the walls share.

The scatter between walls holds what varies between them; the bias of the
chain and of the model is the same for all of them and is not averaged away.
Four two-sided walls of three tests, one truth (issue 24): the walls agree
to better than the bias they share, and the pooled interval must hold the
truth all the same.
"""

from dataclasses import replace

import numpy as np
import pytest
from scipy import stats
from test_diagnosis import SPEC, H, I

from rocklab import diagnosis as D
from rocklab.diagnosis.pooling import pooled_parameter
from rocklab.lab import virtual_lab as vl

TRUTH = {"restitution_scale": {"c": 0.95}, "instability_angle": {"alpha_r_over_alpha": 0.91}}
TRUTH["flight_damping"] = {"zeta": 0.008}


@pytest.fixture(scope="module")
def four_walls():
    model = {"impact": I.Scaled(H(), 0.95), "zeta": 0.008}
    entries = []
    for i, sp in enumerate(["1a", "2a", "3b", "5c"]):
        records = vl.series_records(
            sp, SPEC.loc[sp], "two-sided", model, n=3, fs=200.0, alpha_ratio=0.91, seed=i, t_end=30.0
        )
        entries.append(D.diagnose_records(records, f"{sp}-2s", n_boot=10, n_history=0))
    return entries


def test_the_pooled_intervals_hold_what_every_series_holds(four_walls):
    walls = {e.key: e.key[:2] for e in four_walls}
    b = D.diagnose_boundary(four_walls, "two-sided", walls=walls)
    assert set(b.verdict) == set(TRUTH)
    narrow = 0
    for f in b.findings:
        for k, truth in TRUTH[f.effect].items():
            lo, hi = f.ci95[k]
            assert lo <= truth <= hi, (f.effect, k, truth, lo, hi)
            # the series agree to better than the bias they share: their scatter alone misses the truth
            mine = [next(g for g in e.findings if g.effect == f.effect) for e in four_walls]
            _, (lo, hi), *_ = pooled_parameter({e.key: g.params[k] for e, g in zip(four_walls, mine)}, walls)
            narrow += not lo <= truth <= hi
            assert f.u_systematic[k] == pytest.approx(np.mean([g.u_systematic[k] for g in mine]))
    assert narrow >= 1


def test_a_shared_systematic_uncertainty_is_not_averaged_away():
    values = {f"s{i}": 0.9 for i in range(4)}
    walls = {s: s for s in values}
    m, ci, level, n, note, u = pooled_parameter(values, walls, {s: 0.01 for s in values})
    assert (m, level, n, note, u) == (pytest.approx(0.9), "wall", 4, "", pytest.approx(0.01))
    assert ci == pytest.approx([0.9 - 1.96 * 0.01, 0.9 + 1.96 * 0.01], rel=1e-3)
    # a series at the null value carries none; the mean's share is the mean of the walls'
    _, ci, *_, u = pooled_parameter(values, walls, {"s0": 0.01, "s1": 0.01})
    assert u == pytest.approx(0.005) and ci[1] - 0.9 == pytest.approx(1.96 * 0.005, rel=1e-3)
    # two series of one wall are one wall's evidence: its uncertainty is their mean
    _, _, _, n, _, u = pooled_parameter(values, {"s0": "a", "s1": "a", "s2": "b", "s3": "c"}, {"s0": 0.02})
    assert n == 3 and u == pytest.approx(0.01 / 3)
    # the interval stays within the parameter's bounds
    _, ci, *_ = pooled_parameter(values, walls, {s: 0.1 for s in values}, bounds=(0.0, 1.0))
    assert ci[1] == 1.0


def test_without_a_systematic_part_the_interval_is_students_t():
    rng = np.random.default_rng(1)
    values = {f"s{i}": 0.9 + 0.01 * rng.standard_normal() for i in range(5)}
    x = np.array(list(values.values()))
    half = stats.t.ppf(0.975, 4) * x.std(ddof=1) / np.sqrt(5)
    _, ci, *_ = pooled_parameter(values)
    assert ci == pytest.approx([x.mean() - half, x.mean() + half])


def test_a_series_short_of_naming_a_cause_its_data_show_counts_at_its_own_estimate(four_walls):
    """A wall whose data carry a cause's signature but lack the held-out power to name it (a one-sided
    wall of eight impacts) says how large the cause is: the boundary pools it there, not at the null value
    (issue 24, item 6: pooling without selection, 'with their own estimates')."""
    walls = {e.key: e.key[:2] for e in four_walls}
    key, name = "instability_angle", "alpha_r_over_alpha"
    own = [next(f for f in e.findings if f.effect == key).params[name] for e in four_walls]

    def unnamed(e, estimates):
        return replace(
            e,
            verdict=[v for v in e.verdict if v != key],
            findings=[f for f in e.findings if f.effect != key],
            unnamed_estimates=estimates or e.unnamed_estimates,
        )

    def pooled(entries):
        b = D.diagnose_boundary(entries, "two-sided", walls=walls)
        return next(f for f in b.findings if f.effect == key)

    # without its standard error the walls weigh the same: the plain mean over them
    f = pooled([unnamed(four_walls[0], {key: {name: own[0]}}), *four_walls[1:]])
    assert f.params[name] == pytest.approx(np.mean(own))
    assert f.n_series == 3 and "1 that did not" in f.evidence["pooled"]
    # its systematic part is the namers' mean, not nothing: the chain and the model are theirs
    u = [next(g for g in e.findings if g.effect == key).u_systematic[name] for e in four_walls[1:]]
    assert f.u_systematic[name] == pytest.approx(np.mean(u))
    # without the signature's estimate the series is left out, not put at the null value (issue 41,
    # item 4: zeros for the series that cannot see a cause are the loser's curse); the three others
    # pooled with their standard errors, within their scatter of the plain mean
    f = pooled([unnamed(four_walls[0], None), *four_walls[1:]])
    assert f.params[name] == pytest.approx(np.mean(own[1:]), abs=np.ptp(own[1:]))
    assert [g.series for g in f.left_out] == [four_walls[0].key] and "left out: series" in f.evidence["pooled"]
