"""Loss in flight: a viscous moment -2 zeta p thetadot between impacts."""

from __future__ import annotations

import math

import numpy as np

from rocklab._imports import lazy_module
from rocklab.diagnosis.causes import Cause
from rocklab.diagnosis.parameters import Param
from rocklab.physics.law import FlightLoss

stats = lazy_module("scipy.stats")

ZETA = Param("zeta", 0.0, 0.2, 0.0, practical=2e-4)


def laws(v):
    return (FlightLoss(v["zeta"]),)


def signature(ob):
    """The speed lost between a take-off and the next impact (none in a rigid flight)."""
    S = ob.S
    with np.errstate(invalid="ignore", divide="ignore"):
        fl = S.vb[:, 1:] / S.va[:, :-1]
    fl = fl[np.isfinite(fl) & ob.big[:, :-1]]
    if fl.size < 3:
        return None
    med = float(np.median(fl))
    w = stats.wilcoxon(fl - 1.0, alternative="less") if np.ptp(fl) > 0 else None
    pv = float(w.pvalue) if w is not None else 1.0
    # 1 - v_land/v_off ~ 4 zeta p int|thetadot| / v_off^2 ~ zeta pi / 2 at small amplitude
    return {
        "value": med,
        "zeta": float(max(2.0 * (1.0 - med) / math.pi, 0.0)),
        "supports": bool(pv < 0.01 and med < 1 - 2e-4),  # a speed loss of 0.02 % per flight
        "text": f"impact speed / previous take-off speed = {med:.4f} (median of {fl.size} flights, "
        f"Wilcoxon p = {pv:.2g}; 1 = no loss in flight)",
    }


def starts(sig):
    return {"zeta": max(sig.get(CAUSE.name, {}).get("zeta", 0.0), 1e-4)}


CAUSE = Cause(
    name="flight_damping",
    law="-2 zeta p thetadot between impacts",
    params=(ZETA,),
    laws=laws,
    signature=signature,
    starts=starts,
    short="zeta",
)
