"""Diagnosis of a series, of a boundary condition, of a campaign (Sect. 3, Figs. 14-15).

:func:`diagnose_series` compares the base model with the tests of one
series (:mod:`rocklab.diagnosis.errors`), selects the causes the data
carry (:func:`rocklab.diagnosis.estimation.selection.select_effects` on a
:class:`rocklab.diagnosis.series_problem.WallProblem`), runs the causes estimated
after selection and states the gain; :mod:`rocklab.diagnosis.pooling` sums
the series of a boundary condition up.  A series longer than
:data:`rocklab.diagnosis.splitting.SPLIT_CAP` tests has its causes chosen on
some of its tests and estimated on the others (:mod:`rocklab.diagnosis.splitting`).
Method: docs/diagnosis-method.md.

Small samples: a cause is named only where the 95 % interval of its
parameter over the tests clears its null value: a bootstrap over tests, or
from fewer than :data:`rocklab.inference.intervals.MIN_BOOTSTRAP` tests
the cluster-robust t interval on their few degrees of freedom
(:func:`rocklab.diagnosis.estimation.resampling.parameter_intervals`), wide
as three tests make it.  A series of one test is compared with the base
model but names nothing (``too_small``: nothing varies between tests to
measure the noise of a parameter by).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Collection, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, TypedDict, cast

import numpy as np

from rocklab.diagnosis import catalogue
from rocklab.diagnosis.discovery import discovery
from rocklab.diagnosis.errors import what_is_wrong
from rocklab.diagnosis.estimation import beyond_the_catalogue, rivals, select_effects, stand_ins
from rocklab.diagnosis.estimation.bias import BIAS_DRAWS, model_bias, net_of_noise
from rocklab.diagnosis.estimation.change import changes_over_tests
from rocklab.diagnosis.estimation.fitting import linearised
from rocklab.diagnosis.estimation.resampling import heldout_gain, heldout_means, sandwich_errors
from rocklab.diagnosis.estimation.selection import RejectedBy, sentences, supported
from rocklab.diagnosis.estimation.systematic import (
    effective_dof,
    standard_error,
    verdict_intervals,
    widened,
    widened_dof,
)
from rocklab.diagnosis.evidence import MeasuredTest, in_series_order, measured_test, observe
from rocklab.diagnosis.extended import engineering_errors, model_params, simulated_tests
from rocklab.diagnosis.result import (
    BaseRun,
    ChangeKind,
    Finding,
    HeldOut,
    ModelBias,
    SeriesChange,
    SeriesDiagnosis,
    SeriesExtended,
    Structure,
)
from rocklab.diagnosis.series_problem import WallProblem
from rocklab.diagnosis.splitting import SPLIT_CAP, estimated, split_series, spread_over
from rocklab.physics.boundary import Boundary

if TYPE_CHECKING:
    from rocklab.diagnosis.causes.stop_threshold import StopEstimate
    from rocklab.diagnosis.estimation.fitting import Fits
    from rocklab.diagnosis.estimation.selection import Selection
    from rocklab.diagnosis.result import Number

log = logging.getLogger(__name__)

#: Tests a series needs to name a cause: an interval over tests needs two to vary.
MIN_TESTS_TO_NAME = 2
#: Tests of a series simulated to measure the bias of its model, at most, spread over the series
#: (:func:`spread_over`) and shared between the draws (:func:`_with_model_bias`): the bias is a property of
#: the model, the same on any tests; the noise of fewer is in its standard error, which u_model takes off
#: (:mod:`rocklab.diagnosis.estimation.bias`).
#: Above every series of the embedded campaign (29 tests at most); a series ten times longer would
#: otherwise simulate ten times the tests, and its job grow with the campaign.
MAX_BIAS_TESTS = 32


class _Head(TypedDict):
    """What every entry of a series starts with."""

    scope: str
    key: str
    boundary: str
    n_tests: int
    n_impacts: int
    base: BaseRun


def base_name(boundary: str) -> str:
    """The base model of a boundary condition, in words."""
    return (
        "Housner e_an,2s (Eq. 2), nominal alpha, released from rest at theta0"
        if boundary == Boundary.TWO_SIDED
        else "one-sided e_an,1s (Eq. 14), nominal alpha, released from rest at theta0"
    )


def not_identifiable(tests: Sequence[MeasuredTest], named: Collection[str] = ()) -> dict[str, str]:
    """The causes of the catalogue that the design of a series cannot carry, and why.

    Each cause says where the tests cannot tell it from the noise or from
    another cause whatever its size (:attr:`rocklab.diagnosis.causes.Cause.not_identifiable`:
    a drift between three tests, a viscous loss on short flights only); its
    absence from the verdict is then no evidence against it.  A rule of the
    design, known before any fit.

    Parameters
    ----------
    tests : list of MeasuredTest
        The tests of the series that the diagnosis uses (two impacts or more).
    named : iterable of str
        The causes the series names: those are carried, whatever the rule says.

    Returns
    -------
    dict
        Cause -> why, in words; empty where every cause of the boundary can be named.
    """
    ob = observe(tests)
    causes = catalogue.for_boundary(tests[0].boundary, families=True)
    out = {}
    for c in causes:
        why = c.not_identifiable(ob) if c.not_identifiable is not None and c.name not in named else ""
        if why:
            out[c.name] = why
    return out


def unnamed_estimates(problem: WallProblem, sel: Selection, fits: Fits) -> dict[str, dict[str, float]]:
    """The parameters of each candidate a series does not name whose signature its data carry.

    Its fit with the chosen model (``sel``, the selection with its ``fits``),
    where the selection made one: what the series says of the cause's size
    where it lacked the evidence to name it (a one-sided wall of eight
    impacts whose flights give alpha_r/alpha = 0.729 and whose fit says
    0.7299, short of the held-out test on three tests).  A boundary condition
    pools its series there rather than at the null value
    (:func:`rocklab.diagnosis.pooling.diagnose_boundary`).  A candidate whose
    signature is absent has none: the data show no sign of it; nor one with
    a parameter at a bound: the data did not fix it.
    """
    named = tuple(sel["effects"])
    out = {}
    for x in problem.candidates(True):
        if x in named or not supported(problem.signature, x):
            continue
        f = fits.get(problem.combine(named, x))  # type: ignore[arg-type]  # None, where x cannot join: no fit
        if f is None:
            continue
        own = [q for q in catalogue.by_name(x).params if q.name in f.values]
        tol = [1e-6 * (q.upper - q.lower) for q in own]
        if own and all(q.lower + t < f.values[q.name] < q.upper - t for q, t in zip(own, tol)):
            out[x] = {q.name: float(f.values[q.name]) for q in own}
    return out


def unnamed_standard_errors(
    problem: WallProblem, sel: Selection, fits: Fits, unnamed: Mapping[str, Mapping[str, float]]
) -> dict[str, dict[str, float]]:
    """The statistical standard errors of :func:`unnamed_estimates` [each parameter's unit].

    The cluster-robust (by test) sandwich of the fit that gave each estimate,
    linearised at it (:func:`~rocklab.diagnosis.estimation.resampling.sandwich_errors`,
    as a named cause's interval is where the tests are too few to resample):
    an unnamed estimate was never resampled, and the boundary's
    random-effects mean weighs every series' estimate by its error
    (:func:`rocklab.diagnosis.pooling.pooled_parameter`).  A direction the
    tests do not fix has no finite error and is left without one.
    """
    named = tuple(sel["effects"])
    every = problem.subset(np.arange(problem.n_tests))
    out = {}
    for x, values in unnamed.items():
        f = fits[problem.combine(named, x)]  # type: ignore[index]  # the fit unnamed_estimates read
        names, *_, A, y = linearised(problem, every, f)
        se = dict(zip(names, sandwich_errors(A, y)))
        finite = {k: float(se[k]) for k in values if np.isfinite(se.get(k, np.inf))}
        if finite:
            out[x] = finite
    return out


def diagnose_series(
    tests: Sequence[Any],
    *,
    key: str = "",
    scope: str = "series",
    n_boot: int = 40,
    n_history: int = 2,
    seed: int = 0,
    split_cap: int = SPLIT_CAP,
) -> SeriesDiagnosis:
    """Diagnosis of one series: base model, what it gets wrong, causes, gain.

    Parameters
    ----------
    tests : list of MeasuredTest or of record dicts (see :func:`measured_test`)
        All of one boundary condition.
    key, scope : str
        Identify the entry.
    n_boot : int
        Bootstrap resamples (of tests) for the 95 % intervals.
    n_history : int
        Tests simulated in time (:func:`rocklab.diagnosis.extended.simulate_measured`) for the
        RMS of theta/alpha.
    split_cap : int
        Tests above which the causes are chosen on this many and estimated on the others
        (:func:`rocklab.diagnosis.splitting.split_series`): the selection's steps (the causes, their
        evidence, the stand-ins and rivals, the changes over the tests, the unnamed estimates) on the
        first, the named causes' parameters, intervals and model bias on the second.

    Returns
    -------
    SeriesDiagnosis
        One entry of results/diagnosis.json; each finding carries
        ``n_tests``, the tests its interval rests on.  With fewer than
        :data:`MIN_TESTS_TO_NAME` tests of two impacts or more the entry
        compares the base model only, names no cause and says why in
        ``too_small``; otherwise ``not_identifiable`` (only where some cause
        is, :func:`not_identifiable`) names the causes its design cannot
        carry, whose absence from the verdict says nothing.
    """
    t0 = time.perf_counter()
    tests = [t if isinstance(t, MeasuredTest) else measured_test(t) for t in tests]
    tests = in_series_order([t for t in tests if t.n_impacts >= 2])
    if not tests:
        raise ValueError("a diagnosis needs tests with at least two impacts")
    boundary = tests[0].boundary
    if any(t.boundary != boundary for t in tests):
        raise ValueError("a diagnosis needs tests of one boundary condition")
    log.info(
        "%s %s (%s): %d tests of two impacts or more, %d impacts",
        scope,
        key,
        boundary,
        len(tests),
        sum(t.n_impacts for t in tests),
    )
    base_err = engineering_errors(tests, n_history=n_history)
    base = BaseRun(
        model=base_name(boundary),
        errors=base_err,
        alternatives={
            "two-sided e (Hogan 1992)": engineering_errors(tests, base="two-sided-e", n_history=0),
            "e = 0 (Liberatore & Spera 2003)": engineering_errors(tests, base="zero", n_history=0),
        }
        if boundary == Boundary.ONE_SIDED
        else None,
    )
    statement, off = what_is_wrong(base_err, "the simulation")
    log.info("base model: %s", statement)
    head: _Head = {
        "scope": scope,
        "key": key,
        "boundary": boundary,
        "n_tests": len(tests),
        "n_impacts": int(sum(t.n_impacts for t in tests)),
        "base": base,
    }
    if len(tests) < MIN_TESTS_TO_NAME:
        why = (
            f"one test: nothing varies between tests to give an interval ({MIN_TESTS_TO_NAME} tests at least), "
            "and a cause is named only where the interval of its parameter clears its null value"
        )
        log.warning("%s %s is too small to name a cause: %s", scope, key, why)
        return SeriesDiagnosis(**head, what_is_wrong=statement, too_small=why, sample_test=_sample_test(tests))
    chosen, rest = split_series(tests, split_cap)
    split = len(chosen) < len(tests)
    if split:
        log.info("%s %s: causes chosen on %d tests, estimated on the %d others", scope, key, len(chosen), len(rest))
    problem = WallProblem(chosen)
    sig = problem.signature
    fits: Fits = {}
    sel = select_effects(problem, signature=sig, n_boot=n_boot, seed=seed, fits=fits)
    sel = beyond_the_catalogue(problem, sel, signature=sig, n_boot=n_boot, seed=seed, fits=fits)
    # the parameters and intervals of a split series rest on the tests that did not choose its model
    est = estimated(WallProblem(rest), sel, n_boot=n_boot, seed=seed) if split else sel
    effects, values = sel["effects"], est["fit"].values
    findings = []
    for eff in effects:
        own = [q.name for q in catalogue.by_name(eff).params]
        st = sel["steps"][eff]
        cause = catalogue.by_name(eff)
        findings.append(
            Finding(
                effect=eff,
                params={k: values[k] for k in own},
                ci95={k: cast("list[Number]", est["ci"][k]) for k in own if k in est["ci"]},
                n_tests=len(rest),
                evidence={
                    "signature": sig.get(eff, {}).get("text", ""),
                    "fit": f"held-out deviance per observation lowered by {st['gain']:.3g} "
                    f"(standard error {st['se']:.2g}), dBIC = {st['dbic']:.1f}",
                },
                error_heldout=heldout_means(st["heldout"]),
                gain=heldout_gain(sel["base"], st["heldout"], st["gain"]),
                curve=cause.curve(tests, values, sel["catalogue"]["fit"].values)
                if cause.curve is not None and "catalogue" in sel
                else None,
                **discovery(problem, eff, est),
            )
        )
    # a cause selected has its paired deviance gain
    findings.sort(key=lambda f: -(f.gain["deviance_per_obs"] or 0.0))
    # the causes estimated once the chosen model is known, from what it leaves
    structure = list(sel["structure"])
    ext, ext_values = list(effects), dict(values)
    for cause in problem.after_selection:
        # a cause estimated after selection says what the model leaves for it, and estimates itself
        assert cause.unexplained is not None and cause.estimate is not None
        mp = model_params(rest, effects, values)
        left = problem.left_for(effects, sel["fit"].values)[cause.name]
        found = cause.estimate(rest, mp, seed=seed) if left else None
        log.info("%s: %s; %s", cause.name, "; ".join(map(str, left)) or "nothing left for it", _estimated(left, found))
        if found is not None and found["named"]:
            structure = [st for st in structure if st not in left]
            findings.append(found["finding"])
            ext.append(cause.name)
            ext_values.update(found["values"])
    bias, draws = _with_model_bias(rest, findings, est, ext, ext_values, seed)
    dof = _with_systematic(findings, est, bias.get("u_model", {}), draws)
    params = {q.name: q for f in findings for q in catalogue.by_name(f.effect).params}
    verdict_intervals(findings, params, {f.effect: cast(int, f.n_tests) for f in findings}, dof=dof)
    blind = not_identifiable(tests, [f.effect for f in findings])
    # a cause the design cannot identify is never named, and a rival these tests cannot tell from a named
    # cause was never tested against it: a named cause whose effect either could produce is named with
    # that caveat, not with confidence; a rival the data prefer is a form the selection missed
    caveats = stand_ins(problem, sel, blind, fits=fits)
    rival, preferred = rivals(problem, sel, sig, fits=fits)
    structure += preferred
    changes = within_series(problem, sel, findings, [t.test_id for t in chosen], fits, seed)
    # a change of a candidate the selection turned down: the tests are not one wall state, and the
    # verdict that pools them is no explanation of the series
    structure += [moved(c) for c in changes if c.kind is not ChangeKind.NONE and c.effect not in sel["effects"]]
    unexplained = bool(structure) and not sel["weak"]
    if not findings and not unexplained and not off:
        verdict_text = "the base model explains the data within the noise"
    elif not findings and not unexplained:
        verdict_text = "none of the candidate causes is carried by the data"
    else:
        verdict_text = ""
    for y, xs in rival.items():
        caveats[y] = caveats.get(y, {}) | xs
    for y, xs in caveats.items():
        next(f for f in findings if f.effect == y).may_stand_in_for = xs
    listed = "catalogue" in sel
    unnamed = unnamed_estimates(problem, sel, fits)
    unnamed_se = unnamed_standard_errors(problem, sel, fits, unnamed)
    ext_err = engineering_errors(tests, ext, ext_values, n_history=n_history) if ext else None
    entry = SeriesDiagnosis(
        **head,
        n_tests_selection=len(chosen) if split else None,
        n_tests_estimation=len(rest) if split else None,
        what_is_wrong=(verdict_text + ": " if verdict_text else "") + statement,
        verdict=[f.effect for f in findings],
        not_identifiable=blind or None,
        unexplained=unexplained,
        residual_structure=structure,
        findings=findings,
        changes=changes or None,
        listed_verdict=sel["catalogue"]["effects"] if listed else None,
        listed_params=cast("dict[str, Number]", sel["catalogue"]["fit"].values) if listed else None,
        weak_evidence=sentences({k: v["reason"] for k, v in sel["weak"].items()}),
        rejected=sentences(sel["rejected"]),
        signatures={k: v["text"] for k, v in sig.items()},
        unnamed_estimates=unnamed or None,
        unnamed_se=unnamed_se or None,
        heldout=HeldOut(base=heldout_means(sel["base"]), model=heldout_means(sel["final"])),
        model_bias=bias or None,
        extended=SeriesExtended(
            effects=ext,
            params=cast("dict[str, Number]", ext_values),
            errors=ext_err,
            statement=what_is_wrong(ext_err, "the extended model")[0],
        )
        if ext and ext_err is not None
        else None,
        sample_test=_sample_test(tests),
    )
    log.info(
        "%s %s: verdict %s%s in %.1f s",
        scope,
        key,
        ", ".join(entry.verdict) or "none",
        "; unexplained structure" if unexplained else "",
        time.perf_counter() - t0,
    )
    return entry


def within_series(
    problem: WallProblem,
    sel: Selection,
    findings: list[Finding],
    test_ids: Sequence[str],
    fits: Fits,
    seed: int,
) -> list[SeriesChange]:
    """The parameters of the selected causes, and of the candidates a change between tests may have
    turned down, tested for a change over the series' tests before the boundary condition pools them
    (:func:`rocklab.diagnosis.estimation.change.changes_over_tests`).

    The selected causes are tested in the selection's fit; a candidate whose signature the data carry
    but that the held-out test or the bootstrap turned down in the fit of the chosen model with it (a
    rocking edge crushed half-way: its fit predicts neither half's tests left out, and nothing is
    named).  A finding whose parameter changes is flagged (``changes_within``): its value is a mean over
    the wall states the series went through, and its law is still named.  No cold fit: the cost is a
    linearisation per fit tested, and two warm refits where a change point is found.
    """
    named = tuple(sel["effects"])
    tested = {eff: sel["fit"] for eff in named}
    for x, why in sel["rejected"].items():
        ext = problem.combine(named, x) if x not in named else None
        if why.by in (RejectedBy.HELD_OUT, RejectedBy.INTERVAL) and ext is not None and ext in fits:
            tested[x] = fits[ext]
    changes = changes_over_tests(problem, tested, test_ids=test_ids, seed=seed)
    for f in findings:
        changed = [c.parameter for c in changes if c.effect == f.effect and c.kind is not ChangeKind.NONE]
        f.changes_within = changed or None
    return changes


def moved(change: SeriesChange) -> Structure:
    """A change of a parameter over the tests as structure the verdict leaves, in words."""
    # a change found is always sized (rocklab.diagnosis.estimation.change)
    assert change.before is not None and change.after is not None and change.ci95_size is not None
    return Structure(change.effect, f"{change.effect}: {change}: the tests are not one wall state")


def _with_model_bias(
    tests: Sequence[MeasuredTest],
    findings: list[Finding],
    sel: Selection,
    ext: list[str],
    values: dict[str, float],
    seed: int,
) -> tuple[ModelBias, dict[str, int]]:
    """The bias of the model, measured on the tests simulated at the extended model
    (:mod:`rocklab.diagnosis.estimation.bias`): the selected causes fitted again, a cause estimated
    after selection (a stop) estimated again, on each of :data:`~rocklab.diagnosis.estimation.bias.BIAS_DRAWS`
    draws.

    The draws share the tests simulated (at most :data:`MAX_BIAS_TESTS`, spread over the series), each
    test simulated once, in one draw, with its own noise (seed + the draw): the simulation costs what one
    draw of them all did, and a draw has two tests at least (fewer draws of a short series).

    Returns
    -------
    bias : dict
        ``b`` (the mean over the draws) and ``u_model`` by parameter, or ``not_measured`` (why); empty
        without a selected cause.
    draws : dict
        Parameter -> the draws its ``u_model`` rests on, its degrees of freedom.
    """
    if not sel["effects"]:
        return {}, {}
    picked = spread_over(tests, MAX_BIAS_TESTS)
    n_draws = max(1, min(BIAS_DRAWS, len(picked) // 2))
    try:
        simulated = [simulated_tests(picked[r::n_draws], ext, values, seed=seed + r) for r in range(n_draws)]
        simulated = [s for s in simulated if len(s) >= 2]
        if not simulated:
            raise ValueError("no draw of two simulated tests of two impacts or more")
    except (NotImplementedError, ValueError) as err:
        log.warning("bias of the model not measured: %s", err)
        return {"not_measured": str(err)}, {}
    u, b = model_bias([WallProblem(s) for s in simulated], sel["fit"])
    draws = dict.fromkeys(u, len(simulated))
    # a cause estimated after selection, estimated again on each draw: its bias, net of the noise its
    # interval on the draw's tests gives (systematic.standard_error)
    for f in findings:
        cause = catalogue.by_name(f.effect)
        if f.effect in sel["effects"] or cause.estimate is None:
            continue
        assert f.n_tests is not None
        found: dict[str, list[tuple[float, float]]] = {}
        for sim in simulated:
            mp = model_params(sim, sel["effects"], sel["fit"].values)
            again = cause.estimate(sim, mp, seed=seed)
            for k, ci in f.ci95.items() if again is not None else ():
                # the draw's own interval, on its units (the tests that stop) less one
                own = again["finding"].ci95.get(k) or ci
                df = ((again["finding"].n_tests or len(sim)) if own is not ci else f.n_tests) - 1
                se = standard_error(cast("list[float]", own), df=max(df, 1))
                found.setdefault(k, []).append((float(again["values"][k] - f.params[k]), se))
        for k, pairs in found.items():
            bk, sek = np.array(pairs).T
            b[k], u[k], draws[k] = float(bk.mean()), float(net_of_noise(bk, sek)), len(pairs)
    return {"b": b, "u_model": u}, draws


def _with_systematic(
    findings: list[Finding], sel: Selection, u_model: Mapping[str, float], draws: Mapping[str, int]
) -> dict[str, dict[str, float]]:
    """Widen each finding's statistical intervals by its systematic parts, the pulls of the residual
    groups (a selected cause's, ``sel["ci"]``) and the model's bias ``u_model`` on its ``draws``, added
    by Welch-Satterthwaite (:func:`rocklab.diagnosis.estimation.systematic.widened`); set
    ``u_systematic``, their sum in quadrature.

    Returns
    -------
    dict
        Effect -> parameter -> the effective degrees of freedom of its interval (the verdict's
        simultaneous intervals take their quantiles on them).
    """
    ci_all = sel["ci"]
    dof: dict[str, dict[str, float]] = {}
    for f in findings:
        assert f.n_tests is not None
        selected = f.effect in sel["effects"]
        bounds = {q.name: q for q in catalogue.by_name(f.effect).params}
        f.u_systematic = {}
        for k, ci in f.ci95.items():
            # the findings being made hold numbers (a file's None is a number not finite)
            stat = ci_all.statistical.get(k, ci) if selected else cast("list[float]", ci)
            df = ci_all.df if selected else max(f.n_tests - 1, 1)
            u_p, nu_p = (ci_all.u_sys.get(k, 0.0), ci_all.dof_sys.get(k, np.inf)) if selected else (0.0, np.inf)
            u_m, nu_m = u_model.get(k, 0.0), draws.get(k, np.inf)
            u, nu = float(np.hypot(u_p, u_m)), effective_dof([u_p, u_m], [nu_p, nu_m])
            x0, q = cast(float, f.params[k]), bounds[k]
            f.ci95[k] = cast(
                "list[Number]", widened(cast("list[float]", stat), x0, q.lower, q.upper, u, df=df, df_sys=nu)
            )
            f.u_systematic[k] = u
            dof.setdefault(f.effect, {})[k] = widened_dof(cast("list[float]", stat), x0, u, df, nu)
    return dof


def _estimated(left: list[Structure], found: StopEstimate | None) -> str:
    """What the estimate of a cause after selection gave, in words (the log)."""
    if not left:
        return "not estimated"
    if found is None:
        return "no estimate"
    return f"{'named' if found['named'] else 'not named'}: {found['finding'].evidence['fit']}"


def _sample_test(tests: Sequence[MeasuredTest]) -> str:
    """The test of most impacts (the one the figures draw)."""
    return tests[int(np.argmax([t.n_impacts for t in tests]))].test_id


def diagnose_records(
    records: Iterable[MeasuredTest | Mapping[str, Any]],
    key: object,
    *,
    n_boot: int = 40,
    n_history: int = 2,
    seed: int = 0,
) -> SeriesDiagnosis | None:
    """:func:`diagnose_series` of one series' records, or None when none of its
    tests has two impacts or more (nothing to compare a model with).

    A diagnosis that raises does not stop the job: the series' entry says it did
    not finish (:func:`not_finished`), and the campaign's other series run on.
    """
    tests = [r if isinstance(r, MeasuredTest) else measured_test(r) for r in records]
    tests = [t for t in tests if t.n_impacts >= 2]
    if not tests:
        log.warning("series %s: no test with two impacts or more, nothing to diagnose", key)
        return None
    try:
        return diagnose_series(tests, key=str(key), n_boot=n_boot, n_history=n_history, seed=seed)
    except Exception as err:  # any failure of one series' diagnosis: reported in its entry
        return not_finished(tests, str(key), err)


def not_finished(tests: Sequence[MeasuredTest], key: str, err: BaseException) -> SeriesDiagnosis:
    """The entry of a series whose diagnosis raised ``err``: its tests and impacts and the exception
    (``not_finished``, its type and message), logged as a warning with its traceback."""
    reason = f"{type(err).__name__}: {err}"
    log.warning("series %s: the diagnosis did not finish (%s)", key, reason, exc_info=err)
    return SeriesDiagnosis(
        scope="series",
        key=key,
        boundary=tests[0].boundary,
        n_tests=len(tests),
        n_impacts=int(sum(t.n_impacts for t in tests)),
        not_finished=reason,
    )
