"""Restitution scale: e = c e_an, a calibrated e (Fig. 14b)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from rocklab.diagnosis.causes import Cause, Signature, Trials
from rocklab.diagnosis.evidence import series_level
from rocklab.diagnosis.parameters import Param
from rocklab.physics.law import Restitution

if TYPE_CHECKING:
    from rocklab.diagnosis.evidence import Observed

C = Param("c", 0.2, 2.0, 1.0, practical=0.005)


def laws(v: Mapping[str, float]) -> tuple[Restitution]:
    return (Restitution(v["c"]),)


def signature(ob: Observed) -> Signature | None:
    """The measured e/e_an: one level per test (its median), their mean over tests."""
    e = ob.ratio[ob.ok]
    if e.size < 3:
        return None
    level = series_level(ob.ratio, ob.ok)
    lo, hi = np.percentile(e, [25, 75])
    return {
        "value": level,
        "supports": bool(abs(level - 1) > C.practical),
        "text": f"measured e/e_an = {level:.3f} (mean over tests of their medians; "
        f"IQR of the {e.size} impacts {lo:.3f}-{hi:.3f})",
    }


def on_ratios(trials: Trials) -> Signature:
    """The measured r/e_an of the impacts: one level per trial (its median), their mean over trials."""
    ratio = trials.ratio
    ok = np.isfinite(ratio)
    med = series_level(ratio, ok)
    return {
        "value": med,
        "supports": abs(med - 1) > C.practical,
        "text": f"measured r/e_an = {med:.3f} (mean over trials of their medians, {ok.sum()} impacts)",
    }


def starts(sig: Mapping[str, Signature]) -> dict[str, float]:
    return {"c": sig.get(CAUSE.name, {}).get("value", 1.0)}


CAUSE = Cause(
    name="restitution_scale",
    law="e = c e_an",
    params=(C,),
    laws=laws,
    signature=signature,
    starts=starts,
    on_ratios=on_ratios,
    short="escale",
)
