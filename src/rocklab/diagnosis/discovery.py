"""Discovery reporting: whether a finding's form was discovered (a generalised family) rather than listed.

What a family of :mod:`rocklab.diagnosis.catalogue` gives beside the listed
causes: the closed form of the library it reduces to, and its paired
held-out gain against the base model and the best listed model, for the
findings of a series (:func:`discovery`) and for the report of a family
fitted whether named or not (:func:`family_against_listed`, the limestone
blocks).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, TypedDict, cast

import numpy as np

from rocklab.diagnosis.estimation import Problem, fit, heldout, paired_gain, parameter_intervals
from rocklab.diagnosis.result import FamilyComparison

if TYPE_CHECKING:
    from rocklab.diagnosis.estimation.fitting import Fits
    from rocklab.diagnosis.estimation.selection import Selection
    from rocklab.diagnosis.result import Number


class Discovery(TypedDict, total=False):
    """The fields of a finding that say whether its form was discovered (:func:`discovery`)."""

    discovered: bool
    family: str
    reduces_to: str
    best_listed: list[str]
    heldout_gain: dict[str, float | None]


def family_against_listed(
    problem: Problem[Any],
    family: str,
    sel: Selection,
    *,
    n_boot: int = 40,
    seed: int = 0,
    fits: Fits | None = None,
) -> FamilyComparison:
    """A family fitted whether named or not, against the base model and the best listed cause.

    The fit of ``family`` on all tests, its bootstrap intervals, the closed
    form it reduces to, and its paired held-out deviance gain per
    observation over the base model and over the single listed cause of
    lowest BIC (the best member of the catalogue), for a report of what a
    form outside the catalogue would give (the limestone blocks).
    """
    fits = {} if fits is None else fits
    all_idx = np.arange(problem.n_tests)
    by_name = {c.name: c for c in problem.causes}
    cause = by_name[family]
    for ext in [(family,), *((c,) for c in problem.candidates())]:
        if ext not in fits:
            fits[ext] = fit(problem, all_idx, ext)
    best = min(problem.candidates(), key=lambda c: fits[(c,)].bic)
    f = fits[(family,)]
    ho = heldout(problem, (family,), f)
    ci = parameter_intervals(problem, f, n_boot=n_boot, seed=seed)
    vs_base, se_base = paired_gain(sel["base"]["deviance"], ho["deviance"])
    vs_best, se_best = paired_gain(heldout(problem, (best,), fits[(best,)])["deviance"], ho["deviance"])
    assert cause.closed_form is not None
    return FamilyComparison(
        effect=family,
        form=cause.law,
        # the fit's numbers, as the record holds them
        params=cast("dict[str, Number]", f.values),
        ci95=cast("dict[str, list[Number]]", ci),
        reduces_to=cause.closed_form(f.values, ci),
        discovered=family in sel["effects"],
        best_listed=best,
        best_listed_params=cast("dict[str, Number]", fits[(best,)].values),
        dbic_vs_base=f.bic - fits[()].bic if () in fits else None,
        dbic_vs_best_listed=f.bic - fits[(best,)].bic,
        heldout_gain={
            "vs_base": vs_base,
            "vs_base_se": se_base,
            "vs_best_listed": vs_best,
            "vs_best_listed_se": se_best,
        },
    )


def discovery(problem: Problem[Any], eff: str, sel: Selection) -> Discovery:
    """The fields of a finding that say whether its form was discovered (a family) rather than listed.

    A discovered form carries the closed form of the library it reduces to
    (or "no closed form of the library") and its held-out gain against the
    base model and against the best model of the listed causes.
    """
    cause = next(c for c in problem.causes if c.name == eff)
    if not getattr(cause, "family", None):
        return {"discovered": False}
    ho = sel["final"]["deviance"]
    vs_catalogue, se_catalogue = paired_gain(sel["catalogue"]["final"]["deviance"], ho)
    vs_base, se_base = paired_gain(sel["base"]["deviance"], ho)
    own = [q.name for q in cause.params]
    assert cause.closed_form is not None
    return {
        "discovered": True,
        "family": f"{cause.law} (holds {cause.family})",
        "reduces_to": cause.closed_form(
            {k: sel["fit"].values[k] for k in own}, {k: sel["ci"][k] for k in own if k in sel["ci"]}
        ),
        "best_listed": sel["catalogue"]["effects"],
        "heldout_gain": {
            "vs_base": vs_base,
            "vs_base_se": se_base,
            "vs_best_listed": vs_catalogue,
            "vs_best_listed_se": se_catalogue,
        },
    }
