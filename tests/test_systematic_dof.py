"""The systematic part's degrees of freedom (issue 41): coverage of groups carrying independent biases.

One parameter, G residual groups; group g holds the share p_g of the information and reads the parameter
with a bias e_g of its own, independent of the others'.  The fit is the weighted mean of the groups' readings
and each group's rows are its reading less the fit, weighted by a noise far below the biases, so the pulls
are those of :func:`rocklab.diagnosis.estimation.systematic.pulls`, and the truth is known: the coverage of
an interval is counted over seeded draws.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from rocklab.diagnosis.estimation.systematic import (
    bias_correction,
    effective_dof,
    pull_noise,
    pulls,
    simultaneous,
    statistical_error,
    systematic_uncertainty,
    widened,
    widened_dof,
)

DRAWS = 4000
#: The noise the groups' rows are weighted by: far below the biases, so that the pulls are the biases'.
SIGMA = 1e-6


def _groups(p: np.ndarray, e: np.ndarray, fit: float | None = None) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Groups of shares ``p`` reading 0 with biases ``e``, linearised at ``fit`` (their weighted mean)."""
    fit = float(p @ e) if fit is None else fit
    return {
        f"g{i}": (np.array([[np.sqrt(w) / SIGMA]]), np.array([np.sqrt(w) * (x - fit) / SIGMA]))
        for i, (w, x) in enumerate(zip(p, e))
    }


def _coverage(p: np.ndarray, scale: np.ndarray, seed: int) -> tuple[float, float]:
    """Coverage of the truth 0 by z u_sys of the raw pulls (the former interval) and by :func:`widened`.

    The shares, hence k and nu, are the same in every draw, and :func:`widened` of a point is t(nu) u_sys:
    one call gives its factor, and the draws' pulls are computed at once (checked on the first draws
    against :func:`systematic_uncertainty`).
    """
    rng = np.random.default_rng(seed)
    e = rng.standard_normal((DRAWS, p.size)) * scale
    x0 = e @ p
    raw = np.sqrt(np.sum((p * (e - x0[:, None])) ** 2, axis=1))
    (k,), (nu,) = bias_correction(_groups(p, e[0]))
    for i in range(3):
        (u,), (nu_i,) = systematic_uncertainty(_groups(p, e[i]))
        assert (u, nu_i) == pytest.approx((np.sqrt(k) * raw[i], nu), rel=1e-6)
    factor = widened([0.0, 0.0], 0.0, -np.inf, np.inf, 1.0, df=np.inf, df_sys=nu)[1]
    return float(np.mean(np.abs(x0) < 1.96 * raw)), float(np.mean(np.abs(x0) <= factor * np.sqrt(k) * raw))


EQUAL = [np.full(g, 1 / g) for g in (2, 3, 4, 6)]
UNEQUAL = [np.array([0.9, 0.1]), np.array([0.9, 0.05, 0.05]), np.array([0.6, 0.3, 0.1])]


@pytest.mark.parametrize(("p", "old_at_most"), list(zip(EQUAL, (0.65, 0.80, 0.85, 0.90))))
def test_equal_shares_are_covered_where_z_u_sys_was_not(p, old_at_most):
    """z u_sys covers 0.60, 0.75, 0.81, 0.87 for 2, 3, 4, 6 equal groups (issue 41); t on G - 1 degrees of
    freedom with u_sys rescaled by G / (G - 1) holds 0.95 (exact: the error is independent of the pulls)."""
    old, new = _coverage(p, np.ones(p.size), seed=1)
    assert old < old_at_most
    assert 0.93 <= new <= 0.97


@pytest.mark.parametrize("p", UNEQUAL)
def test_unequal_shares_of_biases_in_units_of_their_noise_are_covered(p):
    """The module's model, biases of variance 1 / p_g: t on Satterthwaite's degrees of freedom holds 0.95 and
    a little more (with unequal shares the quadratic form is no scaled chi-square)."""
    old, new = _coverage(p, 1.0 / np.sqrt(p), seed=2)
    assert old < 0.85
    assert 0.93 <= new <= 0.98


@pytest.mark.parametrize(("p", "old_at_most", "lowest"), list(zip(UNEQUAL, (0.25, 0.2, 0.7), (0.90, 0.82, 0.93))))
def test_biases_of_one_variance_with_a_dominant_group_are_undercovered(p, old_at_most, lowest):
    """What this interval does not hold (module docstring): biases of one variance whatever the information,
    issue 41's simulation (z u_sys 0.20 where one group holds 90 %), are undercovered where a group
    dominates: some 0.92 for shares 0.9 / 0.1, 0.85 for 0.9 / 0.05 / 0.05."""
    old, new = _coverage(p, np.ones(p.size), seed=3)
    assert old < old_at_most
    assert lowest <= new < 0.96


def test_the_noise_of_the_residuals_is_taken_off_the_pulls():
    """Groups of noise and no bias: the mean of sum d_g^2 is :func:`pull_noise`, and u_sys is zero about half
    the time (what the statistical part holds is not counted twice)."""
    rng = np.random.default_rng(4)
    n = np.array([30, 10, 5])
    sq, zero = [], 0
    for _ in range(2000):
        obs = [rng.standard_normal(k) for k in n]
        fit = np.concatenate(obs).mean()
        groups = {f"g{i}": (np.ones((k, 1)), fit - o) for i, (k, o) in enumerate(zip(n, obs))}
        sq.append(sum(float(d[0]) ** 2 for d in pulls(groups).values()))
        zero += systematic_uncertainty(groups)[0][0] == 0
    assert np.mean(sq) == pytest.approx(float(pull_noise(groups)[0]), rel=0.1)
    assert 0.3 < zero / 2000 < 0.8


def test_the_pulls_are_taken_at_the_optimum_of_the_linearisation():
    """A fit stopped short of its optimum: the pulls still sum to zero, and are those at the optimum."""
    p, e = np.array([0.5, 0.3, 0.2]), np.array([0.4, -0.2, 0.1])
    at, off = pulls(_groups(p, e)), pulls(_groups(p, e, fit=float(p @ e) + 0.05))
    assert sum(off.values()) == pytest.approx([0.0], abs=1e-12)
    for g in at:
        assert off[g] == pytest.approx(at[g])


def _correction(p):
    return tuple(float(x[0]) for x in bias_correction(_groups(np.asarray(p, float), np.zeros(len(p)))))


def test_equal_shares_give_g_over_g_less_one_on_g_less_one_degrees_of_freedom():
    for g in (2, 3, 4, 6):
        assert _correction(np.full(g, 1 / g)) == pytest.approx((g / (g - 1), g - 1))
    # two groups: one difference between them, one degree of freedom, whatever the shares
    assert _correction([0.9, 0.1]) == pytest.approx((1 / 0.18, 1.0))
    # one parameter: 1 / (1 - S2) on (1 - S2)^2 / (S2 - 2 sum p^3 + S2^2)
    p = np.array([0.6, 0.3, 0.1])
    s2, s3 = np.sum(p**2), np.sum(p**3)
    assert _correction(p) == pytest.approx((1 / (1 - s2), (1 - s2) ** 2 / (s2 - 2 * s3 + s2**2)))
    assert _correction([1.0]) == (1.0, np.inf)


def test_a_group_that_pulls_a_parameter_through_its_correlation_is_a_view_of_it():
    """Two parameters, x fixed by group a alone and y by b and c, a and b both reading x + y: a sees y only
    through x.  The correction counts each group's view as it is: k sum d_g^2 is unbiased for the variance of
    the fit's error in a Monte Carlo of biases in units of the groups' noise."""
    A = {"a": np.array([[1.0, 0.0], [1.0, 1.0]]), "b": np.array([[1.0, 1.0]]), "c": np.array([[0.0, 1.0]])}
    groups = {g: (a, np.zeros(len(a))) for g, a in A.items()}
    k, nu = bias_correction(groups)
    rng = np.random.default_rng(5)
    B = sum(a.T @ a for a in A.values())
    Binv = np.linalg.inv(B)
    err, sq = [], []
    for _ in range(4000):
        # each group's bias delta_g of covariance B_g^+, read as its rows' offsets
        off = {g: a @ (np.linalg.pinv(a) @ rng.standard_normal(len(a))) for g, a in A.items()}
        fit = Binv @ sum(A[h].T @ off[h] for h in A)
        grp = {g: (A[g], off[g] - A[g] @ fit) for g in A}
        err.append(fit)
        sq.append(np.sum(np.array(list(pulls(grp).values())) ** 2, axis=0))
    assert k * np.mean(sq, axis=0) == pytest.approx(np.var(err, axis=0), rel=0.1)
    assert np.all(nu >= 1) and np.all(np.isfinite(nu))


def test_one_group_has_no_systematic_part_and_the_statistical_interval_stands():
    groups = _groups(np.array([1.0]), np.array([0.3]))
    (u,), (nu,) = systematic_uncertainty(groups)
    assert u == 0.0 and nu == np.inf
    assert widened([0.1, 0.5], 0.3, 0.0, 1.0, u, df=4, df_sys=nu) == pytest.approx([0.1, 0.5])
    assert widened_dof([0.1, 0.5], 0.3, u, 4, nu) == pytest.approx(4)


def test_a_small_systematic_part_leaves_the_statistical_interval_and_its_dof():
    ci = [0.1, 0.5]
    lo, hi = widened(ci, 0.3, -np.inf, np.inf, 1e-4, df=4, df_sys=1)
    assert [lo, hi] == pytest.approx(ci, rel=1e-6)
    assert widened_dof(ci, 0.3, 1e-4, 4, 1) == pytest.approx(4, rel=1e-3)
    # a large one on one degree of freedom: its own interval, t on 1 (12.7 at 95 %)
    lo, hi = widened(ci, 0.3, -np.inf, np.inf, 100.0, df=4, df_sys=1)
    assert hi - 0.3 == pytest.approx(stats.t.ppf(0.975, 1) * 100.0, rel=1e-3)


def test_welch_satterthwaite():
    # GUM G.4.1: two parts of equal size on 4 and 4: 8 degrees of freedom; a part on infinite adds none
    assert effective_dof([1.0, 1.0], [4, 4]) == pytest.approx(8.0)
    assert effective_dof([1.0, 1.0], [4, np.inf]) == pytest.approx(16.0)
    assert effective_dof([0.0, 0.0], [4, 4]) == np.inf


def test_the_statistical_error_of_a_widened_interval_is_recovered_where_the_systematic_part_is_exact():
    se, u, df = 0.07, 0.05, 4
    h = stats.t.ppf(0.975, df) * se
    half = widened([0.3 - h, 0.3 + h], 0.3, -np.inf, np.inf, u, df=df)[1] - 0.3
    assert statistical_error(half, u, df) == pytest.approx(se, rel=1e-6)
    assert np.isnan(statistical_error(stats.norm.ppf(0.975) * u, u, df))


def test_a_simultaneous_interval_takes_the_sidak_quantile_of_its_own_t():
    lo, hi = simultaneous([0.2, 0.5], 0.3, 0.0, 1.0, 3, 5)
    r = stats.t.ppf(0.5 + 0.95 ** (1 / 3) / 2, 5) / stats.t.ppf(0.975, 5)
    assert [lo, hi] == pytest.approx([0.3 - 0.1 * r, 0.3 + 0.2 * r])
    assert simultaneous([0.2, 0.5], 0.3, 0.0, 1.0, 1, 5) == pytest.approx([0.2, 0.5])
    assert simultaneous([0.0, 0.05], 0.0, 0.0, 1.0, 3, 4)[0] == 0.0


@pytest.mark.parametrize(("ratio", "lowest", "highest"), [(0.25, 0.93, 0.97), (1.0, 0.92, 0.965), (4.0, 0.86, 0.94)])
def test_a_systematic_part_on_one_degree_of_freedom_beside_a_statistical_one(ratio, lowest, highest):
    """A statistical part on 9 degrees of freedom (ten tests) and a systematic one of ``ratio`` times its
    standard deviation estimated on one (two groups): Welch-Satterthwaite's t covers about 0.95 while the
    systematic part is not the larger, and some 0.88-0.92 where it dominates (the method page says so); the
    systematic part's own t(1) u_sys as a floor would cover 0.97-0.98 in the first case, at the price of
    effects the data carry."""
    rng = np.random.default_rng(int(ratio * 100))
    n, t9 = 3000, stats.t.ppf(0.975, 9)
    error = rng.standard_normal(n) + ratio * rng.standard_normal(n)
    u_stat = np.sqrt(rng.chisquare(9, n) / 9)
    u_sys = ratio * np.sqrt(rng.chisquare(1, n))
    covered = [
        abs(x) <= widened([-t9 * s, t9 * s], 0.0, -np.inf, np.inf, u, df=9, df_sys=1)[1]
        for x, s, u in zip(error, u_stat, u_sys)
    ]
    assert lowest <= np.mean(covered) <= highest
