"""The bias of the model measured on tests simulated at the fit (rocklab.diagnosis.estimation.bias).

A toy with a closed form: tests see a mean m through a model that reads
every observation low by a share ``s`` (an approximation of the model that
every test and group shares, which neither the resampling nor the pulls see):
the fit is m (1 + s); the same model fitted on tests simulated at the fit
(the truth the fit claims, measured without the model's error) lands at
m (1 + s)^2, so b = s m (1 + s), to the noise, which u_model takes off.
Then the wall: a viscous loss in flight, whose estimate what the
derivative filter reads of it (flight_filter.filter_reading) moves by more than
the statistical interval is wide.
"""

import sys
from pathlib import Path

import numpy as np
import pytest
from test_systematic_intervals import TRUTH, _Mean

from rocklab.diagnosis.estimation import Problem, fit
from rocklab.diagnosis.estimation.bias import model_bias, net_of_noise

NOISE = 0.0005
#: The standard error of one fit: the noise over all observations of the toy's six tests of 40.
SE = NOISE / np.sqrt(6 * 40)


class ShareLow(Problem):
    """Tests of k observations of a mean ``m``, read by a model that takes them to be (1 + share) too low."""

    causes = (_Mean(),)

    def __init__(self, m, share, n_tests=6, k=40, noise=NOISE, seed=0):
        rng = np.random.default_rng(seed)
        self.y = m + noise * rng.standard_normal((n_tests, k))
        self.share, self.n_tests = share, n_tests

    def subset(self, idx):
        return {"obs": self.y[np.asarray(idx)]}

    def residuals(self, sub, ext, values):
        return {"obs": values.get("m", 0.0) - (1 + self.share) * sub["obs"]}

    def noise(self, sub):
        return {"obs": np.ones_like(sub["obs"])}


def _fit(problem):
    return fit(problem, np.arange(problem.n_tests), ("mean",))


@pytest.mark.parametrize("share", [0.01, 0.03])
def test_the_bias_of_a_model_that_reads_low_is_its_closed_form(share):
    measured = ShareLow(TRUTH, share)
    f = _fit(measured)
    assert f.values["m"] == pytest.approx(TRUTH * (1 + share), rel=1e-3)
    u, b = model_bias([ShareLow(f.values["m"], share, seed=s) for s in (1, 2, 3)], f)
    # the measured noise and the mean of three simulated draws'
    assert b["m"] == pytest.approx(share * f.values["m"], abs=4 * np.sqrt(1 + 1 / 3) * SE)
    # the noise of the draws taken off: a little under |b|, whose noise is a third of one draw's
    assert abs(b["m"]) - 2 * SE < u["m"] <= abs(b["m"]) + SE


def test_an_exact_model_has_no_bias_beyond_the_noise():
    f = _fit(ShareLow(TRUTH, 0.0))
    u, b = model_bias([ShareLow(f.values["m"], 0.0, seed=s) for s in (1, 2, 3)], f)
    assert abs(b["m"]) < 4 * np.sqrt(1 + 1 / 3) * SE
    assert u["m"] < 4 * SE


def test_more_draws_leave_a_bias_of_one_standard_error_at_zero_less_often():
    """Issue 41: a bias of one standard error, net of the noise of one draw, is zero about half the time;
    mean(b_r^2) - mean(se^2) over three draws less often (a closed form: b_r = bias + se z_r)."""
    rng = np.random.default_rng(0)
    b = 1.0 + rng.standard_normal((3, 20000))
    one = np.mean(net_of_noise(b[:1], np.ones((1, b.shape[1]))) == 0)
    three = np.mean(net_of_noise(b, np.ones_like(b)) == 0)
    assert 0.40 < one < 0.55 and three < 0.35


def test_a_fit_without_parameters_has_no_bias():
    f = fit(ShareLow(TRUTH, 0.0), np.arange(6), ())
    assert model_bias([ShareLow(TRUTH, 0.0)], f) == ({}, {})


@pytest.fixture(scope="module")
def damped():
    """The discovery bench's series of a viscous loss zeta = 0.01 on a stocky two-sided wall, 100 Hz, 10 tests."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
    import discovery

    row = {"cause": "flight_damping", "boundary": "two-sided", "fs": 100.0, "wall": "stocky", "n_tests": 10,
           "seed": 3}  # fmt: skip
    return discovery.run_cell(row, 40)


def test_the_interval_of_a_loss_in_flight_holds_it_by_the_models_bias(damped):
    assert damped["verdict"] == ["flight_damping"]
    assert damped["outside"] == [] and damped["params_covered"] == 1


def test_the_bias_is_measured_on_at_most_a_fixed_number_of_tests_spread_over_the_series():
    """A series ten times longer simulates no more tests for its model's bias (its job would grow with
    the campaign): at most MAX_BIAS_TESTS, from its first test to its last; a shorter one, all."""
    from rocklab.diagnosis.series import MAX_BIAS_TESTS, spread_over

    short = list(range(MAX_BIAS_TESTS))
    assert spread_over(short, MAX_BIAS_TESTS) == short
    long = list(range(10 * MAX_BIAS_TESTS + 7))
    picked = spread_over(long, MAX_BIAS_TESTS)
    assert len(picked) == MAX_BIAS_TESTS and picked[0] == 0 and picked[-1] == long[-1]
    gaps = np.diff(picked)
    assert gaps.min() >= 1 and gaps.max() - gaps.min() <= 1
