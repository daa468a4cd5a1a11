"""Hinges that differ (two-sided walls): alpha_+- = alpha_r exp(+-s_alpha/2), e_+- = e exp(+-s_e/2)
on the hinge being left."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from rocklab._imports import lazy_module
from rocklab.diagnosis.causes import Cause, Signature, Trials
from rocklab.diagnosis.parameters import Param
from rocklab.physics.boundary import Boundary
from rocklab.physics.law import Hinge, Restitution

if TYPE_CHECKING:
    from rocklab.diagnosis.evidence import Observed

stats = lazy_module("scipy.stats")

S_ALPHA = Param("s_alpha", -0.5, 0.5, 0.0, practical=0.005)
S_E = Param("s_e", -0.5, 0.5, 0.0, practical=0.003)


def laws(v: Mapping[str, float]) -> tuple[Restitution, Hinge]:
    return (Restitution(asymmetry=v["s_e"]), Hinge(asymmetry=v["s_alpha"]))


def signature(ob: Observed) -> Signature:
    """e and alpha by hinge, theta0/alpha by push or pull release."""
    S, ratio, ok, a_T = ob.S, ob.ratio, ob.ok, ob.a_T
    parts, ps, start = [], [], {}
    plus = S.side > 0
    a_, b_ = ratio[ok & plus], ratio[ok & ~plus]
    if a_.size >= 3 and b_.size >= 3:
        u = stats.mannwhitneyu(a_, b_)
        ps.append((u.pvalue, abs(np.median(a_) / np.median(b_) - 1)))
        start["s_e"] = float(np.log(np.median(a_) / np.median(b_)))
        parts.append(f"e/e_an leaving hinge +/-: {np.median(a_):.3f} / {np.median(b_):.3f} (p = {u.pvalue:.2g})")
    # the apex of flight k is on hinge -side_k
    ta, tb = a_T[~plus[:, :-1]], a_T[plus[:, :-1]]
    ta, tb = ta[np.isfinite(ta)], tb[np.isfinite(tb)]
    if ta.size >= 3 and tb.size >= 3:
        u = stats.mannwhitneyu(ta, tb)
        ps.append((u.pvalue, abs(np.median(ta) / np.median(tb) - 1)))
        start["s_alpha"] = float(np.log(np.median(ta) / np.median(tb)))
        parts.append(
            f"alpha_r/alpha from flights on hinge +/-: {np.median(ta):.3f} / {np.median(tb):.3f} (p = {u.pvalue:.2g})"
        )
    push = np.array([t.side0 > 0 for t in ob.tests])
    if push.sum() >= 2 and (~push).sum() >= 2:
        r0 = S.theta0 / np.array([t.alpha for t in ob.tests])
        w = stats.ttest_ind(r0[push], r0[~push], equal_var=False)
        ps.append((w.pvalue, abs(np.mean(r0[push]) / np.mean(r0[~push]) - 1)))
        parts.append(
            f"theta0/alpha pushed / pulled: {np.mean(r0[push]):.3f} / {np.mean(r0[~push]):.3f} (p = {w.pvalue:.2g})"
        )
    sup = any(pv < 0.01 and size > S_E.practical for pv, size in ps)
    return {
        "value": float(min((pv for pv, _ in ps), default=1.0)),
        "supports": bool(sup),
        **start,
        "text": "; ".join(parts) if parts else "one hinge only",
    }


def on_ratios(trials: Trials) -> Signature:
    """r/e_an on odd and even impacts: the two base edges in turn."""
    ratio = trials.ratio
    ok = np.isfinite(ratio)
    odd, even = ratio[ok & trials.odd], ratio[ok & ~trials.odd]
    mw = stats.mannwhitneyu(odd, even)
    per = [np.nanmedian(r[o]) - np.nanmedian(r[~o]) for r, o in zip(ratio, trials.odd)]
    return {
        "value": float(np.median(odd) / np.median(even)),
        "supports": bool(mw.pvalue < 0.01),
        "text": f"r/e_an on odd / even impacts {np.median(odd):.3f} / {np.median(even):.3f} "
        f"(p = {mw.pvalue:.2g}); odd minus even per trial from {np.min(per):+.3f} to "
        f"{np.max(per):+.3f}",
    }


def starts(sig: Mapping[str, Signature]) -> dict[str, float]:
    return {k: sig.get(CAUSE.name, {}).get(k, 0.0) for k in ("s_alpha", "s_e")}


CAUSE = Cause(
    name="hinge_asymmetry",
    law="alpha_+- = alpha_r exp(+-s_alpha/2), e_+- = e exp(+-s_e/2) on the hinge being left",
    params=(S_ALPHA, S_E),
    laws=laws,
    boundaries=(Boundary.TWO_SIDED,),
    signature=signature,
    starts=starts,
    on_ratios=on_ratios,
    short="asym",
)
