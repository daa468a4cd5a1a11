"""The systematic error of a fit's parameters: how far each residual group pulls them.

The intervals of :mod:`rocklab.diagnosis.estimation.resampling` resample
whole tests, so they hold what varies between tests and nothing that every
test shares.  An error of the measurement chain or of the model's
approximations is of the second kind: for a wall, the derivative filter's
bias on the impact velocities, an impact instant read to a fraction of a
sample, a flight fitted by its linearisation; at the lab's noise the
statistical intervals are some 1e-6 wide and such errors are larger.  Each
residual group of a problem sees its own part of the physics through its own
part of the chain (a wall's velocities through the derivative filter,
apexes through the local fits of the flights, flight and gap times through
the impact instants: :mod:`rocklab.diagnosis.evidence`), so an error of one
part makes the groups disagree, and the fit settles where their pulls
balance.  The pull of group g on the parameters is

    d_g = B^-1 A_g^T y_g,        B = sum over groups of A_g^T A_g,

with A_g, y_g the group's weighted derivatives and minus its weighted
residuals at the fit (:func:`~rocklab.diagnosis.estimation.fitting.linearised`):
the step the estimate takes when the group's observations are moved onto the
model, the share of the estimate that rests on the group's misfit.  The pulls
of all groups sum to zero at an optimum inside the bounds; each is the
systematic standard uncertainty a group's error gives the parameters, the
groups' errors independent (different parts of the chain), so

    u_sys = sqrt(sum over groups of d_g^2)             (per parameter),

and the 95 % interval adds it to the statistical part (:func:`widened`).

The pulls of G groups sum to zero: u_sys^2 estimates the variance of the
fit's systematic error from the G - 1 independent differences between the
groups, biased low and loose.  Let group g hold the share p_g of the
information on a parameter (for one parameter w_g / sum w, its weight in
the fit; :func:`bias_correction` holds the general case of correlated
parameters) and carry a bias e_g
of its own, independent between groups, of variance s^2 / w_g: a bias in
units of the group's own noise, as the Birge ratio takes the disagreement
of inconsistent data (the model is the same in any units of the parameter,
and it is the one whose error the information-weighted fit minimises).  The
fit's error is sum p_g e_g, of variance V = s^2 / sum w, and
d_g = p_g (e_g - sum p_h e_h), so

    E[sum d_g^2] = V (1 - S2),          S2 = sum p_g^2,

(G - 1)/G of V for equal shares, Kish's effective number of groups
1 / S2 in place of G.  The estimate is rescaled by k = 1 / (1 - S2), so
that k u_sys^2 is unbiased, and its degrees of freedom are Satterthwaite's
for the quadratic form, nu = (1 - S2)^2 / (S2 - 2 sum p^3 + S2^2) (G - 1 for
equal shares, 1 for two groups whatever their shares;
:func:`bias_correction`): the Type A evaluation of an uncertainty from the
scatter of a few values (GUM, JCGM 100:2008, G.3).  Under this model the
error is independent of the pulls and Student's t on nu is exact for equal
shares.  Biases of one variance whatever the information (issue 41's
simulation) would call for a larger k where one group dominates: that
model extrapolates the disagreement of a group that holds a few millionths
of the information onto the one that holds the rest (on the contact lab,
an edge inset's u_sys 0.015 where the error was 3e-4, and the cause no
longer named); under it this interval undercovers with a dominant group,
tests/test_systematic_dof.py measures by how much.  The pulls are taken at
the optimum of the linearisation (:func:`pulls`) and net of the share the
residuals' noise gives them (:func:`pull_noise`), which the statistical
part holds already.

The statistical part (on the units resampled less one, nu_stat) and the
systematic parts (the pulls on nu; the model's bias on its draws,
:mod:`rocklab.diagnosis.estimation.bias`) add in quadrature, each side of
the interval apart, u_c^2 = u_stat^2 + sum u_i^2 with u_stat = h / t(nu_stat)
from the statistical half-width h, and the interval's half-width is
t(nu_eff) u_c, Student's t on the Welch-Satterthwaite degrees of freedom

    nu_eff = u_c^4 / (u_stat^4 / nu_stat + sum u_i^4 / nu_i)

(GUM, JCGM 100:2008, G.4.1 and G.6.4; :func:`effective_dof`).  It is the
statistical interval where u_sys = 0 and tends to it where u_sys << u_stat;
where the systematic part rests on one degree of freedom, t is 12.7 at
95 %.  The simultaneous intervals of a verdict take the Šidák quantile of
the same t (:func:`simultaneous`).  Everything is computed for each fit
from its own data; no constant is set on a benchmark.  What it cannot see:
an error that moves every group alike, or one of a group that alone fixes
a parameter (its pull is then nothing); the noise taken off is the noise
model's, and a noise underestimated is left in the pulls; the selection
of the causes on the same data is not corrected for.  A problem of one
residual group has no second view: its systematic part is zero.
"""

from __future__ import annotations

import logging
from collections.abc import Collection, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, TypeAlias, TypeVar, cast

import numpy as np

from rocklab._imports import lazy_module
from rocklab.diagnosis.estimation.fitting import Fit, linearised
from rocklab.diagnosis.estimation.problem import Problem
from rocklab.inference.multiplicity import simultaneous_factor

optimize = lazy_module("scipy.optimize")
stats = lazy_module("scipy.stats")

if TYPE_CHECKING:
    from rocklab.diagnosis.parameters import Param
    from rocklab.diagnosis.result import Finding, Number

log = logging.getLogger(__name__)

Sub = TypeVar("Sub")

#: The residuals of a problem by subset, causes and values (:class:`_Groups`).
Memo: TypeAlias = dict[tuple[int, tuple[str, ...], tuple[tuple[str, float], ...]], dict[str, np.ndarray]]

#: Residual group -> its weighted derivatives and minus its weighted residuals, stacked over the tests.
Groups: TypeAlias = dict[str, tuple[np.ndarray, np.ndarray]]


class _Groups(Problem[Sub]):
    """``problem`` seen through some of its residual groups, its residuals computed once per point.

    The linearisation of each group (:func:`by_group`) evaluates the residuals at the same points:
    the memo makes that one evaluation for all groups, as one linearisation of all of them.
    """

    def __init__(self, problem: Problem[Sub], groups: Iterable[str], memo: Memo) -> None:
        self.problem, self.groups, self.memo = problem, set(groups), memo
        self.n_tests, self.causes = problem.n_tests, problem.causes

    def subset(self, idx: np.ndarray) -> Sub:
        return self.problem.subset(idx)

    def noise(self, sub: Sub) -> dict[str, np.ndarray]:
        return self.problem.noise(sub)

    def params(self, ext: Collection[str]) -> list[Param]:
        return self.problem.params(ext)

    def residuals(self, sub: Sub, ext: Collection[str], values: Mapping[str, float]) -> dict[str, np.ndarray]:
        return self.residuals_at(sub, ext, [values])[0]

    def residuals_at(
        self, sub: Sub, ext: Collection[str], values: Sequence[Mapping[str, float]]
    ) -> list[dict[str, np.ndarray]]:
        keys = [(id(sub), tuple(ext), tuple(v.items())) for v in values]
        missing = {k: v for k, v in zip(keys, values) if k not in self.memo}
        self.memo.update(zip(missing, self.problem.residuals_at(sub, ext, list(missing.values()))))
        return [{g: r for g, r in self.memo[k].items() if g in self.groups} for k in keys]


def by_group(
    problem: Problem[Any], fitted: Fit
) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray, list[np.ndarray], list[np.ndarray], Groups]:
    """The linearisation of ``fitted`` over all tests, group by group.

    Returns
    -------
    names : list of str
    x0, lo, hi : ndarray
        As :func:`~rocklab.diagnosis.estimation.fitting.linearised`.
    A, y : list of ndarray
        Per test, the rows of every group (the linearisation of all groups).
    groups : dict
        Group -> (A_g, y_g), its rows stacked over the tests.
    """
    every = problem.subset(np.arange(problem.n_tests))
    memo: Memo = {}
    parts = {g: linearised(_Groups(problem, [g], memo), every, fitted) for g in fitted.var}
    names, x0, lo, hi = next(iter(parts.values()))[:4]
    A = [np.concatenate([p[4][i] for p in parts.values()]) for i in range(problem.n_tests)]
    y = [np.concatenate([p[5][i] for p in parts.values()]) for i in range(problem.n_tests)]
    groups = {g: (np.concatenate(p[4]), np.concatenate(p[5])) for g, p in parts.items()}
    return names, x0, lo, hi, A, y, groups


def pulls(groups: Mapping[str, tuple[np.ndarray, np.ndarray]]) -> dict[str, np.ndarray]:
    """The pull of each residual group on the parameters at the optimum of the linearisation (module
    docstring), group -> ndarray.

    A fit stops within its tolerance of the optimum, or on a bound, where the pulls d_g = B^-1 A_g^T y_g
    sum to the step left, D; group g's share of it, B^-1 A_g^T A_g D, is taken off each (the pulls at
    the linearisation's optimum, which sum to zero: the groups' disagreement, wherever the fit stopped).
    """
    Bg = {g: a.T @ a for g, (a, _) in groups.items()}
    Binv = np.linalg.pinv(sum(Bg.values()))
    d = {g: Binv @ (a.T @ b) for g, (a, b) in groups.items()}
    left = sum(d.values())
    return {g: x - Binv @ Bg[g] @ left for g, x in d.items()}


def pull_noise(groups: Mapping[str, tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """The share of sum d_g^2 the residuals' noise gives, per parameter [its unit squared].

    The rows of A_g, y_g are weighted by their noise model (unit variance); with white noise eps_g and
    H_g = B^-1 A_g^T A_g, d_g = B^-1 A_g^T eps_g - H_g B^-1 sum_h A_h^T eps_h, whose covariance is
    B^-1 B_g B^-1 - B^-1 B_g B^-1 B_g B^-1 (for one parameter, the statistical variance times
    p_g (1 - p_g)).
    """
    Bg = [a.T @ a for a, _ in groups.values()]
    Binv = np.linalg.pinv(sum(Bg))
    return np.sum([np.diag(Binv @ b @ Binv - Binv @ b @ Binv @ b @ Binv) for b in Bg], axis=0)


def _root_pinv(b: np.ndarray) -> np.ndarray:
    """The symmetric square root of the pseudo-inverse of a symmetric positive semi-definite ``b``."""
    w, v = np.linalg.eigh(b)
    keep = w > 1e-12 * max(float(w.max()), 0.0)
    return cast(np.ndarray, (v[:, keep] / np.sqrt(w[keep])) @ v[:, keep].T)


def bias_correction(groups: Mapping[str, tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """The factor k that makes k sum d_g^2 unbiased for the variance of the fit's systematic error, and its
    degrees of freedom nu, per parameter.

    Groups of independent biases in units of their own noise (module
    docstring): group g reads the parameters off by delta_g, of covariance
    s^2 B_g^+ (B_g = A_g^T A_g, the group's information).  With
    H_g = B^-1 B_g the fit's error is sum H_g delta_g, of covariance s^2 B^-1,
    and the pulls are d_g = H_g (delta_g - sum_h H_h delta_h), linear in the
    standard normal z of delta_g = s (B_g^+)^(1/2) z_g: per parameter j,
    sum d_gj^2 = s^2 z^T M_j z, so

        k_j = (B^-1)_jj / tr M_j,        nu_j = (tr M_j)^2 / tr(M_j^2)

    (Satterthwaite 1946; GUM, JCGM 100:2008, G.4).  A parameter that one
    group alone informs sees no second view: k = 1, nu infinite.  For one
    parameter, with p_g the groups' shares of the information and
    S2 = sum p_g^2, k = 1 / (1 - S2) and nu = (1 - S2)^2 / (S2 - 2 sum p^3 + S2^2):
    G / (G - 1) and G - 1 for equal shares, nu = 1 for two groups whatever
    their shares.  Correlated parameters are counted as they are: a group
    that pulls a parameter through its correlation with another is a view
    of it.

    Returns
    -------
    k, nu : ndarray
        One per parameter.
    """
    Bg = [a.T @ a for a, _ in groups.values()]
    Binv = np.linalg.pinv(sum(Bg))
    H = [Binv @ b for b in Bg]
    root = [_root_pinv(b) for b in Bg]
    n = Binv.shape[0]
    # T[g][:, h-th block]: the map of z_h onto d_g
    T = [np.hstack([((g == h) * H[g] - H[g] @ H[h]) @ root[h] for h in range(len(Bg))]) for g in range(len(Bg))]
    k, nu = np.ones(n), np.full(n, np.inf)
    for j in range(n):
        rows = np.array([t[j] for t in T])
        M = rows.T @ rows
        tr = float(np.trace(M))
        # below this the fit's error is not seen by the groups' disagreement: no second view
        if tr > 1e-12 * Binv[j, j]:
            k[j], nu[j] = Binv[j, j] / tr, tr**2 / float(np.sum(M * M))
    return k, nu


def systematic_uncertainty(groups: Mapping[str, tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """The systematic standard uncertainty of each parameter, and its degrees of freedom.

    The pulls of the groups in quadrature (:func:`pulls`), net of the share
    their noise gives (:func:`pull_noise`: the statistical part is not
    counted twice), rescaled to an unbiased estimate of the variance by the
    groups' views of the parameter (:func:`bias_correction`):
    u_sys = sqrt(k max(sum d_g^2 - noise, 0)).

    Parameters
    ----------
    groups : dict
        Group -> (A_g, y_g), as :func:`by_group` returns them.

    Returns
    -------
    u : ndarray
        One per parameter [its unit]; zeros for a single group.
    nu : ndarray
        Its degrees of freedom, one per parameter (infinite for a single group).
    """
    d = np.array(list(pulls(groups).values()))
    k, nu = bias_correction(groups)
    return np.sqrt(k * np.maximum(np.sum(d**2, axis=0) - pull_noise(groups), 0.0)), nu


def effective_dof(u: Sequence[float], dof: Sequence[float]) -> float:
    """The Welch-Satterthwaite degrees of freedom of the sum in quadrature of uncertainties ``u`` on ``dof``.

    nu_eff = (sum u_i^2)^2 / sum(u_i^4 / nu_i) (GUM, JCGM 100:2008, Eq. G.2b);
    a part on infinite degrees of freedom adds nothing to the denominator;
    infinite where every part is known exactly or all are zero.
    """
    u2 = np.asarray(u, float) ** 2
    nu = np.asarray(dof, float)
    den = float(np.sum(np.divide(u2**2, nu, out=np.zeros_like(u2), where=np.isfinite(nu) & (u2 > 0))))
    return float(np.sum(u2)) ** 2 / den if den > 0 else np.inf


def _t(level: float, df: float) -> float:
    """The two-sided quantile of Student's t on ``df`` degrees of freedom at ``level`` (the normal's for
    ``df`` infinite: 1.96 at 95 %)."""
    return float(stats.t.ppf(0.5 + level / 2, df))


def standard_error(ci: Sequence[float], level: float = 0.95, df: float = np.inf) -> float:
    """The standard error a symmetric interval ``ci`` of ``level`` stands for: its half-width over the
    quantile of Student's t on ``df`` degrees of freedom (the normal's by default, the inverse of
    :func:`widened`'s scaling; an interval over n units, t or expanded bootstrap, on n - 1)."""
    return (ci[1] - ci[0]) / (2.0 * _t(level, df))


def _side(h: float, u_sys: float, df: float, df_sys: float, level: float) -> tuple[float, float]:
    """One side of :func:`widened`: the half-width from a statistical one ``h`` on ``df``, and its
    effective degrees of freedom."""
    u_stat = h / _t(level, df) if h > 0 else 0.0
    u_c = float(np.hypot(u_stat, u_sys))
    nu = effective_dof([u_stat, u_sys], [df, df_sys])
    # Welch-Satterthwaite's degrees of freedom can exceed the statistical part's where the systematic part,
    # on more of them, is small: t(nu) u_c then falls below the statistical interval, which stands (its
    # degrees of freedom those that make t(nu) u_c its width).  The systematic part's own t(nu_sys) u_sys is
    # no floor: at one degree of freedom (12.7 u_sys) it is the interval of a systematic error alone, and
    # beside a statistical part known on more units it covers 0.97-0.98 where Welch-Satterthwaite covers
    # 0.94-0.95 (tests/test_systematic_dof.py), losing effects the data carry (a rocking edge worn over a
    # series); where the systematic part dominates on one degree of freedom, Welch-Satterthwaite covers
    # some 0.88-0.92, the price said on the method page
    floor = h
    if _t(level, nu) * u_c >= floor:
        return _t(level, nu) * u_c, nu
    fewest = min(df, df_sys)
    # at the fewer degrees of freedom t u_c reaches the floor, but for rounding where one part is all of it
    if _t(level, fewest) * u_c <= floor:
        return floor, fewest
    return floor, float(optimize.brentq(lambda n: _t(level, n) * u_c - floor, fewest, nu))


def widened(
    ci: Sequence[float],
    x0: float,
    lower: float,
    upper: float,
    u_sys: float,
    level: float = 0.95,
    df: float = np.inf,
    df_sys: float = np.inf,
) -> list[float]:
    """The statistical interval ``ci`` of an estimate ``x0`` with a systematic standard uncertainty
    ``u_sys`` added.

    Each side's half-width h stands for the standard uncertainty
    u_stat = h / t(df); with ``u_sys`` on ``df_sys`` degrees of freedom it
    becomes t(nu_eff) sqrt(u_stat^2 + u_sys^2), Student's t on their
    Welch-Satterthwaite degrees of freedom (module docstring,
    :func:`effective_dof`), cut at the bounds [lower, upper]; the result
    always holds ``x0`` (a side that missed it starts from it), and is
    never narrower than the statistical interval (its degrees of freedom
    then those that make t(nu) u_c that width: :func:`widened_dof`).  Both on
    infinite degrees of freedom (the defaults) it is sqrt(h^2 + (z u_sys)^2),
    z = 1.96 at 95 %; without ``u_sys`` it is ``ci``.
    """
    below = _side(max(x0 - ci[0], 0.0), u_sys, df, df_sys, level)[0]
    above = _side(max(ci[1] - x0, 0.0), u_sys, df, df_sys, level)[0]
    return [float(max(lower, x0 - below)), float(min(upper, x0 + above))]


def widened_dof(ci: Sequence[float], x0: float, u_sys: float, df: float, df_sys: float, level: float = 0.95) -> float:
    """The effective degrees of freedom of the interval :func:`widened` makes of ``ci``: the fewer of its
    two sides' (the wider quantile)."""
    return min(_side(max(h, 0.0), u_sys, df, df_sys, level)[1] for h in (x0 - ci[0], ci[1] - x0))


def statistical_error(half: float, u_sys: float, df: float, level: float = 0.95) -> float:
    """The statistical standard error u_stat of a half-width ``half`` that :func:`widened` made from a
    statistical part on ``df`` degrees of freedom and ``u_sys`` on infinite ones; NaN where ``half``
    holds nothing but ``u_sys``.

    The half-width grows with u_stat there (both the quantile and u_c do), so the root is one.  Of an
    interval whose systematic part had fewer degrees of freedom it is too large: the cautious side.
    """
    if not half > _side(0.0, u_sys, df, np.inf, level)[0]:
        return np.nan
    return float(optimize.brentq(lambda s: _side(s * _t(level, df), u_sys, df, np.inf, level)[0] - half, 0.0, half))


def simultaneous(
    ci: Sequence[float], x0: float, lower: float, upper: float, k: int, df: float, level: float = 0.95
) -> list[float]:
    """The interval ``ci`` of ``level`` on ``df`` (effective) degrees of freedom as one of ``k`` that hold
    all their parameters together at ``level``.

    Each side's distance from ``x0`` is t(df) u_c (:func:`widened`): it is
    widened by the Šidák factor of Student's t on the same ``df``
    (:func:`rocklab.inference.multiplicity.simultaneous_factor`) and cut at
    the bounds: a side on its bound stays there.  For ``k`` = 1 the interval
    is ``ci``.
    """
    r = simultaneous_factor(k, df, level)
    return [float(max(lower, x0 - r * max(x0 - ci[0], 0.0))), float(min(upper, x0 + r * max(ci[1] - x0, 0.0)))]


def verdict_intervals(
    findings: Sequence[Finding],
    params: Mapping[str, Param],
    n_units: Mapping[str, int],
    level: float = 0.95,
    dof: Mapping[str, Mapping[str, float]] | None = None,
) -> None:
    """Give each finding ``ci95_joint``: its intervals as part of the verdict's, which hold every parameter
    of every cause named together at ``level`` (:func:`simultaneous` over all of them): the claim that the
    verdict and all its values are right.

    Parameters
    ----------
    findings : list of rocklab.diagnosis.result.Finding
        With ``effect``, ``params`` and ``ci95``.
    params : dict
        Parameter name -> :class:`~rocklab.diagnosis.parameters.Param` (its bounds).
    n_units : dict
        Effect -> the units (tests, the tests that show a stop, block groups) its intervals rest on.
    dof : dict, optional
        Effect -> parameter -> the effective degrees of freedom of its interval (:func:`widened_dof`);
        one missing: the units less one, the statistical part's alone.
    """
    k = sum(len(f.ci95) for f in findings)
    dof = dof or {}
    for f in findings:
        df = n_units[f.effect] - 1
        # the findings of a diagnosis being made hold numbers (a file's None is a number not finite)
        f.ci95_joint = {
            name: cast(
                "list[Number]",
                simultaneous(
                    cast("list[float]", ci),
                    cast(float, f.params[name]),
                    params[name].lower,
                    params[name].upper,
                    k,
                    dof.get(f.effect, {}).get(name, df),
                    level,
                ),
            )
            for name, ci in f.ci95.items()
            if ci is not None
        }
