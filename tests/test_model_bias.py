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
from rocklab.diagnosis.estimation.bias import model_bias

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
    u, b = model_bias(ShareLow(f.values["m"], share, seed=1), f)
    # two noise draws: the measured and the simulated
    assert b["m"] == pytest.approx(share * f.values["m"], abs=4 * np.sqrt(2) * SE)
    # the noise of one draw taken off: a little under |b|
    assert abs(b["m"]) - SE < u["m"] <= abs(b["m"])


def test_an_exact_model_has_no_bias_beyond_the_noise():
    f = _fit(ShareLow(TRUTH, 0.0))
    u, b = model_bias(ShareLow(f.values["m"], 0.0, seed=1), f)
    assert abs(b["m"]) < 4 * np.sqrt(2) * SE
    assert u["m"] < 4 * SE


def test_a_fit_without_parameters_has_no_bias():
    f = fit(ShareLow(TRUTH, 0.0), np.arange(6), ())
    assert model_bias(ShareLow(TRUTH, 0.0), f) == ({}, {})


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
