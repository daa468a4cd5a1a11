"""Losses in flight by their dependence on the angular velocity (a family of the viscous loss, issue 12).

The deceleration 2 zeta p thetadot + mu p^2 sign(thetadot) + kappa
thetadot |thetadot| between impacts (:func:`rocklab.physics.flight.loss_deceleration`):
viscous (zeta), dry friction at the hinge (a constant moment mu m g R) and
quadratic drag (kappa), fitted as mu / alpha (the friction moment over the
wall's restoring moment at rest, m g R sin alpha) and kappa alpha (the drag
moment at thetadot_r over that same moment), both [-].  Its member mu =
kappa = 0 is the listed :mod:`rocklab.diagnosis.causes.flight_damping`.

Each law has its own flight-loss curve, the speed a flight loses between
take-off and the next impact relative to its take-off speed v
(:func:`rocklab.physics.flight.speed_loss`): at small amplitude of order
mu / alpha (dry friction: constant in v), 4 zeta v / (3 p alpha) (viscous:
proportional to v) and kappa v^2 / (2 p^2 alpha) (drag: as v^2).  Short
flights show no loss in their measured speeds (the derivative filter moves
it into the measured e, :func:`rocklab.diagnosis.flight_filter.filter_reading`):
the curve is read on the flights whose fit windows stay within one half.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, TypedDict

import numpy as np

from rocklab._imports import lazy_module
from rocklab.diagnosis.causes import Cause, Signature, flight_damping
from rocklab.diagnosis.causes.flight_damping import LONG_FLIGHT, MIN_LONG_FLIGHTS, long_flights
from rocklab.diagnosis.parameters import Param
from rocklab.physics.flight import takeoff_speed
from rocklab.physics.law import FlightLoss
from rocklab.physics.wall import overturning_velocity

if TYPE_CHECKING:
    from rocklab.diagnosis.evidence import MeasuredTest, Observed
    from rocklab.diagnosis.result import Curve, CurveLine

stats = lazy_module("scipy.stats")

MU = Param("mu_over_alpha", 0.0, 0.2, 0.0, practical=5e-4)
KAPPA = Param("kappa_alpha", 0.0, 2.0, 0.0, practical=1e-3)

#: Log ratio of the residual sums of the flight-loss curve, viscous over the best member, that
#: says the listed viscous loss has the wrong form (chi^2 of one degree of freedom at p = 1e-3).
FORM_CHI2 = 10.8

#: Median speed loss of the long flights that a model without a loss in flight misses.
UNMODELLED_LOSS = 1e-3

#: The members of the family: name, its parameter, the others at their null, the exponent of v in the loss.
MEMBERS = (
    ("flight_damping: viscous, -2 zeta p thetadot", "zeta", 1),
    ("dry friction at the hinge, a constant moment mu m g R (RockingModel.mu)", "mu_over_alpha", 0),
    ("quadratic drag, -kappa thetadot |thetadot| (RockingModel.kappa)", "kappa_alpha", 2),
)


class _FlightKeywords(TypedDict):
    """The keywords of a flight's closed forms (:func:`rocklab.physics.flight.takeoff_speed`)."""

    zeta: float
    mu: float
    kappa: float
    k: float


def laws(v: Mapping[str, float]) -> tuple[FlightLoss]:
    return (FlightLoss(v["zeta"], v["mu_over_alpha"], v["kappa_alpha"]),)


def member_curves(A: np.ndarray, v: np.ndarray, alpha: float, p: float, read: np.ndarray) -> dict[str, np.ndarray]:
    """Each member's flight-loss curve per unit of its parameter on the flights of ``read``, as the
    derivative filter reads it (:func:`rocklab.diagnosis.causes.flight_damping.filter_reading`): linear in
    the parameter for the small losses of a wall.

    Returns
    -------
    dict
        Member parameter name -> array like ``A``.
    """
    u = 1e-3
    return {
        "zeta": flight_damping.viscous_curve(A, alpha, p, read),
        "mu_over_alpha": flight_damping.filter_reading(A, alpha, p, v, mu=u * alpha, read=read) / u,
        "kappa_alpha": flight_damping.filter_reading(A, alpha, p, v, kappa=u / alpha, read=read) / u,
    }


def signature(ob: Observed) -> Signature | None:
    """The speed lost between take-off and the next impact against the flight's speed (long flights).

    Each member's curve (:func:`member_curves`) fitted by its one parameter
    (least squares); where another member fits the curve better than the
    viscous loss beyond the noise (log ratio of the residual sums above
    :data:`FORM_CHI2`, and by 2e-4 of the speed in RMS), the listed
    ``flight_damping`` has the wrong form: ``against_member`` says so; where
    the long flights lose more than :data:`UNMODELLED_LOSS` of their speed,
    a model without a loss in flight misses it: ``unmodelled``
    (:meth:`rocklab.diagnosis.series_problem.WallProblem.form_structure`).  Short
    flights hide their loss in the measured e, so the listed loss's own
    signature, a median over all flights, can miss a drag.
    """
    A, v, loss, read = long_flights(ob)
    if v.size < MIN_LONG_FLIGHTS or np.ptp(loss) == 0:
        return None
    alpha, p = float(np.median(ob.alpha)), float(np.median(ob.p))
    w = stats.wilcoxon(loss, alternative="greater")
    fits = {name: flight_damping.curve_scale(g, loss) for name, g in member_curves(A, v, alpha, p, read).items()}
    best = min(fits, key=lambda k: fits[k][1])
    rms = {k: np.sqrt(r) for k, (_, r) in fits.items()}
    med = float(np.median(loss))
    supports = bool(w.pvalue < 0.01 and med > 2e-4)
    lr = v.size * np.log(fits["zeta"][1] / fits[best][1])
    wrong = supports and best != "zeta" and lr > FORM_CHI2 and rms["zeta"] - rms[best] > 2e-4
    label = {name: text.split(",")[0] for text, name, _ in MEMBERS}
    return {
        "value": med,
        "best": best,
        "start": fits[best][0],
        "supports": supports,
        "against_member": f"flight loss: the speed lost per flight follows {label[best]} "
        f"(RMS {100 * rms[best]:.2f} % of the speed), not the viscous loss ({100 * rms['zeta']:.2f} %)"
        if wrong
        else None,
        "unmodelled": f"flight loss: the flights above {LONG_FLIGHT:g} alpha lose {100 * med:.2f} % of their speed "
        "between take-off and the next impact, and the model has no loss in flight"
        if supports and med > UNMODELLED_LOSS
        else None,
        "text": f"speed lost per flight {100 * med:.2f} % (median of {v.size} flights above {LONG_FLIGHT:g} alpha, "
        f"Wilcoxon p = {w.pvalue:.2g}); its curve against the speed fitted by each member: "
        + ", ".join(f"{label[k]} {100 * rms[k]:.2f} %" for k in fits)
        + " RMS",
    }


def starts(sig: Mapping[str, Signature]) -> dict[str, float]:
    """The member that fits the flight-loss curve best, at its fitted value (not the listed viscous loss's)."""
    s = sig.get(CAUSE.name)
    if not s or s.get("best", "zeta") == "zeta":
        return {}  # the listed loss's own start (its signature)
    return {s["best"]: s["start"]}


def closed_form(values: Mapping[str, float], ci: Mapping[str, Sequence[float]]) -> str:
    """The member of the family the intervals hold (the others at their null), or none."""
    fits = [
        text
        for text, name, _ in MEMBERS
        if all(CAUSE.holds(ci, q.name, q.null) for q in CAUSE.params if q.name != name)
    ]
    if len(fits) == 1:
        return fits[0]
    if fits:
        return "undecided between " + "; ".join(fits)
    return "no closed form of the library"


def curve(tests: Sequence[MeasuredTest], values: Mapping[str, float], listed: Mapping[str, float]) -> Curve:
    """The flight-loss curve of the fitted family and of the listed viscous loss, against the long flights.

    Parameters
    ----------
    tests : list of MeasuredTest
    values : dict
        The family's parameters.
    listed : dict
        The parameters of the best model of the listed causes (zeta 0 where
        it has no loss in flight).

    Returns
    -------
    dict
        ``x`` label and ``y`` label, ``measured`` ({x, y}: the long flights),
        ``family`` and ``best_listed`` ({x, y, label}): take-off speed over
        thetadot_r against the relative speed loss as the derivative filter
        reads it (:func:`member_curves`), on the series' mean wall.
    """
    from rocklab.diagnosis.evidence import observe

    ob = observe(tests)
    _, v, loss, _ = long_flights(ob)
    alpha, fs = float(np.mean(ob.alpha)), float(1.0 / np.median(ob.S.tfloor))
    # the wall as found: its instability angle, and its dependence on the amplitude (instability_amplitude)
    a, k = alpha * values.get("alpha_r_over_alpha", 1.0), values.get("rounding", 0.0)
    p = float(np.mean(ob.p))
    vr = float(overturning_velocity(alpha, p))
    A = np.linspace(0.02, 0.98, 60) * a

    def line(zeta: float, mu_a: float, kappa_a: float, label: str) -> CurveLine:
        kw: _FlightKeywords = {"zeta": zeta, "mu": mu_a * alpha, "kappa": kappa_a / alpha, "k": k}
        v_off = takeoff_speed(A, a, p, **kw)
        read = flight_damping.filter_reading(A, a, p, v_off, fs=fs, fits=tests[0].fits, **kw)
        return {"x": (v_off / vr).tolist(), "y": read.tolist(), "label": label}

    zeta = listed.get("zeta", 0.0)
    fam = ", ".join(f"{q.name} = {values[q.name]:.3g}" for q in CAUSE.params)
    return {
        "x": "take-off speed / thetadot_r",
        "y": "speed lost by the next impact / take-off speed (as the filter reads it)",
        "measured": {
            "x": (v / vr).tolist(),
            "y": loss.tolist(),
            "label": f"measured, flights above {LONG_FLIGHT:g} alpha",
        },
        "family": line(values["zeta"], values["mu_over_alpha"], values["kappa_alpha"], f"flight_loss ({fam})"),
        "best_listed": line(zeta, 0.0, 0.0, f"best listed member: flight_damping (zeta = {zeta:.3g})"),
    }


CAUSE = Cause(
    name="flight_loss",
    law="-2 zeta p thetadot - mu p^2 sign(thetadot) - kappa thetadot |thetadot| between impacts "
    "(viscous, dry friction at the hinge, drag)",
    params=(flight_damping.ZETA, MU, KAPPA),
    laws=laws,
    signature=signature,
    starts=starts,
    replaces=(flight_damping.CAUSE.name,),
    family=flight_damping.CAUSE.name,
    closed_form=closed_form,
    curve=curve,
    # short flights move their loss into the measured e (module docstring): a viscous loss named on too few
    # long flights may be a lower e, a lower rocking angle or a dry friction alike
    checks_form=True,
    # the same reading of short flights as of the viscous member's: dry friction and drag alike
    not_identifiable=flight_damping.short_flights_only,
    on_the_maps=(
        flight_damping.CAUSE.name,
        "its viscous member, zeta: the maps' numba engine does not simulate dry friction or drag in flight "
        "(mu/alpha, kappa alpha), which are lost",
    ),
)
