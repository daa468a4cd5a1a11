"""Which causes the data carry: greedy forward selection with removal tests.

A candidate enters on the information criterion, the paired held-out
deviance (:mod:`rocklab.diagnosis.estimation.resampling`) and a bootstrap
interval clear of its null (:func:`select_effects`); where the listed causes
leave structure (:mod:`rocklab.diagnosis.estimation.structure`) the
selection is run again with the generalised families
(:func:`beyond_the_catalogue`).  A named cause that a cause the design
cannot identify (:func:`stand_ins`) or a rival the series cannot tell from it
(:func:`rivals`) may stand in for is named with that caveat.

Size: the selection's steps (entry, removal, the families, the caveats) share
their rejections and fits; apart they would pass them back and forth.
"""

from __future__ import annotations

import enum
import logging
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NotRequired, TypeAlias, TypedDict, cast

import numpy as np

from rocklab._imports import lazy_module
from rocklab.diagnosis.estimation.fitting import Fit, Fits, fit
from rocklab.diagnosis.estimation.problem import Problem
from rocklab.diagnosis.estimation.resampling import Intervals, heldout, paired_difference, parameter_intervals
from rocklab.diagnosis.estimation.structure import structure
from rocklab.diagnosis.result import Structure
from rocklab.inference.intervals import MIN_BOOTSTRAP

if TYPE_CHECKING:
    from rocklab.diagnosis.causes import Signature

stats = lazy_module("scipy.stats")

log = logging.getLogger(__name__)

#: BIC drop that is strong evidence for one model over another (Kass & Raftery 1995): what a cause needs to enter.
BIC_MARGIN = 10.0


class RejectedBy(enum.Enum):
    """The step of the selection that turned a candidate down; its value is the sentence's template."""

    DESIGN = "the design cannot identify it ({why})"
    SIGNATURE = "its signature in the data is absent"
    INFORMATION_CRITERION = "BIC {dbic:+.1f}"
    HELD_OUT = "held-out deviance gain {gain:.3g} within the noise (standard error {se:.2g})"
    INTERVAL = "95% interval within the smallest effect worth naming of its null value"
    CARRIED = "carried by {by} (removing it costs {loss:.3g} +- {se:.2g} held out)"


@dataclass(frozen=True)
class Rejection:
    """Why the selection turned a candidate down: the step (:class:`RejectedBy`) and the numbers its
    sentence quotes.  Decisions read ``by``; only the files and the pages read :attr:`sentence`."""

    by: RejectedBy
    why: str = ""
    dbic: float = math.nan
    gain: float = math.nan
    se: float = math.nan
    loss: float = math.nan
    carried_by: str = ""

    @property
    def sentence(self) -> str:
        """The reason as results/diagnosis.json and the pages give it."""
        return self.by.value.format(
            why=self.why, dbic=self.dbic, gain=self.gain, se=self.se, loss=self.loss, by=self.carried_by
        )


class Step(TypedDict):
    """A cause's entry into a selection: the held-out result after it, its paired gain and its BIC."""

    heldout: dict[str, np.ndarray]
    gain: float
    se: float
    dbic: float


class Weak(TypedDict):
    """A candidate turned down that would remove the structure left: its parameters and why it was."""

    params: dict[str, float]
    reason: Rejection | None


class Selection(TypedDict):
    """The causes a selection names and its evidence (:func:`select_effects`); ``catalogue``: the selection
    of the listed causes where one beyond them replaced it (:func:`beyond_the_catalogue`)."""

    effects: list[str]
    fit: Fit
    ci: Intervals
    base: dict[str, np.ndarray]
    final: dict[str, np.ndarray]
    steps: dict[str, Step]
    rejected: dict[str, Rejection]
    structure: list[Structure]
    weak: dict[str, Weak]
    catalogue: NotRequired[Selection]


#: A candidate of a stage: its BIC against the current model, its name, its causes with the current ones,
#: their fit.
Candidate: TypeAlias = tuple[float, str, tuple[str, ...], Fit]


def sentence_of(rejection: Rejection | None) -> str:
    """The sentence of a rejection as the files give it, "" for none (a weak candidate never turned down)."""
    return rejection.sentence if rejection is not None else ""


def sentences(rejected: Mapping[str, Rejection | None]) -> dict[str, str]:
    """Cause -> :func:`sentence_of` its rejection, of a selection's ``rejected`` or weak reasons."""
    return {k: sentence_of(r) for k, r in rejected.items()}


def supported(signature: Mapping[str, Signature], cause: str) -> bool:
    """Whether the data carry the signature of ``cause`` (``signature``: cause -> its signature dict,
    :func:`rocklab.diagnosis.catalogue.signatures`); a cause without a signature is never held back by one."""
    return signature.get(cause, {}).get("supports", True)


def _improves(d: np.ndarray) -> bool:
    """Whether paired per-test improvements ``d`` are beyond the noise.

    The mean exceeds twice its standard error, or every one of at least five
    tests improved (one-sided sign test, p <= 1/32): with few tests that
    differ in how much they gain, the standard error alone is too strict.
    With fewer than :data:`~rocklab.inference.intervals.MIN_BOOTSTRAP`
    tests the standard error rests on n - 1 degrees of freedom: the mean
    exceeds Student's t quantile of the same one-sided level (97.7 %, that
    of two normal standard errors) times it, 4.5 for three tests.
    """
    d = d[np.isfinite(d)]
    gain, se = paired_difference(d)
    if d.size < MIN_BOOTSTRAP:
        return d.size >= 2 and gain > float(stats.t.ppf(stats.norm.cdf(2.0), d.size - 1)) * se
    return gain > 2 * se or bool(np.all(d > 0))


def heldout_of(problem: Problem[Any], fitted: Fit) -> dict[str, np.ndarray]:
    """:func:`~rocklab.diagnosis.estimation.resampling.heldout` of ``fitted`` (a fit of all the
    problem's tests), made once a fit: the selections on one problem share their fits, and the second
    (the families, :func:`beyond_the_catalogue`) and the rivals meet the first one's models again."""
    if fitted.heldout is None:
        fitted.heldout = heldout(problem, fitted.ext, fitted)
    return fitted.heldout


def _null_excluded(problem: Problem[Any], effect: str, ci: Mapping[str, Sequence[float]]) -> bool:
    """Whether some parameter of ``effect`` stays clear of its null by a practical margin.

    A generalised family (a cause with a ``family``) is judged on the
    parameters its listed member lacks, the form it adds: where those sit at
    their null the fit is the listed member, which is a candidate of its own.
    Its shared parameters move with its own ones (the rounding of a hinge
    moves the angle of the flights released at alpha_r), so a form too small
    to name could otherwise carry the family in by a shared parameter.
    """
    by_name = {c.name: c for c in problem.causes}
    member = getattr(by_name[effect], "family", None)
    shared = {q.name for q in by_name[member].params} if member in by_name else set()
    for q in problem.params((effect,)):
        if q.name in shared:
            continue
        if q.practical is not None and q.name in ci:
            lo, hi = ci[q.name]
            if lo > q.null + q.practical or hi < q.null - q.practical:
                return True
    return False


def _in_order(cands: list[Candidate], family_of: Mapping[str, str | None], bic_margin: float) -> list[Candidate]:
    """The candidates (dbic, name, ...) in the held-out test's order: by BIC, but a family right after its
    listed member where it does not beat it by the margin a cause needs to enter (the listed law, the
    paper's, is not displaced by a flexible one that fits as well: a law of the speed marginally ahead of
    Eq. 17 on the embedded wall 3a, two-sided)."""
    listed = {eff: dbic for dbic, eff, *_ in cands}

    def key(cand: Candidate) -> tuple[float, int]:
        member = family_of.get(cand[1])
        if member in listed and cand[0] > listed[member] - bic_margin:
            return (listed[member], 1)
        return (cand[0], 0)

    return sorted(cands, key=key)


def select_effects(
    problem: Problem[Any],
    *,
    signature: Mapping[str, Signature] | None = None,
    n_boot: int = 40,
    max_effects: int = 4,
    seed: int = 0,
    bic_margin: float = BIC_MARGIN,
    families: bool = False,
    fits: Fits | None = None,
) -> Selection:
    """Greedy forward selection of the causes the data carry, with removal tests.

    Parameters
    ----------
    problem : Problem
    signature : dict, optional
        effect -> {"supports": bool, ...}; an effect whose signature does not
        support it is never named, one its design cannot identify
        (``not_identifiable``: why) included.
    n_boot : int
        Bootstrap resamples for the 95 % intervals.
    bic_margin : float
        BIC must drop by more than this (strong evidence, Kass & Raftery 1995).
    families : bool
        Candidates include the generalised families of the problem's causes
        (those with a ``family``): the search beyond the catalogue.
    fits : dict, optional
        Fits by causes, shared with an earlier selection on the same problem.

    Returns
    -------
    dict
        ``effects`` (chosen, in order of entry), ``fit`` (:class:`~rocklab.diagnosis.estimation.fitting.Fit`),
        ``ci`` (parameter intervals), ``base``/``final`` held-out results,
        ``steps`` (the held-out result after each entry), ``rejected``
        (effect -> :class:`Rejection`), ``structure`` (what the chosen model leaves) and
        ``weak`` (candidates turned down that would remove all of it, none that did worse held out:
        effect -> ``params`` and ``reason``, its :class:`Rejection` or None).
    """
    all_idx = np.arange(problem.n_tests)
    signature = signature or {}
    fits = {} if fits is None else fits

    def fit_of(ext: tuple[str, ...]) -> Fit:
        # a fit is deterministic: the rounds, the removals and the weak-evidence
        # pass meet the same models again
        if ext not in fits:
            t0 = time.perf_counter()
            f = fits[ext] = fit(problem, all_idx, ext)
            log.info(
                "fit %s: %s; -2 log L %.1f, BIC %.1f on %d observations; %d passes, %s in %.1f s",
                "+".join(ext) or "base model",
                ", ".join(f"{k} = {v:.4g}" for k, v in f.values.items()) or "no parameter",
                f.m2ll,
                f.bic,
                f.n_obs,
                f.passes,
                "converged" if f.converged else "not converged",
                time.perf_counter() - t0,
            )
        return fits[ext]

    candidates = problem.candidates(families)
    family_of = {c.name: c.family for c in problem.causes if getattr(c, "family", None)}
    log.info("selection over %d tests, candidates %s", problem.n_tests, ", ".join(candidates))
    current: tuple[str, ...] = ()
    cur_fit = fit_of(current)
    cur_ho = heldout_of(problem, cur_fit)
    base_ho = cur_ho
    steps: dict[str, Step] = {}
    rejected: dict[str, Rejection] = {}
    ci = Intervals()
    # candidates that predicted the tests left out worse than the model they would join: no evidence for them
    worse_held_out = set()
    for stage in range(1, max_effects + 1):
        # candidates in the order of their information criterion; the held-out test and the
        # bootstrap, the costly steps, only until one passes
        cands = []
        for eff in candidates:
            ext = problem.combine(current, eff) if eff not in current else None
            if ext is None or ext == current or (eff in rejected and rejected[eff].by is RejectedBy.INTERVAL):
                continue
            if not supported(signature, eff):
                # never named without it: its fit, the costliest of all for a loss in flight, is not needed
                why = signature[eff].get("not_identifiable")
                rejected[eff] = Rejection(RejectedBy.DESIGN, why=why) if why else Rejection(RejectedBy.SIGNATURE)
                log.info("stage %d: %s rejected: %s", stage, eff, rejected[eff].sentence)
                continue
            f = fit_of(ext)
            dbic = f.bic - cur_fit.bic
            if dbic > -bic_margin:
                rejected[eff] = Rejection(RejectedBy.INFORMATION_CRITERION, dbic=dbic)
            else:
                cands.append((dbic, eff, ext, f))
                continue
            log.info("stage %d: %s rejected: %s", stage, eff, rejected[eff].sentence)
        cands = _in_order(cands, family_of, bic_margin)
        if cands:
            log.info(
                "stage %d: held-out test in the order of BIC until one passes: %s",
                stage,
                ", ".join(f"{eff} ({dbic:+.1f})" for dbic, eff, *_ in cands),
            )
        accepted = False
        for dbic, eff, ext, f in cands:
            ho = heldout_of(problem, f)
            d = cur_ho["deviance"] - ho["deviance"]
            gain, se = paired_difference(d)
            if not _improves(d):
                rejected[eff] = Rejection(RejectedBy.HELD_OUT, gain=gain, se=se)
                if gain <= 0:
                    worse_held_out.add(eff)
                else:
                    worse_held_out.discard(eff)
                log.info("stage %d: %s (BIC %+.1f) rejected: %s", stage, eff, dbic, rejected[eff].sentence)
                continue
            c = parameter_intervals(problem, f, n_boot=n_boot, seed=seed)
            if not _null_excluded(problem, eff, c):
                rejected[eff] = Rejection(RejectedBy.INTERVAL)
                log.info(
                    "stage %d: %s (BIC %+.1f, held-out gain %.3g) rejected: %s",
                    stage,
                    eff,
                    dbic,
                    gain,
                    rejected[eff].sentence,
                )
                continue
            rejected.pop(eff, None)
            current, cur_fit, cur_ho, ci = ext, f, ho, c
            steps[eff] = {"heldout": ho, "gain": gain, "se": se, "dbic": dbic}
            log.info(
                "stage %d: %s accepted: BIC %+.1f, held-out deviance gain %.3g (standard error %.2g)",
                stage,
                eff,
                dbic,
                gain,
                se,
            )
            accepted = True
            break
        if not accepted:
            log.info(
                "stage %d: no candidate accepted; selection stops at %s", stage, "+".join(current) or "the base model"
            )
            break
        # removal: a cause that entered earlier may be carried by the new one
        for old in [c for c in current if c != eff and c in steps]:
            ext = tuple(c for c in current if c != old)
            f = fit_of(ext)
            ho = heldout_of(problem, f)
            loss, se = paired_difference(ho["deviance"] - cur_ho["deviance"])
            if not _improves(ho["deviance"] - cur_ho["deviance"]) or f.bic - cur_fit.bic < bic_margin:
                rejected[old] = Rejection(RejectedBy.CARRIED, loss=loss, se=se, carried_by=eff)
                log.info("stage %d: %s removed: %s", stage, old, rejected[old].sentence)
                steps.pop(old)
                current, cur_fit, cur_ho = ext, f, ho
                ci = parameter_intervals(problem, f, n_boot=n_boot, seed=seed) if ext else Intervals()
    found = structure(problem, all_idx, current, cur_fit.values)
    # structure that a candidate turned down by the held-out test or the bootstrap would remove
    # is weak evidence for it, not something outside the catalogue; one that did worse held out
    # removes it by fitting the noise of the tests it was fitted on, and is no evidence
    weak: dict[str, Weak] = {}
    if found:
        for eff in candidates:
            if eff in worse_held_out:
                continue
            ext = problem.combine(current, eff) if eff not in current else None
            if ext is not None and ext != current and supported(signature, eff):
                f = fit_of(ext)
                if not structure(problem, all_idx, ext, f.values):
                    weak[eff] = {"params": f.values, "reason": rejected.get(eff)}
    log.info(
        "chosen: %s; structure left: %s; weak evidence for: %s",
        "+".join(current) or "the base model",
        "; ".join(map(str, found)) or "none",
        ", ".join(weak) or "none",
    )
    return {
        "effects": list(current),
        "fit": cur_fit,
        "ci": ci,
        "base": base_ho,
        "final": cur_ho,
        "steps": steps,
        "rejected": rejected,
        "structure": found,
        "weak": weak,
    }


def _wrong_forms(
    problem: Problem[Any],
    sel: Selection,
    signature: Mapping[str, Signature],
    fits: Fits,
    bic_margin: float = BIC_MARGIN,
) -> list[Structure]:
    """Statements that a named listed cause has the wrong form: its family fits better in its place.

    The structure tests look for a pattern in the residual groups and lack
    the power to see a wrong form on a short series (a restitution linear in
    the impact speed read as Eq. 17 on three tests), where the information
    criterion already is decisive: the family in the listed member's place
    lowers the BIC by more than the strong evidence a cause needs to enter.
    """
    current = tuple(sel["effects"])
    out = []
    for c in problem.causes:
        # a family its signature does not support is never named: no search for it
        if getattr(c, "family", None) not in current or not supported(signature, c.name):
            continue
        assert c.family is not None
        dbic = _in_place_of(problem, sel, c.name, c.family, fits)
        if dbic is not None and dbic < -bic_margin:
            out.append(Structure(c.name, f"{c.name} in place of {c.family} lowers the BIC by {-dbic:.0f}"))
    return out


def beyond_the_catalogue(
    problem: Problem[Any],
    sel: Selection,
    *,
    signature: Mapping[str, Signature],
    n_boot: int = 40,
    seed: int = 0,
    fits: Fits | None = None,
) -> Selection:
    """The selection with the generalised families, where the listed causes leave structure (issue 12).

    Where ``sel`` (a selection of the listed causes,
    :func:`select_effects`) leaves structure in the residual groups (not
    only what the stage after selection addresses, :meth:`Problem.extra_structure`)
    that no candidate turned down by the held-out test or the bootstrap would remove (one turned
    down by the information criterion removes it only with a worse fit), or where a family fits decisively
    better than its named listed member (:func:`_wrong_forms`), the selection is run again with the
    families of the problem's causes among the candidates (the same engine:
    information criterion, signature, held-out deviance, bootstrap).  When
    it names a family, it replaces ``sel``, with ``catalogue`` (the
    selection of the listed causes) kept beside it; otherwise ``sel`` stands,
    with the families that would remove the structure but fall short of the
    evidence to be named added to its weak evidence.
    """
    # weak evidence for a listed cause that the held-out test or the bootstrap turned down stands; one the
    # information criterion turned down removes the structure only with a worse fit: a form it lacks
    if any(w["reason"] is None or w["reason"].by is not RejectedBy.INFORMATION_CRITERION for w in sel["weak"].values()):
        return sel
    if problem.candidates(True) == problem.candidates():
        return sel
    # structure of the residual groups: what the stage after selection addresses (a stop) is not the families'
    every = problem.subset(np.arange(problem.n_tests))
    after = problem.extra_structure(every, tuple(sel["effects"]), sel["fit"].values)
    fits = {} if fits is None else fits
    left = [st for st in sel["structure"] if st not in after] + _wrong_forms(problem, sel, signature, fits)
    if not left:
        return sel
    log.info(
        "structure left by the listed causes (%s): the generalised families are searched", "; ".join(map(str, left))
    )
    wide = select_effects(problem, signature=signature, n_boot=n_boot, seed=seed, families=True, fits=fits)
    families = set(problem.candidates(True)) - set(problem.candidates())
    named = [e for e in wide["effects"] if e in families]
    if not named:
        weak = {k: v for k, v in wide["weak"].items() if k in families}
        log.info(
            "no family named: %s",
            f"weak evidence for {', '.join(weak)}" if weak else "the structure stays unexplained",
        )
        return {**sel, "weak": {**sel["weak"], **weak}}
    log.info("discovered: %s", ", ".join(named))
    return {**wide, "catalogue": sel}


def stand_ins(
    problem: Problem[Any],
    sel: Selection,
    hidden: Mapping[str, str],
    *,
    fits: Fits | None = None,
    bic_margin: float = BIC_MARGIN,
) -> dict[str, dict[str, str]]:
    """The named causes that a cause the design cannot identify may stand in for.

    A cause the series' design cannot tell from the noise or from another
    cause (``hidden``: :func:`rocklab.diagnosis.series.not_identifiable`) is
    never named, so a named cause whose effect it could produce is named
    without the evidence to exclude it.  The catalogue's own models decide
    which, on this series: a named cause ``Y`` may stand in for ``X`` where
    the model with ``X`` in ``Y``'s place is not worse by the strong
    evidence a cause needs to enter (its BIC not above the chosen model's
    by ``bic_margin``).

    Parameters
    ----------
    problem : Problem
    sel : dict
        The selection (:func:`select_effects` or :func:`beyond_the_catalogue`).
    hidden : mapping
        Cause -> why the design cannot identify it.
    fits : dict, optional
        Fits by causes, shared with the selection.

    Returns
    -------
    dict
        Named cause -> {cause it may stand in for: why that one is not identifiable}; only causes that may.
    """
    fits = {} if fits is None else fits
    out: dict[str, dict[str, str]] = {}
    for x, why in hidden.items():
        if x not in problem.candidates(True):
            continue
        for y in sel["effects"]:
            dbic = _in_place_of(problem, sel, x, y, fits)
            if dbic is None:
                continue
            log.info("%s in place of %s: BIC %+.1f", x, y, dbic)
            if dbic < bic_margin:
                out.setdefault(y, {})[x] = why
    return out


def rivals(
    problem: Problem[Any],
    sel: Selection,
    signature: Mapping[str, Signature],
    *,
    fits: Fits | None = None,
    bic_margin: float = BIC_MARGIN,
) -> tuple[dict[str, dict[str, str]], list[Structure]]:
    """The named causes that a candidate the series cannot tell from them may stand in for.

    The selection tries the candidates in the order of their information
    criterion and names the first that passes the held-out test; a rival
    that fits almost as well is then never tested against it, and on a short
    series (six impacts over three tests, a restitution falling with the
    amplitude named as an instability angle that grows with it) the two are
    alike to the data.  A named cause ``Y`` may stand in for a candidate
    ``X`` whose signature the data carry where the model with ``X`` in
    ``Y``'s place is not worse by the strong evidence a cause needs to enter
    (its BIC within ``bic_margin`` of the chosen model's) and does not
    predict the held-out tests worse beyond the noise (the paired test of
    the selection).  A generalised family and its listed member are one
    cause in two forms (:func:`beyond_the_catalogue` decides between them)
    and are not each other's rivals.  Where ``X`` in ``Y``'s place is better
    by that evidence and predicts the held-out tests better beyond the noise,
    the data prefer it: a form the selection did not reach (a law of the speed
    whose closed form's signature is absent), which leaves the model's
    structure unexplained rather than a caveat on a confident name.

    Returns
    -------
    caveats : dict
        Named cause -> {rival: why}; only causes that have one.
    preferred : list of str
        The structure the rivals the data prefer leave: one line each.
    """
    fits = {} if fits is None else fits
    family = {c.name: getattr(c, "family", None) for c in problem.causes}
    named = tuple(sel["effects"])
    out: dict[str, dict[str, str]] = {}
    preferred: list[Structure] = []
    for y in named:
        for x in problem.candidates(True):
            if x in named or family.get(x) == y or family.get(y) == x or not supported(signature, x):
                continue
            dbic = _in_place_of(problem, sel, x, y, fits)
            if dbic is None or dbic >= bic_margin:
                continue
            ext = problem.combine(tuple(e for e in named if e != y), x)
            assert ext is not None
            d = heldout_of(problem, fits[ext])["deviance"] - sel["final"]["deviance"]
            if _improves(d):
                continue
            gain, se = paired_difference(d)
            numbers = (
                f"in its place the BIC is {dbic:+.1f} and the held-out deviance per observation {gain:+.3g} "
                f"(standard error {se:.2g}) on {problem.n_tests} tests"
            )
            if dbic <= -bic_margin and _improves(-d):
                out.setdefault(y, {})[x] = f"{numbers}: the data prefer it"
                preferred.append(
                    Structure(x, f"{x} in place of {y}: {numbers}, a better form the selection did not reach")
                )
                log.info("the data prefer %s in place of %s: %s", x, y, numbers)
            else:
                out.setdefault(y, {})[x] = f"{numbers}: these tests cannot tell them apart"
                log.info("%s may stand in for %s: %s", y, x, out[y][x])
    return out, preferred


def _nested_fit(problem: Problem[Any], ext: tuple[str, ...], x: str, fits: Fits) -> Fit:
    """The fit of ``ext``, where its cause ``x`` is not held at its null while a sub-model gives it an effect.

    The cold starts of :func:`~rocklab.diagnosis.estimation.fitting.fit`
    (nulls and the signatures' guesses) can end where another cause of
    ``ext`` has taken ``x``'s effect and holds it at its null (a lower angle
    with the viscous loss at zero, 90 BIC worse than the viscous loss
    alone).  Where ``x``'s parameters all end within the smallest effect
    worth naming of their nulls, each sub-model of ``ext`` with ``x`` and
    one cause fewer (fitted and kept in ``fits``) starts the fit again, the
    cause it lacks at its null, and the best end stands.
    """
    idx = np.arange(problem.n_tests)
    best = fits[ext] if ext in fits else fit(problem, idx, ext)
    own = [q for q in problem.params((x,)) if q.practical is not None and q.name in best.values]
    if own and all(abs(best.values[q.name] - q.null) <= cast(float, q.practical) for q in own):
        nulls = {q.name: q.null for q in problem.params(ext)}
        for c in (c for c in ext if c != x):
            sub = tuple(e for e in ext if e != c)
            if sub not in fits:
                fits[sub] = fit(problem, idx, sub)
            warm = fit(problem, idx, ext, x0=nulls | {k: v for k, v in fits[sub].values.items() if k in nulls})
            if warm.bic < best.bic:
                best = warm
    fits[ext] = best
    return best


def _in_place_of(problem: Problem[Any], sel: Selection, x: str, y: str, fits: Fits) -> float | None:
    """BIC of the selection's model with the cause ``x`` in place of its cause ``y``, less the model's;
    None where ``x`` cannot join the others (``fits``: shared with the selection)."""
    ext = problem.combine(tuple(e for e in sel["effects"] if e != y), x)
    if ext is None:
        return None
    return _nested_fit(problem, ext, x, fits).bic - sel["fit"].bic
