"""A boundary condition and a campaign from the diagnoses of their series.

The series of a boundary condition are different walls and set-ups, so
their parameters are not fitted together: :func:`diagnose_boundary` names
the causes most of its series name and pools each parameter over all of
them, each at its own estimate, a series that cannot estimate one left
out (:func:`pooled_parameter`: a random-effects mean over walls, its t
interval widened by the systematic part the series share);
:func:`diagnose_campaign` diagnoses every series
(:func:`rocklab.diagnosis.series.diagnose_records`) and then every boundary
condition.  A series whose parameter changes over its tests counts in its
pool with its standard error widened by the spread of its states
(:func:`state_spread`).  Method: docs/diagnosis-method.md.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NamedTuple, cast

import numpy as np
import numpy.typing as npt

from rocklab.diagnosis import catalogue
from rocklab.diagnosis.errors import what_is_wrong
from rocklab.diagnosis.estimation import systematic
from rocklab.diagnosis.estimation.systematic import widened
from rocklab.diagnosis.evidence import MeasuredTest
from rocklab.diagnosis.result import (
    BaseRun,
    BoundaryDiagnosis,
    BoundaryExtended,
    CampaignDiagnosis,
    ChangeKind,
    ChangingSeries,
    Errors,
    HeldOut,
    LeftOut,
    LeftOutBecause,
    Number,
    PooledEvidence,
    PooledFinding,
    SeriesChange,
    SeriesDiagnosis,
    SeriesExtended,
    Structure,
)
from rocklab.diagnosis.series import MIN_TESTS_TO_NAME, base_name, diagnose_records
from rocklab.inference.intervals import mean_over_units, no_interval_note, random_effects_mean, t_interval
from rocklab.lab.hierarchy import plural
from rocklab.physics.boundary import Boundary

if TYPE_CHECKING:
    from rocklab.diagnosis.result import Finding, MeasuredAndModel

log = logging.getLogger(__name__)


def _wmean(vals: Iterable[Number] | np.ndarray, w: npt.ArrayLike | Sequence[Number]) -> float | None:
    """Weighted mean of the finite values (None counts as missing); None if there are none."""
    vals = np.array([np.nan if v is None else v for v in vals], float)
    w = np.asarray(w, float)
    ok = np.isfinite(vals)
    return float(np.sum(vals[ok] * w[ok]) / np.sum(w[ok])) if ok.any() else None


def _merge_errors(errors: Sequence[Mapping[str, Any]], w: npt.ArrayLike | Sequence[Number]) -> Errors:
    """Weighted means over series of :func:`engineering_errors` dicts."""
    return {
        k: (
            cast("MeasuredAndModel", {s: _wmean([e[k][s] for e in errors], w) for s in v})
            if isinstance(v, dict)
            else _wmean([e[k] for e in errors], w)
        )
        for k, v in errors[0].items()
    }


def pooled_parameter(
    values: Mapping[str, float],
    walls: Mapping[str, str] | None = None,
    u_sys: Mapping[str, float] | None = None,
    bounds: tuple[float, float] = (-np.inf, np.inf),
    se: Mapping[str, float] | None = None,
) -> tuple[float, list[float] | None, str, int, str, float]:
    """The random-effects mean of one parameter over series, and its 95 % interval.

    Each series is one unit; where the series' walls are known, each wall's
    value is the mean of its series and the walls are the units
    (:mod:`rocklab.lab.hierarchy`: a boundary condition's parameter holds for
    walls, and the series of one wall are one wall's evidence).  With every
    series' standard error (``se``) the units weigh 1 / (v_j + tau^2), tau^2
    the variance between them, and the standard error is Hartung-Knapp's
    (:func:`~rocklab.inference.intervals.random_effects_mean`): a precise
    series counts more only where the units agree within their errors.
    Without them (or with one missing) the units weigh the same (the scatter
    between series, sd ~0.01-0.05 of e/e_an, dwarfs a series' own standard
    error: :func:`~rocklab.inference.intervals.mean_over_units`).  Student's
    t on units - 1 degrees of freedom; none below the units a verdict needs
    (:func:`rocklab.lab.hierarchy.too_few_units`).

    The scatter between units holds what varies between them and nothing
    that all share: the series of one lab are measured with one chain and
    fitted with one model, so the systematic part of their intervals
    (``u_sys``, :class:`~rocklab.diagnosis.estimation.resampling.Intervals`)
    is taken as common to all of them, the error of the mean the mean of
    their errors: the t interval is widened by the mean over units of their
    systematic standard uncertainties (a unit the mean of its series'), as a
    series' interval is by its own
    (:func:`~rocklab.diagnosis.estimation.systematic.widened`).  Taking them
    as common is the cautious side: were they independent, the scatter would
    already hold them.

    Parameters
    ----------
    values : dict
        Series -> its value [the parameter's unit].
    walls : mapping, optional
        Series -> wall.
    u_sys : dict, optional
        Series -> the systematic standard uncertainty of its value [the parameter's unit] (none: 0).
    bounds : tuple of float
        The parameter's bounds, which the interval does not cross.
    se : dict, optional
        Series -> the statistical standard error of its value [the parameter's unit]; a series missing
        gives the units equal weights.

    Returns
    -------
    mean : float
    ci : list of float or None
    unit_level : str
    n_units : int
    note : str
        Why there is no interval; "" when there is one.
    u_shared : float
        The systematic standard uncertainty of the mean.
    """
    level = "series" if walls is None else "wall"
    units = [s if walls is None else walls[s] for s in values]
    errors = [np.nan if se is None else se.get(s, np.nan) for s in values]
    m, sd, k, note, _ = random_effects_mean(list(values.values()), errors, units, level)
    u_sys = u_sys or {}
    u_shared, *_ = mean_over_units([u_sys.get(s, 0.0) for s in values], units, level)
    if note:
        return m, None, level, k, no_interval_note(note), u_shared
    lo, hi, _ = t_interval(m, sd, k - 1)
    return m, widened([float(lo), float(hi)], m, *bounds, u_shared), level, k, "", u_shared


def statistical_error(ci: Sequence[Number], u_sys: float, n_tests: int | None) -> float:
    """The statistical standard error of a series' estimate from its 95 % interval [the parameter's unit].

    The interval's half-width h holds the statistical part, Student's t on
    the tests less one times the standard error, and the systematic part
    ``u_sys``, added by Welch-Satterthwaite
    (:func:`~rocklab.diagnosis.estimation.systematic.widened`): the
    statistical part is what a mean over series averages, the systematic
    part is shared and added once to the mean's interval
    (:func:`pooled_parameter`).  The systematic part's degrees of freedom
    are not kept with a finding: it is taken on infinite ones, which makes
    the statistical error of an interval whose systematic part had fewer
    too large (:func:`~rocklab.diagnosis.estimation.systematic.statistical_error`),
    the cautious side.  An interval cut at a bound is taken by its
    half-width.  NaN where there is no interval or it holds nothing but the
    systematic part.
    """
    if len(ci) != 2 or ci[0] is None or ci[1] is None:
        return np.nan
    return systematic.statistical_error((ci[1] - ci[0]) / 2.0, u_sys, max((n_tests or 2) - 1, 1))


def state_spread(change: SeriesChange) -> float:
    """The standard deviation over a series' tests of the states a changing parameter went through.

    The pool of a boundary condition takes a series' estimate as one wall's
    value; a parameter that changes over the series' tests
    (:class:`~rocklab.diagnosis.result.SeriesChange`) has no one value, and
    its estimate is a mean over the states the wall went through, weighed by
    how many tests each state had: the test protocol's doing, not the
    wall's.  Which state is the wall's is not known, and the spread of the
    states over the tests is what that costs: a change point of size d
    with a share p of the tests after it, |d| sqrt(p (1 - p)); a gradual
    change of d from the first of n tests to the last, the tests evenly
    placed, |d| sqrt((n + 1) / (12 (n - 1))).  0 where none was found.

    Why widen rather than leave the series out (:func:`_parameter_values`):
    its states are states of a wall of the boundary condition, evidence on
    what the pool estimates; leaving out the series whose change cleared the
    test conditions the pool on walls that did not change, by a test whose
    power is low on ten tests (a selection on the outcome, like the winner's
    curse).  Widened, the series weighs less the more its states differ,
    and the pool moves continuously with the size of the change, where a
    series left out at the test's threshold would jump from full weight to
    none.  Where its states span the other walls' values, its departure
    from them is its change's, not the walls' scatter: the variance between
    walls falls, and the interval may narrow.  The size is taken at its
    estimate; its own uncertainty is not added.
    """
    if change.kind is ChangeKind.NONE:
        return 0.0
    # a change found is always sized (rocklab.diagnosis.estimation.change)
    size = abs(cast(float, change.size))
    n = max(change.n_tests, 2)
    if change.kind is ChangeKind.CHANGE_POINT:
        after = (n - cast(int, change.where_index)) / n
        return size * float(np.sqrt(after * (1.0 - after)))
    return size * float(np.sqrt((n + 1) / (12.0 * (n - 1))))


class _Values(NamedTuple):
    """The series' own estimates of one parameter, the series left out of it and those counted though the
    parameter changes over their tests."""

    values: dict[str, float]
    se: dict[str, float]
    own: list[str]
    left_out: dict[str, tuple[LeftOutBecause, str]]
    changing: dict[str, ChangingSeries]


def _parameter_values(
    cause: str, name: str, series: Sequence[SeriesDiagnosis], named: Mapping[str | None, Finding]
) -> _Values:
    """Every series' own estimate of one parameter of ``cause`` under its extended model, with its
    statistical standard error: its finding's where it named the cause; where it did not, its unnamed
    estimate (a series short of the evidence to name it still says how large it is: ``unnamed_estimates``,
    its standard error in ``unnamed_se``).  A series that cannot estimate it is left out, never put at
    the null value: zeros for the series that cannot see a cause are the loser's curse, as a mean over
    the namers alone is the winner's (a wall whose series names zeta 0.0062 beside one that cannot see
    it would pool at 0.0031).  Its design cannot carry the cause (``not_identifiable``), it is too
    small to name any, or it has no estimate of the parameter (no signature of the cause in its data,
    or its fit on a bound).  A series whose parameter changes over its tests is counted, its standard
    error widened by the spread of its states (:func:`state_spread`, which says why it is not left out)."""
    out = _Values({}, {}, [], {}, {})
    for e in series:
        key = cast(str, e.key)
        f = named.get(key)
        mine = (e.unnamed_estimates or {}).get(cause, {})
        if e.too_small:
            out.left_out[key] = (LeftOutBecause.TOO_SMALL, e.too_small)
        elif f is not None and name in f.params and f.params[name] is not None:
            out.values[key] = cast(float, f.params[name])
            out.se[key] = statistical_error(
                f.ci95.get(name, []), (f.u_systematic or {}).get(name, 0.0), f.n_tests or e.n_tests
            )
        elif name in mine:
            out.values[key] = mine[name]
            out.se[key] = (e.unnamed_se or {}).get(cause, {}).get(name, np.nan)
            out.own.append(key)
        elif cause in (e.not_identifiable or {}):
            out.left_out[key] = (LeftOutBecause.NOT_IDENTIFIABLE, cast(dict, e.not_identifiable)[cause])
        else:
            # unnamed_estimates gives none where the data carry no signature of the cause or its fit left
            # the parameter on a bound
            out.left_out[key] = (LeftOutBecause.NO_ESTIMATE, "no estimate: no sign of the cause, or one on a bound")
        change = next((c for c in e.changed if c.effect == cause and c.parameter == name), None)
        if key in out.values and change is not None:
            u = state_spread(change)
            # an unknown standard error stays unknown: the units then weigh alike and their scatter holds it
            out.se[key] = float(np.hypot(out.se[key], u))
            out.changing[key] = ChangingSeries(
                series=key,
                parameter=name,
                kind=change.kind,
                where_test=change.where_test if change.kind is ChangeKind.CHANGE_POINT else None,
                before=change.before,
                after=change.after,
                u_states=u,
            )
    return out


def left_out(per_param: Mapping[str, _Values]) -> list[LeftOut]:
    """The series the parameters of one cause leave out, each once with the parameters it is left out of."""
    out: dict[str, LeftOut] = {}
    for name, v in per_param.items():
        for key, (reason, why) in v.left_out.items():
            out.setdefault(key, LeftOut(series=key, reason=reason, why=why)).params.append(name)
    return list(out.values())


def _pooled_text(
    units: str, n_values: int, n_named: int, n_own: int, gone: Sequence[LeftOut], changing: Sequence[ChangingSeries]
) -> str:
    """How a pooled parameter counts the series, in words."""
    head = f"random-effects mean over {units} of {n_values} series at their own estimates"
    how = [f"{n_named} that named it", f"{n_own} that did not (their data carry its signature)" if n_own else ""]
    text = f"{head}: " + ", ".join(h for h in how if h)
    if gone:
        text += "; left out: " + ", ".join(map(str, gone))
    if changing:
        text += "; changing over their tests: " + ", ".join(map(str, changing))
    return text


@dataclass(frozen=True)
class PooledBias:
    """The mean signed error of pooled parameters in units of the smallest effect worth naming
    (:func:`pooled_bias`).

    ``mean`` and ``ci95`` are in units of each parameter's
    :attr:`~rocklab.diagnosis.parameters.Param.practical`; ``ci95`` is None
    where the units are too few for an interval and ``note`` says so
    (:func:`rocklab.inference.intervals.no_interval_note`).
    """

    mean: float
    ci95: tuple[float, float] | None
    n_units: int
    level: str
    note: str


def pooled_bias(
    estimates: Sequence[float],
    truths: Sequence[float],
    smallest: Sequence[float],
    units: Sequence[str],
    level: str = "campaign",
) -> PooledBias:
    """The pooled bias: the mean signed error of pooled values, each in units of its smallest effect worth
    naming, with its 95 % interval.

    A boundary condition's pooled value of a parameter against the truth it
    was built with, (estimate - truth) / practical: 1 is an error as large as
    the smallest effect the diagnosis would name a cause for, so errors of
    parameters of different sizes (zeta ~0.006, v_stop/v_r ~0.1) are read on
    one scale.  The errors of one unit (a campaign: its parameters share its
    walls and its draw) are one unit's evidence: their mean, and the mean
    over units with Student's t on units - 1 degrees of freedom
    (:func:`~rocklab.inference.intervals.mean_over_units`); none from too few
    units, and ``note`` says so.  A pooled value without the curse has 0
    within the interval.

    Parameters
    ----------
    estimates, truths : sequence of float
        The pooled values and their truths [each parameter's unit].
    smallest : sequence of float
        Each parameter's smallest effect worth naming [its unit]
        (:attr:`~rocklab.diagnosis.parameters.Param.practical`), > 0.
    units : sequence of str
        The unit of each value (the campaign it was pooled in).
    level : str
        The level of the units (:data:`rocklab.lab.hierarchy.LEVELS`).

    Returns
    -------
    PooledBias

    Raises
    ------
    ValueError
        For a smallest effect that is not positive (a parameter that never names a cause has none).
    """
    scale = np.asarray(smallest, float)
    if not (np.isfinite(scale).all() and (scale > 0).all()):
        raise ValueError("a pooled bias needs every parameter's smallest effect worth naming, > 0")
    err = (np.asarray(estimates, float) - np.asarray(truths, float)) / scale
    m, se, k, reason = mean_over_units(err, list(units), level)
    if reason:
        return PooledBias(m, None, k, level, no_interval_note(reason))
    lo, hi, _ = t_interval(m, se, k - 1)
    return PooledBias(m, (float(lo), float(hi)), k, level, "")


def diagnose_boundary(
    entries: CampaignDiagnosis | Iterable[SeriesDiagnosis | BoundaryDiagnosis | Mapping[str, Any]],
    boundary: str,
    *,
    walls: Mapping[str, str] | None = None,
    thickness: Mapping[str, float] | None = None,
) -> BoundaryDiagnosis | None:
    """One boundary condition from the diagnoses of its series.

    ``entries``: a :class:`~rocklab.diagnosis.result.CampaignDiagnosis` or
    its entries (those of other boundary conditions are passed over).
    The series are different walls and set-ups, so their parameters are not
    pooled into one fit: a cause is in the verdict when it is named in at
    least half of the series large enough to name one (not ``too_small``),
    and its parameters pool ALL those series, never only the ones that named
    it (a mean over the namers alone is the winner's curse): every series
    counts at its own estimate under its extended model with its standard
    error, its finding's where it named the cause, its unnamed estimate
    where it did not, and a series that cannot estimate the parameter is
    left out and listed in ``left_out`` with why, never put at the null
    value (the loser's curse: :func:`_parameter_values`); a series whose
    parameter changes over its tests counts with its standard error widened
    by the spread of its states, listed in ``changes_within``
    (:func:`state_spread`).  The mean is a
    random-effects mean over series, or over walls where ``walls`` (series
    -> wall) is given, with a t interval (:func:`pooled_parameter`;
    ``ci_note`` says why there is none).  Each finding gives the ``n_series`` that named it, the
    ``n_units`` its parameters rest on and ``n_tests``.  Errors are
    test-weighted means over all series.  With ``thickness`` (wall ->
    thickness [m]) the entry gives ``wall_thickness_m``, the mean over its
    walls: the size the findings were measured at, for the maps' transfer
    under absolute sizes (:mod:`rocklab.seismic.calibrated`).
    """
    ser = CampaignDiagnosis.of(entries).series_of(boundary)
    if not ser:
        return None
    usable = [e for e in ser if not e.too_small]
    small = [e.key for e in ser if e.too_small]
    w_all = np.array([e.n_tests for e in ser], float)
    n_tests = int(w_all.sum())
    # the series entries as the diagnosis writes them: every key the file's schema requires set
    base_err = _merge_errors([cast(BaseRun, e.base).errors for e in ser], w_all)
    counts: dict[str, list] = {}
    for e in usable:
        for f in e.findings:
            counts.setdefault(f.effect, []).append((e, f))
    of_series = f"{len(usable)} series" + (f" large enough to name a cause (of {len(ser)})" if small else "")
    findings = []
    for eff, lst in counts.items():
        if len(lst) < 0.5 * len(usable):
            continue
        w = np.array([e.n_tests for e, _ in lst], float)
        named = {e.key: f for e, f in lst}
        params, ci, notes, units, shared = {}, {}, {}, {}, {}
        bounds = {q.name: (q.lower, q.upper) for q in catalogue.by_name(eff).params}
        per_param = {}
        for name in lst[0][1].params:
            # the too small series too: each is listed where it is left out
            v = per_param[name] = _parameter_values(eff, name, ser, named)
            u_sys = {k: (f.u_systematic or {}).get(name, 0.0) for k, f in named.items()}
            # an own estimate comes through the chain and the model the namers' came through, with no
            # systematic part of its own: their mean systematic part
            u_sys |= dict.fromkeys(v.own, float(np.mean(list(u_sys.values()))))
            params[name], interval, level, units[name], note, shared[name] = pooled_parameter(
                v.values, walls, u_sys, bounds.get(name, (-np.inf, np.inf)), v.se
            )
            if interval is None:
                notes[name] = note
            else:
                ci[name] = interval
        note = "; ".join(f"{k}: {v}" for k, v in notes.items())
        gone = left_out(per_param)
        changing = [c for v in per_param.values() for c in v.changing.values()]
        n_own = max(len(v.own) for v in per_param.values())
        findings.append(
            PooledFinding(
                effect=eff,
                params=cast("dict[str, Number]", params),
                ci95=cast("dict[str, list[Number]]", ci),
                u_systematic=shared,
                evidence=PooledEvidence(
                    series=f"named in {len(lst)} of {of_series}",
                    pooled=_pooled_text(
                        plural(level, max(units.values())),
                        max(len(v.values) for v in per_param.values()),
                        len(lst),
                        n_own,
                        gone,
                        changing,
                    ),
                    range={
                        n: [float(min(f.params[n] for _, f in lst)), float(max(f.params[n] for _, f in lst))]
                        for n in params
                    },
                ),
                error_heldout={"deviance_per_obs": _wmean([f.error_heldout["deviance_per_obs"] for _, f in lst], w)},
                gain={k: _wmean([f.gain.get(k) for _, f in lst], w) for k in lst[0][1].gain},
                n_series=len(lst),
                n_tests=int(w.sum()),
                ci_note=note or None,
                left_out=gone or None,
                changes_within=changing or None,
            )
        )
    findings.sort(key=lambda f: (-(f.n_series or 0), -(f.gain["deviance_per_obs"] or 0)))
    flagged = [e.key for e in usable if e.unexplained]
    kinds: dict[str, int] = {}
    for e in usable:
        # sorted: ties keep one order whatever the hashing of the process
        for k in sorted({st.where for st in e.residual_structure}):
            kinds[k] = kinds.get(k, 0) + 1
    w_used = [e.n_tests for e in usable]
    ho = (
        HeldOut(
            # a series large enough to name a cause has its held-out errors
            base={
                k: _wmean([cast(HeldOut, e.heldout)["base"][k] for e in usable], w_used)
                for k in cast(HeldOut, usable[0].heldout)["base"]
            },
            model={
                k: _wmean([cast(HeldOut, e.heldout)["model"][k] for e in usable], w_used)
                for k in cast(HeldOut, usable[0].heldout)["model"]
            },
        )
        if usable
        else None
    )
    statement, off = what_is_wrong(base_err, "the simulation")
    verdicts = {e.key: e.verdict for e in ser}
    extended = [e for e in ser if e.extended]
    ext_statement = None
    if extended:
        ext_err = _merge_errors(
            [cast(SeriesExtended, e.extended)["errors"] for e in extended], [e.n_tests for e in extended]
        )
        ext_statement = what_is_wrong(ext_err, "the extended model")[0]
    if usable and not findings and not flagged and not off:
        statement = "the base model explains the data within the noise: " + statement
    kinds_left = sorted(kinds.items(), key=lambda x: -x[1])
    out = BoundaryDiagnosis(
        scope="boundary",
        key=boundary,
        boundary=boundary,
        n_tests=n_tests,
        n_series=len(ser),
        n_series_diagnosed=len(usable),
        too_small_series=cast("list[str]", small),
        n_impacts=int(sum(cast(int, e.n_impacts) for e in ser)),
        base=BaseRun(model=base_name(boundary), errors=base_err),
        what_is_wrong=statement,
        verdict=[f.effect for f in findings],
        unexplained=bool(usable) and len(flagged) >= 0.5 * len(usable),
        residual_structure=[Structure(k, f"{k} in {n} of {len(usable)} series") for k, n in kinds_left],
        unexplained_series=cast("list[str]", flagged),
        findings=findings,
        heldout=ho,
        series_verdicts=cast("dict[str, list[str]]", verdicts),
        extended=BoundaryExtended(statement=ext_statement, n_series=len(extended)) if ext_statement else None,
        too_small=None
        if usable
        else (
            f"none of its {len(ser)} series has the {MIN_TESTS_TO_NAME} tests "
            "of two impacts or more a series needs to name one"
        ),
        wall_thickness_m=float(np.mean([thickness[w] for w in {walls[cast(str, e.key)] for e in ser}]))
        if walls is not None and thickness is not None
        else None,
    )
    log.info(
        "boundary %s: %d series (%d too small to name a cause), %d tests; verdict %s",
        boundary,
        len(ser),
        len(small),
        n_tests,
        ", ".join(out.verdict) or "none",
    )
    return out


def with_boundaries(
    entries: CampaignDiagnosis | Iterable[SeriesDiagnosis | BoundaryDiagnosis | Mapping[str, Any]],
    *,
    walls: Mapping[str, str] | None = None,
    thickness: Mapping[str, float] | None = None,
) -> CampaignDiagnosis:
    """Series entries followed by one entry per boundary condition (:func:`diagnose_boundary`; ``walls``:
    series -> wall, ``thickness``: wall -> thickness [m])."""
    series = CampaignDiagnosis.of(entries)
    pooled = (diagnose_boundary(series, b, walls=walls, thickness=thickness) for b in Boundary)
    return CampaignDiagnosis([*series.entries, *(e for e in pooled if e is not None)])


def diagnose_campaign(
    series_records: Mapping[str, Sequence[MeasuredTest | Mapping[str, Any]]],
    *,
    n_boot: int = 40,
    n_history: int = 2,
    by_boundary: bool = True,
    seed: int = 0,
) -> CampaignDiagnosis:
    """Diagnose every series and every boundary condition of a campaign.

    Parameters
    ----------
    series_records : dict
        series id -> list of test records (dicts for :func:`measured_test`)
        or :class:`MeasuredTest`.
    by_boundary : bool
        Add one entry per boundary condition (:func:`diagnose_boundary`).

    Returns
    -------
    CampaignDiagnosis
        The content of results/diagnosis.json.
    """
    entries = [
        diagnose_records(recs, sid, n_boot=n_boot, n_history=n_history, seed=seed)
        for sid, recs in series_records.items()
    ]
    series = CampaignDiagnosis([e for e in entries if e is not None])
    return with_boundaries(series) if by_boundary else series
