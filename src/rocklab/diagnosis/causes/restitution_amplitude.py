"""Restitution that falls with the impact speed: e/e_an = a - b (thetadot^-/thetadot_r)^2, Eq. 17 (Fig. 15b)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from rocklab.diagnosis.causes import Cause, Signature, Trials, restitution_scale
from rocklab.diagnosis.estimation.structure import within_slope
from rocklab.diagnosis.parameters import Param
from rocklab.physics.law import Amplitude

if TYPE_CHECKING:
    from rocklab.diagnosis.evidence import Observed

#: ``a`` of Eq. 17 has no null of its own: it is the scale.
A = Param("a", 0.2, 2.5, 1.0)
B = Param("b", -3.0, 3.0, 0.0, practical=0.01)


def laws(v: Mapping[str, float]) -> tuple[Amplitude]:
    return (Amplitude(v["a"], v["b"]),)


def _within_tests(ratio: np.ndarray, x: np.ndarray, ok: np.ndarray, what: str) -> Signature | None:
    """The slope of the measured e/e_an on ``x`` within tests (rows), its test over tests.

    The speed varies between the impacts of a test, the level of e between
    tests (a scale, a drift): the slope is taken within tests and tested over
    them (:func:`rocklab.diagnosis.estimation.structure.within_slope`), which
    neither other causes nor a few wild impacts at small amplitude can fake or
    hide as they can in a regression over all impacts.
    """
    ok = ok & np.isfinite(x)
    slope, p, span = within_slope(np.where(ok, ratio, 0.0), x, ok, min_obs=2)
    if not np.isfinite(p):
        return None
    assert B.practical is not None
    return {
        "value": float(-slope),
        "supports": bool(p < 0.01 and abs(slope) > B.practical),
        "text": f"{what}: slope {slope:+.3f} within tests (p = {p:.2g}, {int(ok.sum())} impacts over {span:.2f})",
    }


def signature(ob: Observed) -> Signature | None:
    """The trend of the measured e/e_an with the squared impact speed over thetadot_r, within tests."""
    return _within_tests(ob.ratio, ob.vr**2, ob.ok, "e/e_an against (thetadot^-/thetadot_r)^2")


def on_ratios(trials: Trials) -> Signature | None:
    """The trend of r/e_an with the squared impact speed relative to the first impact's, within trials."""
    ratio = trials.ratio
    return _within_tests(ratio, trials.u, np.isfinite(ratio), "r/e_an against (thetadot^-_k/thetadot^-_1)^2")


def starts(sig: Mapping[str, Signature]) -> dict[str, float]:
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
