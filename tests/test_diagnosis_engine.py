"""The estimation engine (rocklab.diagnosis.estimation) on problems with a known answer: intervals, structure tests."""

import numpy as np
import pytest
from scipy import optimize, stats

from rocklab.diagnosis.estimation import fit, noise, parameter_intervals, resampling, within_slope
from rocklab.diagnosis.estimation.problem import Problem
from rocklab.diagnosis.parameters import Param
from rocklab.inference.intervals import expanded, percentile_interval


class _Cause:
    def __init__(self, name, params, replaces=()):
        self.name, self.params, self.replaces = name, params, replaces


class DecayProblem(Problem):
    """Per-test log ratios of y = A exp(-k x) (1 + q x^2) over noisy records: nonlinear in k."""

    def __init__(self, n_tests=12, k=0.3, q=0.05, noise=0.02, seed=0):
        rng = np.random.default_rng(seed)
        self.x = np.tile(np.linspace(0.0, 4.0, 15), (n_tests, 1))
        self.level = rng.normal(0.0, 0.01, (n_tests, 1))  # a per-test level: the resampling sees clusters
        self.y = np.exp(-k * self.x) * (1 + q * self.x**2) * np.exp(self.level + rng.normal(0.0, noise, self.x.shape))
        self.n_tests = n_tests
        self.causes = (_Cause("decay", (Param("k", 0.0, 2.0, 0.0, 0.01), Param("q", -1.0, 1.0, 0.0, 0.01))),)

    def subset(self, idx):
        return np.asarray(idx)

    def residuals(self, sub, ext, values):
        k, q = values.get("k", 0.0), values.get("q", 0.0)
        x = self.x[sub]
        return {"g": np.log(np.exp(-k * x) * (1 + q * x**2) / self.y[sub])}

    def noise(self, sub):
        return {"g": np.full(self.x[sub].shape, 0.01)}


def test_one_step_bootstrap_matches_the_refit_of_every_resample():
    problem = DecayProblem()
    f = fit(problem, np.arange(problem.n_tests), ("decay",))
    ci = parameter_intervals(problem, f, n_boot=40, seed=3)
    # the refit of every resample (the engine's former bootstrap) with the same draws
    rng = np.random.default_rng(3)
    draws = []
    for _ in range(40):
        pick = np.sort(rng.integers(0, problem.n_tests, problem.n_tests))
        g = fit(problem, pick, ("decay",), x0=f.values, n_irls=1)
        draws.append([g.values["k"], g.values["q"]])
    d = np.array(draws)
    for i, k in enumerate(("k", "q")):
        # both expanded alike for their few tests
        ref = np.array(expanded(percentile_interval(d[:, i]), f.values[k], problem.n_tests))
        width = ref[1] - ref[0]
        assert width > 0
        assert ci[k] == pytest.approx(ref, abs=0.05 * width), (k, ci[k], ref)


def _cr1_closed_form(r, x, groups):
    """Cluster-robust (CR1) standard error of the within-group slope, by the matrices of Cameron & Miller (2015)."""
    X, U, G = [], [], np.unique(groups)
    for g in G:
        m = groups == g
        X.append(x[m] - x[m].mean())
        U.append(r[m] - r[m].mean())
    Xa, Ua = np.concatenate(X), np.concatenate(U)
    bread = 1.0 / (Xa @ Xa)
    beta = bread * (Xa @ Ua)
    meat = sum((xg @ (ug - beta * xg)) ** 2 for xg, ug in zip(X, U))
    n, k = Xa.size, 1
    return beta, np.sqrt(len(G) / (len(G) - 1) * (n - 1) / (n - k) * bread * meat * bread)


@pytest.mark.parametrize("n_tests", [4, 6, 12])
def test_structure_slopes_have_the_small_sample_correction(n_tests):
    from scipy import stats

    rng = np.random.default_rng(n_tests)
    x = rng.uniform(0.0, 1.0, (n_tests, 10))
    r = 0.05 * x + rng.normal(0.0, 0.02, (n_tests, 1)) + rng.normal(0.0, 0.03, x.shape) * (1 + x)
    beta, p, _ = within_slope(r, x, np.ones(x.shape, bool))
    ref_beta, ref_se = _cr1_closed_form(r.ravel(), x.ravel(), np.repeat(np.arange(n_tests), 10))
    se = abs(beta) / stats.t.isf(p / 2, n_tests - 1)
    assert beta == pytest.approx(ref_beta, rel=1e-12)
    assert se == pytest.approx(ref_se, rel=1e-9)
    # the uncorrected error is sqrt((G - 1) / G) of it: 9.5 % too small with 6 tests, 15.5 % with 4 (issue 12)
    meat_only = ref_se * np.sqrt((n_tests - 1) / n_tests)
    assert se / meat_only == pytest.approx({4: 1.1547, 6: 1.0954, 12: 1.0445}[n_tests], abs=1e-4)


@pytest.mark.parametrize("n_tests", [5, 12])
def test_one_step_heldout_matches_the_refit_of_every_fold(n_tests):
    problem = DecayProblem(n_tests=n_tests, seed=n_tests)
    every = np.arange(n_tests)
    f = fit(problem, every, ("decay",))
    ho = resampling.heldout(problem, ("decay",), f)
    # the refit of each fold's training tests (the engine's former held-out fits), each held-out
    # residual scored by the Student-t its training residuals predict (scipy's law, the normal law's
    # constants taken out); the noise here is one variance, so one degree of freedom a residual
    ref = np.full(n_tests, np.nan)
    for held in resampling._folds(n_tests):
        train = np.setdiff1d(every, held)
        g = fit(problem, train, ("decay",), x0=f.values)
        r, x = problem.residuals(held, ("decay",), g.values)["g"], problem.noise(held)["g"]
        v = g.var["g"][0] + g.var["g"][1] * x**2 + noise.VAR_FLOOR
        nu = problem.x[train].size
        ref[held] = np.mean(-2.0 * stats.t.logpdf(r, nu, scale=np.sqrt(v)) - np.log(2.0 * np.pi), axis=1)
    base = resampling.heldout(problem, ())["deviance"]
    # per test, and the gain over the base model the selection weighs, to a per cent of that gain
    assert ho["deviance"] == pytest.approx(ref, abs=0.01 * np.mean(base - ref))
    assert np.mean(base - ho["deviance"]) == pytest.approx(np.mean(base - ref), rel=1e-3)


class NoisyDecayProblem(DecayProblem):
    """DecayProblem whose noise grows as its noise covariate: the weights of the fit matter."""

    def __init__(self, seed=0):
        super().__init__(noise=0.0, seed=seed)
        rng = np.random.default_rng(seed + 1)
        self.cov = rng.uniform(0.5, 3.0, self.x.shape)
        self.y = self.y * np.exp(rng.normal(0.0, 0.01, self.x.shape) * np.sqrt(1.0 + 4.0 * self.cov**2))

    def noise(self, sub):
        return {"g": self.cov[sub]}


def test_reweighted_passes_reach_the_fixed_point_of_the_likelihood():
    problem = NoisyDecayProblem(seed=4)
    every = np.arange(problem.n_tests)
    f = fit(problem, every, ("decay",))
    assert f.converged and f.passes > 1 and f.var["g"][1] > 0
    # the fixed point: a full search with the fit's own weights stays where the fit ended
    x = problem.noise(every)["g"]
    w = 1.0 / np.sqrt(f.var["g"][0] + f.var["g"][1] * x**2 + noise.VAR_FLOOR)
    sol = optimize.least_squares(
        lambda v: (problem.residuals(every, ("decay",), {"k": v[0], "q": v[1]})["g"] * w).ravel(),
        [f.values["k"], f.values["q"]],
        xtol=1e-12,
        ftol=1e-12,
    )
    ci = parameter_intervals(problem, f, n_boot=40, seed=1)
    for i, k in enumerate(("k", "q")):
        assert sol.x[i] == pytest.approx(f.values[k], abs=5e-3 * (ci[k][1] - ci[k][0])), k  # one pass: 6-8 %


def test_noise_model_is_the_profile_minimum_of_a_fine_grid():
    """The noise model's bounded search (scipy's minimize_scalar over log rho) reaches the lowest
    profile likelihood of a fine grid over its whole range, ends (rho = 0, s0 = 0) included, on
    residuals of every shape of noise."""
    rng = np.random.default_rng(7)
    for k in range(60):
        n = int(rng.integers(4, 80))
        x = rng.uniform(0.02, 3.0, n)
        s0, s1 = 10 ** rng.uniform(-3, 0), 10 ** rng.uniform(-3, 0) * (k % 3 > 0)
        r = rng.normal(size=n) * np.sqrt(s0**2 + s1**2 * x**2)
        v0, v1 = noise.noise_variance(r, x)
        r2, x2 = r**2 + noise.VAR_FLOOR, x**2

        def m2ll(a, b, r2=r2, x2=x2):
            v = a + b * x2
            return np.sum(r2 / v + np.log(v))

        lo, hi = -np.log(x2.max()) - 12.0, -np.log(x2.min()) + 12.0
        grid = np.exp(np.linspace(lo, hi, 4000))
        # each rho of the grid with its best s0^2, as the profile has it
        best = min(m2ll(s, rho * s) for rho in grid for s in [np.mean(r2 / (1.0 + rho * x2))])
        best = min(best, m2ll(np.mean(r2), 0.0), m2ll(1e-300, np.mean(r2 / x2)))
        assert m2ll(v0, v1) <= best + 1e-6 * abs(best) + 1e-6, k


def test_a_held_out_residual_is_scored_by_the_t_its_training_residuals_predict():
    """The predictive law of a residual whose variance was estimated from n residuals is Student's t on n
    degrees of freedom (one fewer where the shape of the variance is fitted too); the normal law's
    deviance as n grows, and on three near-noiseless training residuals a residual ten times their scale
    costs some 15 units, not the normal law's 100."""
    r, x = np.array([0.1, -0.3, 2.0]), np.zeros(3)
    var = {"g": (0.04, 0.0)}
    for nu in (1, 3, 10):
        ref = float(np.sum(-2.0 * stats.t.logpdf(r, nu, scale=0.2))) - 3 * np.log(2.0 * np.pi)
        assert noise.deviance({"g": r}, {"g": x}, var, {"g": nu}) == pytest.approx(ref, rel=1e-8)
    normal = noise.deviance({"g": r}, {"g": x}, var)
    assert noise.deviance({"g": r}, {"g": x}, var, {"g": 1e7}) == pytest.approx(normal, rel=1e-5)
    # the degrees of freedom: the residuals, less the shape where s0 and s1 are both fitted
    R, X = {"a": np.array([1.0, 2.0, np.nan]), "b": np.arange(6.0)}, {"a": np.ones(3), "b": np.ones(6)}
    assert noise.predictive_dof(R, X, {"a": (1.0, 0.0), "b": (1.0, 0.5)}) == {"a": 2, "b": 5}
    R, X, tiny = {"g": np.array([1e-2])}, {"g": np.zeros(1)}, {"g": (1e-6, 0.0)}
    assert 12.0 < noise.deviance(R, X, tiny, {"g": 3}) - np.log(1e-6) < 17.0
    assert noise.deviance(R, X, tiny) - np.log(1e-6) == pytest.approx(100.0, rel=1e-3)


def test_a_rejection_is_decided_on_its_step_and_worded_as_the_files_had_it():
    """Issue 40, item 1: the selection decides on ``Rejection.by``; the sentence is only written."""
    from rocklab.diagnosis.estimation.selection import RejectedBy, Rejection, sentences

    cases = {
        Rejection(RejectedBy.DESIGN, why="one contact depth"): "the design cannot identify it (one contact depth)",
        Rejection(RejectedBy.SIGNATURE): "its signature in the data is absent",
        Rejection(RejectedBy.INFORMATION_CRITERION, dbic=-3.04): "BIC -3.0",
        Rejection(RejectedBy.HELD_OUT, gain=0.01234, se=0.0456): (
            "held-out deviance gain 0.0123 within the noise (standard error 0.046)"
        ),
        Rejection(RejectedBy.INTERVAL): "95% interval within the smallest effect worth naming of its null value",
        Rejection(RejectedBy.CARRIED, loss=1.5, se=0.25, carried_by="flight_damping"): (
            "carried by flight_damping (removing it costs 1.5 +- 0.25 held out)"
        ),
    }
    for rejection, text in cases.items():
        assert rejection.sentence == text
    assert {r.by for r in cases} == set(RejectedBy)
    assert sentences({"a": Rejection(RejectedBy.SIGNATURE), "b": None}) == {
        "a": "its signature in the data is absent",
        "b": "",
    }


def test_the_compiled_bounded_search_is_scipys_step_for_step():
    """The noise model's search (:func:`noise._profile_minimum`) ends where scipy's
    ``minimize_scalar(method="bounded")`` ends, bit for bit, on residuals of every shape of noise."""
    rng = np.random.default_rng(11)
    for k in range(300):
        n = int(rng.integers(4, 150))
        x2 = np.maximum(rng.lognormal(-3.0, 2.0, n) ** 2, 1e-300)
        r2 = (rng.normal(size=n) * np.sqrt(10 ** rng.uniform(-6, -2) + 10 ** rng.uniform(-6, -2) * x2)) ** 2
        r2 = r2 + noise.VAR_FLOOR
        lo, hi = -np.log(x2.max()) - 12.0, -np.log(x2.min()) + 12.0
        ref = optimize.minimize_scalar(
            noise._profile, bounds=(lo, hi), args=(r2, x2), method="bounded", options={"xatol": 1e-3}
        )
        assert noise._profile_minimum(lo, hi, 1e-3, r2, x2) == (float(ref.x), float(ref.fun)), k


class TogetherDecay(DecayProblem):
    """:class:`DecayProblem` that evaluates the points of a finite difference together, as one array."""

    def __init__(self, **kw):
        super().__init__(**kw)
        self.together = []

    def residuals_at(self, sub, ext, values):
        self.together.append(len(values))
        k = np.array([v.get("k", 0.0) for v in values])[:, None, None]
        q = np.array([v.get("q", 0.0) for v in values])[:, None, None]
        x = self.x[sub][None]
        return [{"g": r} for r in np.log(np.exp(-k * x) * (1 + q * x**2) / self.y[sub][None])]


def test_a_fit_evaluates_its_finite_differences_together_and_ends_where_it_did():
    """least_squares' finite differences (its own steps, bounds respected) and the linearisation
    of the intervals go through :meth:`Problem.residuals_at`: a problem that evaluates the points
    together is fitted as one that evaluates them one by one, to the last bit."""
    alone, together = DecayProblem(q=0.2), TogetherDecay(q=0.2)
    idx = np.arange(alone.n_tests)
    a, b = fit(alone, idx, ("decay",)), fit(together, idx, ("decay",))
    assert (a.values, a.m2ll, a.passes) == (b.values, b.m2ll, b.passes)
    assert together.together and max(together.together) == 2
    assert parameter_intervals(alone, a, n_boot=20, seed=1) == parameter_intervals(together, b, n_boot=20, seed=1)


class CountingDecay(DecayProblem):
    """DecayProblem that records the points its residuals are evaluated at, one by one."""

    def __init__(self, **kw):
        super().__init__(**kw)
        self.points = []

    def residuals(self, sub, ext, values):
        self.points.append(tuple(sorted(values.items())))
        return super().residuals(sub, ext, values)


def test_a_fit_evaluates_the_residuals_of_a_point_once():
    """The start the masks are read at and each pass's optimum (the point least_squares accepted
    last) are not evaluated again: no point twice, and the fit is that of a problem that has
    no such points to share (the counting changes nothing)."""
    problem = CountingDecay(q=0.2)
    idx = np.arange(problem.n_tests)
    f = fit(problem, idx, ("decay",))
    assert len(problem.points) == len(set(problem.points)), "a point evaluated twice"
    g = fit(DecayProblem(q=0.2), idx, ("decay",))
    assert (f.values, f.m2ll, f.passes) == (g.values, g.m2ll, g.passes)


def test_a_fits_held_out_result_is_made_once():
    """selection.heldout_of: the held-out result of a fit, made on the first call and shared after."""
    from rocklab.diagnosis.estimation.selection import heldout_of

    problem = DecayProblem()
    f = fit(problem, np.arange(problem.n_tests), ("decay",))
    first = heldout_of(problem, f)
    assert heldout_of(problem, f) is first
    again = resampling.heldout(problem, ("decay",), f)
    assert first.keys() == again.keys()
    assert all(np.array_equal(first[k], again[k], equal_nan=True) for k in first)
