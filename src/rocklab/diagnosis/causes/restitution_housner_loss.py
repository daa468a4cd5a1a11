"""An impact law affine in Housner's loss across walls (a family of the base e, issue 12).

e = 1 - lambda (1 - e_an) - delta: a fraction lambda of the loss that Eq. 2
gives the slenderness of the wall plus a constant loss delta per impact.
Its member lambda = 1, delta = 0 is Housner's e; lambda and delta are told
apart only across walls of different slenderness (the limestone blocks of
:mod:`rocklab.diagnosis.block_tests`, pooled), so it is no candidate within
a series (no boundary condition).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from rocklab._imports import lazy_module
from rocklab.diagnosis.causes import Cause, Signature, Trials, restitution_scale
from rocklab.diagnosis.parameters import Param
from rocklab.physics.law import HousnerLoss

if TYPE_CHECKING:
    from rocklab.diagnosis.result import Slenderness

stats = lazy_module("scipy.stats")

LAMBDA = Param("loss_fraction", 0.0, 3.0, 1.0, practical=0.01)
DELTA = Param("loss_constant", -0.2, 0.2, 0.0, practical=0.002)


def laws(v: Mapping[str, float]) -> tuple[HousnerLoss]:
    return (HousnerLoss(v["loss_fraction"], v["loss_constant"]),)


def slenderness_trend(trials: Trials) -> Slenderness:
    """How e/e_an varies with slenderness, block group by block group.

    Slenderness is a property of the block group
    (:data:`rocklab.lab.hierarchy.BLOCK_COVARIATE_LEVEL`): the median r/e_an
    of each trial is averaged over the trials of its group, and the group
    levels are regressed on (B/H)^2 ~ sin^2 alpha, the variable of Housner's
    e, with Student's t on groups - 2 degrees of freedom (the trials of a
    group are repetitions of one block, not replicates of its slenderness).
    A slope means that Eq. 2 gets the trend with slenderness wrong, not only
    the level.

    Returns
    -------
    dict
        ``intercept``, ``slope`` (per unit (B/H)^2), ``slope_se``, ``p``,
        ``n_groups``, ``n_trials``, and the level of each group (mean over
        its trials of their medians).
    """
    ratio = trials.ratio
    ok = np.isfinite(ratio)
    med = np.array([np.median(ratio[i][ok[i]]) for i in range(len(trials.ids))])
    x = np.tan(trials.alpha) ** 2
    groups = np.unique(trials.group)
    level = np.array([med[trials.group == g].mean() for g in groups])
    xg = np.array([x[trials.group == g][0] for g in groups])
    fit = stats.linregress(xg, level)
    hb = np.round(1.0 / np.tan(trials.alpha))
    return {
        "intercept": float(fit.intercept),
        "slope": float(fit.slope),
        "slope_se": float(fit.stderr),
        "p": float(fit.pvalue),
        "n_groups": int(groups.size),
        "n_trials": len(trials.ids),
        "levels": {f"{h:.0f}": float(np.mean(med[hb == h])) for h in np.unique(hb)},
    }


def on_ratios(trials: Trials) -> Signature | None:
    """Across slendernesses, the trend of the block groups' r/e_an with (B/H)^2 (:func:`slenderness_trend`);
    None within one slenderness."""
    if not np.ptp(trials.alpha) > 0:
        return None
    st = slenderness_trend(trials)
    assert st["p"] is not None
    return {
        "value": st["slope"],
        "supports": bool(st["p"] < 0.01),
        "text": f"block-group mean of the trials' median r/e_an against (B/H)^2: slope {st['slope']:+.3f} "
        f"(p = {st['p']:.2g}, {st['n_groups']} groups)",
    }


def closed_form(values: Mapping[str, float], ci: Mapping[str, Sequence[float]]) -> str:
    housner = CAUSE.holds(ci, "loss_fraction", 1.0)
    if housner and CAUSE.holds(ci, "loss_constant", 0.0):
        return "Housner's e (Eq. 2)"
    if CAUSE.holds(ci, "loss_constant", 1.0 - values["loss_fraction"]):
        return f"restitution_scale: e = c e_an with c = {values['loss_fraction']:.3f}"
    if CAUSE.holds(ci, "loss_fraction", 0.0):
        return f"a constant e = {1 - values['loss_constant']:.3f} (rocklab.physics.impact.Constant)"
    return "no closed form of the library"


CAUSE = Cause(
    name="restitution_housner_loss",
    law="e = 1 - lambda (1 - e_an) - delta across walls of different slenderness",
    params=(LAMBDA, DELTA),
    laws=laws,
    boundaries=(),
    family=restitution_scale.CAUSE.name,
    closed_form=closed_form,
    on_ratios=on_ratios,
    short="hloss",
)
