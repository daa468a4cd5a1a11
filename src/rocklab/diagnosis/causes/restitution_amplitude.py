"""Restitution that falls with the impact speed: e/e_an = a - b (thetadot^-/thetadot_r)^2, Eq. 17 (Fig. 15b)."""

from __future__ import annotations

import numpy as np

from rocklab._imports import lazy_module
from rocklab.diagnosis.causes import Cause, restitution_scale
from rocklab.diagnosis.parameters import Param
from rocklab.physics.law import Amplitude

stats = lazy_module("scipy.stats")

#: ``a`` of Eq. 17 has no null of its own: it is the scale.
A = Param("a", 0.2, 2.5, 1.0)
B = Param("b", -3.0, 3.0, 0.0, practical=0.01)


def laws(v):
    return (Amplitude(v["a"], v["b"]),)


def signature(ob):
    """The trend of the measured e/e_an with the squared impact speed over thetadot_r."""
    e, v2 = ob.ratio[ob.ok], ob.vr[ob.ok] ** 2
    if e.size < 3 or not np.ptp(v2) > 0:
        return None
    sl = stats.linregress(v2, e)
    return {
        "value": float(-sl.slope),
        "supports": bool(sl.pvalue < 0.01 and abs(sl.slope) > B.practical),
        "text": f"e/e_an against (thetadot^-/thetadot_r)^2: slope {sl.slope:+.3f} (p = {sl.pvalue:.2g})",
    }


def on_ratios(trials):
    """The trend of r/e_an with the squared impact speed relative to the first impact's."""
    ratio = trials.ratio
    ok = np.isfinite(ratio)
    sl = stats.linregress(trials.u[ok], ratio[ok])
    return {
        "value": float(-sl.slope),
        "supports": bool(sl.pvalue < 0.01),
        "text": f"r/e_an against (thetadot^-_k/thetadot^-_1)^2: slope {sl.slope:+.3f} (p = {sl.pvalue:.2g})",
    }


def starts(sig):
    return {"a": sig.get(restitution_scale.CAUSE.name, {}).get("value", 1.0)}


CAUSE = Cause(
    name="restitution_amplitude",
    law="e/e_an = a - b (thetadot^-/thetadot_r)^2 (Eq. 17)",
    params=(A, B),
    laws=laws,
    signature=signature,
    starts=starts,
    on_ratios=on_ratios,
    replaces=(restitution_scale.CAUSE.name,),
    short="eamp",
)
