"""Instability angle below the nominal one: the wall rocks on alpha_r = r alpha.

A rounded hinge, indented mortar (Sect. 3).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from rocklab.diagnosis.causes import Cause, Signature
from rocklab.diagnosis.parameters import Param
from rocklab.physics.law import Hinge

if TYPE_CHECKING:
    from rocklab.diagnosis.evidence import Observed

R = Param("alpha_r_over_alpha", 0.3, 1.2, 1.0, practical=0.005)


def laws(v: Mapping[str, float]) -> tuple[Hinge]:
    return (Hinge(v["alpha_r_over_alpha"]),)


def signature(ob: Observed) -> Signature:
    """alpha_r/alpha from the flight times (Housner's closed form inverted) and from the fall after the release."""
    r0 = ob.S.theta0 / ob.alpha[:, 0]
    fall = np.array([t.alpha_fall / t.alpha for t in ob.tests])
    med_T = float(np.nanmedian(ob.a_T)) if np.isfinite(ob.a_T).any() else np.nan
    med_f = float(np.nanmedian(fall)) if np.isfinite(fall).any() else np.nan
    value = med_T if np.isfinite(med_T) else (med_f if np.isfinite(med_f) else 1.0)
    assert R.practical is not None
    return {
        "value": float(value),
        "supports": bool(
            (np.isfinite(med_T) and med_T < 1 - R.practical) or (np.isfinite(med_f) and med_f < 1 - R.practical)
        ),
        "text": f"flight times give alpha_r/alpha = {med_T:.3f} (Housner's closed form, median of "
        f"{int(np.isfinite(ob.a_T).sum())} flights); the fall from the release {med_f:.3f}; "
        f"theta0/alpha = {np.median(r0):.3f}",
    }


def starts(sig: Mapping[str, Signature]) -> dict[str, float]:
    return {"alpha_r_over_alpha": sig.get(CAUSE.name, {}).get("value", R.null)}


CAUSE = Cause(
    name="instability_angle",
    law="the wall rocks on alpha_r = r alpha < alpha",
    params=(R,),
    laws=laws,
    signature=signature,
    starts=starts,
    short="alpha",
)
