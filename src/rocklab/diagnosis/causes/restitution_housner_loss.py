"""An impact law affine in Housner's loss across walls (a family of the base e, issue 12).

e = 1 - lambda (1 - e_an) - delta: a fraction lambda of the loss that Eq. 2
gives the slenderness of the wall plus a constant loss delta per impact.
Its member lambda = 1, delta = 0 is Housner's e; lambda and delta are told
apart only across walls of different slenderness (the limestone blocks of
:mod:`rocklab.diagnosis.block_tests`, pooled), so it is no candidate within
a series (no boundary condition).
"""

from __future__ import annotations

from rocklab.diagnosis.causes import Cause
from rocklab.diagnosis.parameters import Param
from rocklab.physics.law import HousnerLoss

LAMBDA = Param("loss_fraction", 0.0, 3.0, 1.0, practical=0.01)
DELTA = Param("loss_constant", -0.2, 0.2, 0.0, practical=0.002)


def laws(v):
    return (HousnerLoss(v["loss_fraction"], v["loss_constant"]),)


def closed_form(values, ci):
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
    family="restitution_scale",
    closed_form=closed_form,
    short="hloss",
)
