"""An instability angle that depends on the amplitude (a family of the instability angle, issue 12).

A rounded or crushing hinge: the flight of apex A rocks on
a(A) = alpha_r (1 - k) + k A, alpha_r = r alpha the angle of the flights
released at it (:func:`rocklab.physics.flight.flight_angle`; the
three-branch moment-rotation of Doherty et al. 2002 that improves the
paper's match, Sect. 3, taken flight by flight).  Its member k = 0 is the
listed constant angle (:mod:`rocklab.diagnosis.causes.instability_angle`),
which does not fit the flight times at all amplitudes when k is not 0.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from rocklab.diagnosis.causes import Cause, Signature, instability_angle
from rocklab.diagnosis.estimation.structure import within_slope
from rocklab.diagnosis.parameters import Param
from rocklab.physics.law import Hinge

if TYPE_CHECKING:
    from rocklab.diagnosis.evidence import Observed

K = Param("rounding", -0.6, 0.8, 0.0, practical=0.02)


def laws(v: Mapping[str, float]) -> tuple[Hinge]:
    r = v["alpha_r_over_alpha"]
    return (Hinge(r, rounding=v["rounding"]),)


def signature(ob: Observed) -> Signature | None:
    """The trend of the flight times' angle (Housner inverted) with the flight's amplitude, within tests.

    a(A) / alpha = r (1 - k) + k A / alpha: the slope of the angle over
    alpha that each flight time gives (:attr:`rocklab.diagnosis.evidence.Observed.a_T`)
    against the apex over alpha is k.
    """
    x = ob.S.A[:, :-1] / ob.alpha
    ok = np.isfinite(ob.a_T) & np.isfinite(x)
    slope, p, span = within_slope(np.where(ok, ob.a_T, 0.0), x, ok, min_obs=2)
    if not np.isfinite(p):
        return None
    assert K.practical is not None
    return {
        "value": float(slope),
        "supports": bool(p < 0.01 and abs(slope) > K.practical),
        "text": f"the flight times' alpha_r/alpha against the flight's apex over alpha: slope {slope:+.3f} "
        f"within tests (p = {p:.2g}, {int(ok.sum())} flights over {span:.2f} of alpha)",
    }


def starts(sig: Mapping[str, Signature]) -> dict[str, float]:
    return {"rounding": sig.get(CAUSE.name, {}).get("value", K.null)}


def closed_form(values: Mapping[str, float], ci: Mapping[str, Sequence[float]]) -> str:
    if not CAUSE.holds(ci, "rounding", 0.0):
        return "no closed form of the library"
    if CAUSE.holds(ci, "alpha_r_over_alpha", 1.0):
        return "the rigid hinge: alpha_r = alpha"
    return f"instability_angle: a constant alpha_r = {values['alpha_r_over_alpha']:.3f} alpha"


CAUSE = Cause(
    name="instability_amplitude",
    law="the flight of apex A rocks on alpha_r (1 - k) + k A, alpha_r = r alpha (a rounded or crushing hinge)",
    params=(instability_angle.R, K),
    laws=laws,
    signature=signature,
    starts=starts,
    replaces=(instability_angle.CAUSE.name,),
    family=instability_angle.CAUSE.name,
    closed_form=closed_form,
    on_the_maps=(
        instability_angle.CAUSE.name,
        "its angle at the instability point, alpha_r = r alpha, the one of the flights that overturn a wall: "
        "under ground motion a flight's apex, which sets its angle, is unknown when the flight starts",
    ),
)
