"""The systematic part of the parameter intervals (issue 24, item 7): the pulls of the residual groups.

Two groups of observations of one mean, the second offset by a systematic
error delta that every test shares: resampling tests cannot see it, the
pulls of the groups can (closed form: two groups alike, the fit halfway,
each pulls it by delta / 4: u_sys = delta / (2 sqrt 2)), and the interval
then holds the truth that the statistical interval misses.
"""

import numpy as np
import pytest
from scipy import stats

from rocklab.diagnosis.estimation import Problem, fit
from rocklab.diagnosis.estimation.fitting import linearised
from rocklab.diagnosis.estimation.resampling import parameter_intervals, sandwich_intervals
from rocklab.diagnosis.estimation.systematic import (
    bias_correction,
    by_group,
    simultaneous,
    standard_error,
    systematic_uncertainty,
    verdict_intervals,
    widened,
    widened_dof,
)
from rocklab.diagnosis.parameters import Param
from rocklab.diagnosis.result import Finding

TRUTH = 0.3


class _Mean:
    name = "mean"
    params = (Param("m", 0.0, 1.0, 0.0, practical=0.01),)
    replaces = ()


class TwoViews(Problem):
    """Tests that see a mean m through two groups of k observations, the second offset by ``delta``."""

    causes = (_Mean(),)

    def __init__(self, delta, n_tests=6, k=30, noise=0.01, seed=0):
        rng = np.random.default_rng(seed)
        shape = (n_tests, k)
        self.y = {
            "a": TRUTH + noise * rng.standard_normal(shape),
            "b": TRUTH + delta + noise * rng.standard_normal(shape),
        }
        self.n_tests = n_tests

    def subset(self, idx):
        return {g: y[np.asarray(idx)] for g, y in self.y.items()}

    def residuals(self, sub, ext, values):
        return {g: values.get("m", 0.0) - y for g, y in sub.items()}

    def noise(self, sub):
        return {g: np.ones_like(y) for g, y in sub.items()}


def _fitted(problem):
    return fit(problem, np.arange(problem.n_tests), ("mean",))


def _u_sys(delta, **kw):
    problem = TwoViews(delta, **kw)
    return float(systematic_uncertainty(by_group(problem, _fitted(problem))[-1])[0][0])


def test_the_linearisation_by_group_is_the_linearisation_of_all_groups():
    problem = TwoViews(0.01)
    f = _fitted(problem)
    names, x0, lo, hi, A, y, groups = by_group(problem, f)
    ref = linearised(problem, problem.subset(np.arange(problem.n_tests)), f)
    assert names == ref[0]
    for a, b in zip(A + y, ref[4] + ref[5]):
        np.testing.assert_array_equal(a, b)
    assert sum(a.shape[0] for a, _ in groups.values()) == sum(a.shape[0] for a in A)


@pytest.mark.parametrize("n_tests", [3, 6])
def test_the_systematic_uncertainty_follows_the_offset_and_vanishes_with_it(n_tests):
    # halfway between two groups alike, each pulls the fit by delta / 4 (to the noise's share of the weights);
    # rescaled by G / (G - 1) = 2 for two groups of equal shares, u_sys is the fit's error delta / 2
    for delta in (0.02, 0.01):
        assert _u_sys(delta, n_tests=n_tests) == pytest.approx(delta / 2, rel=0.2)
    # without an offset, only the noise of the group means: sigma / sqrt(observations), rescaled
    assert _u_sys(0.0, n_tests=n_tests) < np.sqrt(2) * 0.01 / np.sqrt(n_tests * 30)
    assert _u_sys(0.02, n_tests=n_tests) > _u_sys(0.005, n_tests=n_tests) > _u_sys(0.0, n_tests=n_tests)


class SampledView(TwoViews):
    """The second group read on a grid of step ``dt``, at the grid point before: biased by -dt / 2."""

    def __init__(self, dt, **kw):
        super().__init__(0.0, **kw)
        if dt > 0:
            self.y["b"] = np.floor(self.y["b"] / dt) * dt


def test_the_systematic_uncertainty_grows_with_a_coarser_sampling_and_vanishes_with_it():
    def u(dt):
        problem = SampledView(dt)
        groups = by_group(problem, _fitted(problem))[-1]
        (k,), (nu,) = bias_correction(groups)
        assert nu == pytest.approx(1.0)
        return float(systematic_uncertainty(groups)[0][0] / np.sqrt(k))

    assert u(0.02) > u(0.01) > u(0.0)
    # the noise dithers the grid: the bias is dt / 2, each group pulls by a quarter of it (the pulls before
    # their rescaling by the groups' shares, 2.1 here: the floored group's noise weighs it a little less)
    assert u(0.01) == pytest.approx(0.01 / 2 / (2 * np.sqrt(2)), rel=0.3)


def test_one_group_has_no_systematic_part():
    problem = TwoViews(0.02)
    problem.y = {"a": problem.y["a"]}
    u, nu = systematic_uncertainty(by_group(problem, _fitted(problem))[-1])
    assert u == pytest.approx([0.0], abs=1e-12) and nu == [np.inf]


def test_the_interval_holds_a_truth_that_the_statistical_interval_misses():
    problem = TwoViews(0.01)
    f = _fitted(problem)
    names, x0, lo, hi, A, y, _ = by_group(problem, f)
    statistical = sandwich_intervals(names, x0, lo, hi, A, y)["m"]
    assert not statistical[0] <= TRUTH <= statistical[1]
    a, b = parameter_intervals(problem, f, n_boot=40)["m"]
    assert a <= TRUTH <= b and a <= f.values["m"] <= b
    # no wider than the statistical part and the fit's error, delta / 2, times t on the one degree of
    # freedom two groups give (12.7)
    assert b - f.values["m"] < stats.t.ppf(0.975, 1) * 0.01 / 2 + (statistical[1] - statistical[0])


def test_a_widened_interval_holds_its_estimate_within_the_bounds():
    assert widened([0.2, 0.4], 0.3, 0.0, 1.0, 0.0) == pytest.approx([0.2, 0.4])
    # a side that missed the estimate starts from it
    lo, hi = widened([0.31, 0.4], 0.3, 0.0, 1.0, 0.0)
    assert lo == pytest.approx(0.3) and hi == pytest.approx(0.4)
    lo, hi = widened([0.0, 0.001], 0.0, 0.0, 1.0, 0.01)
    assert lo == 0.0 and hi == pytest.approx(np.hypot(0.001, 1.96 * 0.01), rel=1e-3)
    assert widened([0.99, 1.0], 1.0, 0.0, 1.0, 0.5) == pytest.approx([1.0 - np.hypot(0.01, 1.96 * 0.5), 1.0], rel=1e-3)
    assert widened([0.2, 0.4], 0.3, 0.0, 1.0, 10.0) == [0.0, 1.0]


def test_a_simultaneous_interval_takes_the_sidak_quantile_of_its_effective_degrees_of_freedom():
    """A statistical half-width 0.1 on 2 df widened by a systematic 0.05 on 3: the interval is t(nu_eff) u_c,
    and two such parameters together take the Šidák quantile of the same t; a side on its bound stays."""
    stat, u = 0.1, 0.05
    ci = widened([0.3 - stat, 0.3 + stat], 0.3, 0.0, 1.0, u, df=2, df_sys=3)
    nu = widened_dof([0.3 - stat, 0.3 + stat], 0.3, u, 2, 3)
    u_c = np.hypot(stat / stats.t.ppf(0.975, 2), u)
    # Welch-Satterthwaite's 4.15: t u_c 0.151, below the systematic part's own t(3) 0.05 = 0.159, which is no
    # floor (tests/test_systematic_dof.py), and above the statistical part's 0.1, which is one
    ws = u_c**4 / ((stat / stats.t.ppf(0.975, 2)) ** 4 / 2 + u**4 / 3)
    assert stats.t.ppf(0.975, ws) * u_c < stats.t.ppf(0.975, 3) * u
    assert nu == pytest.approx(ws) and ci[1] - 0.3 == pytest.approx(stats.t.ppf(0.975, ws) * u_c)
    # a statistical part on few units beside a small systematic one on many: the statistical interval stands
    assert widened([0.2, 0.4], 0.3, 0.0, 1.0, 0.001, df=2, df_sys=50) == pytest.approx([0.2, 0.4])
    assert ci[1] - 0.3 == pytest.approx(stats.t.ppf(0.975, nu) * u_c)
    # where neither part is alone the wider, the interval is Welch-Satterthwaite's
    u_s = 0.1 / stats.t.ppf(0.975, 4)
    ws = (u_s**2 + 0.03**2) ** 2 / (u_s**4 / 4 + 0.03**4 / 3)
    assert widened_dof([0.2, 0.4], 0.3, 0.03, 4, 3) == pytest.approx(ws)
    assert widened([0.2, 0.4], 0.3, 0.0, 1.0, 0.03, df=4, df_sys=3)[1] - 0.3 == pytest.approx(
        stats.t.ppf(0.975, ws) * np.hypot(u_s, 0.03)
    )
    assert simultaneous(ci, 0.3, 0.0, 1.0, 1, nu) == pytest.approx(ci)
    lo, hi = simultaneous(ci, 0.3, 0.0, 1.0, 2, nu)
    half = stats.t.ppf(0.5 + 0.95**0.5 / 2, nu) * u_c
    assert (lo, hi) == pytest.approx((0.3 - half, 0.3 + half), rel=1e-9)
    lo, hi = simultaneous([0.0, 0.05], 0.0, 0.0, 1.0, 3, 4)
    assert lo == 0.0 and hi > 0.05


def test_a_verdicts_intervals_count_all_its_parameters_each_on_its_own_degrees_of_freedom():
    """Three parameters in two findings: each interval is simultaneous over k = 3, on its effective degrees
    of freedom where given, else on the units its finding rests on less one (a stop on the 5 tests that
    stop of 10); a side cut at its bound by the systematic part stays there."""
    P = {n: Param(n, 0.0, 1.0, 0.0) for n in ("a", "b", "v")}
    u = float(np.hypot(0.01, 0.02))
    cut = widened([0.001, 0.05], 0.002, 0.0, 1.0, u, df=9, df_sys=3)
    nu = widened_dof([0.001, 0.05], 0.002, u, 9, 3)
    assert cut[0] == 0.0 and 3 < nu < 9
    found = [
        Finding(effect="x", params={"a": 0.3, "b": 0.002}, ci95={"a": [0.25, 0.36], "b": cut}, u_systematic={"b": u}),
        Finding(effect="stop", params={"v": 0.2}, ci95={"v": [0.15, 0.26]}),
    ]
    verdict_intervals(found, P, {"x": 10, "stop": 5}, dof={"x": {"b": nu}})
    joint = [f.ci95_joint or {} for f in found]
    assert joint[0]["a"] == pytest.approx(simultaneous([0.25, 0.36], 0.3, 0.0, 1.0, 3, 9))
    assert joint[0]["b"] == pytest.approx(simultaneous(cut, 0.002, 0.0, 1.0, 3, nu))
    assert joint[0]["b"][0] == 0.0
    lo, hi = joint[1]["v"]
    r = stats.t.ppf(0.5 + 0.95 ** (1 / 3) / 2, 4) / stats.t.ppf(0.975, 4)
    assert (lo, hi) == pytest.approx((0.2 - r * 0.05, 0.2 + r * 0.06))


def test_the_standard_error_of_an_interval_over_few_units_is_its_half_width_over_t():
    assert standard_error([0.9, 1.1]) == pytest.approx(0.1 / 1.959964)
    assert standard_error([0.9, 1.1], df=4) == pytest.approx(0.1 / stats.t.ppf(0.975, 4))
