"""Restitution that drifts test after test within a series (a family of the scale, issue 12).

e = c e_an exp(d (n - 1/2)), n the test's place in the series from 0
(first) to 1 (last): hinge wear, or mortar debris gathering between tests
(the paper blames debris for the scatter of theta0/alpha).  Its member
d = 0 is the listed scale (:mod:`rocklab.diagnosis.causes.restitution_scale`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy import stats

from rocklab.diagnosis.causes import Cause, restitution_scale
from rocklab.diagnosis.engine import Param

D = Param("drift", -1.0, 1.0, 0.0, practical=0.005)


def apply(mp, v):
    factor = v["c"] * np.exp(v["drift"] * (mp.order - 0.5))
    return replace(mp, c_pos=factor * mp.c_pos, c_neg=factor * mp.c_neg)


def signature(ob):
    """The per-test median of the measured e/e_an against the test's place in the series."""
    med = np.array([np.median(ob.ratio[i][ob.ok[i]]) if ob.ok[i].any() else np.nan for i in range(len(ob.tests))])
    order = ob.S.order
    ok = np.isfinite(med)
    if ok.sum() < 4 or np.ptp(order[ok]) == 0:
        return None
    fit = stats.linregress(order[ok], np.log(med[ok]))
    return {
        "value": float(fit.slope),
        "supports": bool(fit.pvalue < 0.01 and abs(fit.slope) > D.practical),
        "text": f"log of the per-test median e/e_an against the test's place in the series: slope "
        f"{fit.slope:+.4f} over the series (p = {fit.pvalue:.2g}, {ok.sum()} tests)",
    }


def starts(sig):
    return {"drift": sig.get("restitution_drift", {}).get("value", 0.0)}


def closed_form(values, ci):
    if CAUSE.holds(ci, "drift", 0.0):
        return "restitution_scale: e = c e_an, no drift"
    return "no closed form of the library"


CAUSE = Cause(
    name="restitution_drift",
    law="e = c e_an exp(d (n - 1/2)), n the test's place in the series (0 to 1)",
    params=(restitution_scale.C, D),
    apply=apply,
    signature=signature,
    starts=starts,
    replaces=("restitution_scale",),
    family="restitution_scale",
    closed_form=closed_form,
)
