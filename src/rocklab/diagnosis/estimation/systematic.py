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

and the 95 % interval is the statistical one widened on each side to
sqrt(h^2 + (z u_sys)^2), h its half-width on that side, z = 1.96 the normal
quantile of the level (:func:`widened`): the statistical and the systematic
parts added in quadrature (GUM, JCGM 100:2008, Sect. 5).  It is computed for
each fit from its own data; no constant is set on a benchmark.  What it
cannot see: an error that moves every group alike, or one of a group that
alone fixes a parameter (its pull is then nothing); the noise of the
residuals enters the pulls too, so with the statistical part it is counted
twice (where the noise dominates, an interval some sqrt(2) too wide).
A problem of one residual group has no second view: its systematic part is
zero.
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
    """The pull of each residual group on the parameters (module docstring), group -> ndarray."""
    B = sum(a.T @ a for a, _ in groups.values())
    Binv = np.linalg.pinv(B)
    return {g: Binv @ (a.T @ b) for g, (a, b) in groups.items()}


def systematic_uncertainty(groups: Mapping[str, tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """The systematic standard uncertainty of each parameter: the pulls of the groups in quadrature.

    Parameters
    ----------
    groups : dict
        Group -> (A_g, y_g), as :func:`by_group` returns them.

    Returns
    -------
    ndarray
        One per parameter [its unit]; zeros for a single group.
    """
    d = np.array(list(pulls(groups).values()))
    return np.sqrt(np.sum(d**2, axis=0))


def _z(level: float) -> float:
    """The two-sided normal quantile of ``level`` (1.96 at 95 %)."""
    return float(stats.norm.ppf(0.5 + level / 2))


def standard_error(ci: Sequence[float], level: float = 0.95, df: float = np.inf) -> float:
    """The standard error a symmetric interval ``ci`` of ``level`` stands for: its half-width over the
    quantile of Student's t on ``df`` degrees of freedom (the normal's by default, the inverse of
    :func:`widened`'s scaling; an interval over n units, t or expanded bootstrap, on n - 1)."""
    return (ci[1] - ci[0]) / (2.0 * float(stats.t.ppf(0.5 + level / 2, df)))


def widened(
    ci: Sequence[float], x0: float, lower: float, upper: float, u_sys: float, level: float = 0.95
) -> list[float]:
    """The interval ``ci`` of an estimate ``x0`` with a systematic standard uncertainty ``u_sys`` added.

    Each side's half-width h becomes sqrt(h^2 + (z u_sys)^2), z the normal
    quantile of ``level`` (1.96 at 95 %), cut at the bounds [lower, upper];
    the result always holds ``x0`` (a side that missed it starts from it).
    """
    z = _z(level)
    lo, hi = ci
    below = np.hypot(max(x0 - lo, 0.0), z * u_sys)
    above = np.hypot(max(hi - x0, 0.0), z * u_sys)
    return [float(max(lower, x0 - below)), float(min(upper, x0 + above))]


def simultaneous(
    ci: Sequence[float],
    x0: float,
    lower: float,
    upper: float,
    u_sys: float,
    k: int,
    df: float,
    level: float = 0.95,
) -> list[float]:
    """The interval ``ci`` of :func:`widened` (its systematic part ``u_sys``) as one of ``k`` that hold all
    their parameters together at ``level``.

    Each side's statistical half-width, sqrt(h^2 - (z u_sys)^2), is widened
    by the Šidák factor of Student's t on ``df`` degrees of freedom (the
    units resampled, less one), its systematic part by that of the normal
    quantile (:func:`rocklab.inference.multiplicity.simultaneous_factor`),
    added again in quadrature by :func:`widened` and cut at the bounds: a
    side on its bound stays there.  For ``k`` = 1 the interval is ``ci``.
    """
    z = _z(level)
    r_stat = simultaneous_factor(k, df, level)
    below, above = (
        r_stat * np.sqrt(max(h**2 - (z * u_sys) ** 2, 0.0)) for h in (max(x0 - ci[0], 0.0), max(ci[1] - x0, 0.0))
    )
    return widened([x0 - below, x0 + above], x0, lower, upper, simultaneous_factor(k, np.inf, level) * u_sys, level)


def verdict_intervals(
    findings: Sequence[Finding], params: Mapping[str, Param], n_units: Mapping[str, int], level: float = 0.95
) -> None:
    """Give each finding ``ci95_joint``: its intervals as part of the verdict's, which hold every parameter
    of every cause named together at ``level`` (:func:`simultaneous` over all of them, each on the units
    its intervals rest on less one): the claim that the verdict and all its values are right.

    Parameters
    ----------
    findings : list of rocklab.diagnosis.result.Finding
        With ``effect``, ``params``, ``ci95`` and, where known, ``u_systematic`` (none: the interval is all
        statistical).
    params : dict
        Parameter name -> :class:`~rocklab.diagnosis.parameters.Param` (its bounds).
    n_units : dict
        Effect -> the units (tests, the tests that show a stop, block groups) its intervals rest on.
    """
    k = sum(len(f.ci95) for f in findings)
    for f in findings:
        u = f.u_systematic or {}
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
                    u.get(name, 0.0),
                    k,
                    df,
                    level,
                ),
            )
            for name, ci in f.ci95.items()
            if ci is not None
        }
