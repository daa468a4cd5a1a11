"""Loss in flight: a viscous moment -2 zeta p thetadot between impacts."""

from __future__ import annotations

import math

import numpy as np

from rocklab._imports import lazy_module
from rocklab.diagnosis.causes import Cause
from rocklab.diagnosis.evidence import FILTER_DAMPING_BIAS
from rocklab.diagnosis.parameters import Param
from rocklab.physics.flight import speed_loss
from rocklab.physics.law import FlightLoss

stats = lazy_module("scipy.stats")

ZETA = Param("zeta", 0.0, 0.2, 0.0, practical=2e-4)

#: Flights above this fraction of alpha: the filter's windows stay within one half of them.
LONG_FLIGHT = 0.3

#: Fewest long flights the flight-loss curve is read on.
MIN_LONG_FLIGHTS = 5


def laws(v):
    return (FlightLoss(v["zeta"]),)


def signature(ob):
    """The speed lost between a take-off and the next impact (none in a rigid flight).

    Read on the long flights (:func:`long_flights`), where the derivative
    filter's windows stay within one half of the flight: on a shorter one
    the filter moves the loss into the measured e and reads the next impact
    as fast as the take-off whatever zeta (:func:`short_flights_only`).  A
    median over all the flights sits on that cluster at 1 and crosses the
    threshold by the noise's scatter only: a wall with zeta = 0.01 (h/b
    14.4, 200 Hz) read 0.9997, the signature present, at 0.002 mm of noise
    and 0.9998, absent, at 0.0002 mm, where its long flights lose 1.1 %.
    With fewer than :data:`MIN_LONG_FLIGHTS` long flights (the loss then
    not identifiable), all the flights above the noise.  The starting zeta
    is the viscous curve (:func:`viscous_curve`) fitted to the long flights.
    """
    A, v, loss = long_flights(ob)
    if v.size >= MIN_LONG_FLIGHTS:
        fl, which = 1.0 - loss, f"{v.size} flights above {LONG_FLIGHT:g} alpha"
        g = viscous_curve(A, float(np.median(ob.alpha)), float(np.median(ob.p)))
        zeta = float(g @ loss / (g @ g))
    else:
        S = ob.S
        with np.errstate(invalid="ignore", divide="ignore"):
            fl = S.vb[:, 1:] / S.va[:, :-1]
        fl = fl[np.isfinite(fl) & ob.big[:, :-1]]
        which, zeta = f"{fl.size} flights", None
    if fl.size < 3:
        return None
    med = float(np.median(fl))
    w = stats.wilcoxon(fl - 1.0, alternative="less") if np.ptp(fl) > 0 else None
    pv = float(w.pvalue) if w is not None else 1.0
    # 1 - v_land/v_off ~ 4 zeta p int|thetadot| / v_off^2 ~ zeta pi / 2 at small amplitude
    zeta = 2.0 * (1.0 - med) / math.pi if zeta is None else zeta
    return {
        "value": med,
        "zeta": float(max(zeta, 0.0)),
        "supports": bool(pv < 0.01 and med < 1 - 2e-4),  # a speed loss of 0.02 % per flight
        "text": f"impact speed / previous take-off speed = {med:.4f} (median of {which}, "
        f"Wilcoxon p = {pv:.2g}; 1 = no loss in flight)",
    }


def filter_reading(A, a, p, v, *, zeta=0.0, mu=0.0, kappa=0.0, k=0.0):
    """The speed a long flight of apex A [rad] and take-off speed v [rad/s] loses by its next impact, over
    v, as the derivative filter reads it [-].

    The speed loss (:func:`rocklab.physics.flight.speed_loss`) less the
    filter's bias within one half of the flight: :data:`rocklab.diagnosis.evidence.FILTER_DAMPING_BIAS`
    times zeta, and as much for drag as for a viscous loss of zeta = kappa v / (2 p); none for dry
    friction, a constant moment the fitted curve's free acceleration absorbs.
    """
    return speed_loss(A, a, p, zeta, mu=mu, kappa=kappa, k=k) - FILTER_DAMPING_BIAS * (zeta + kappa * v / (2.0 * p))


def viscous_curve(A, alpha, p):
    """The viscous loss's :func:`filter_reading` per unit zeta: linear in zeta for the small losses of a wall."""
    u = 1e-3
    return filter_reading(A, alpha, p, 0.0, zeta=u) / u


def long_flights(ob):
    """Apex, take-off speed and relative speed loss of the flights the filter reads within one half.

    Returns
    -------
    A, v, loss : ndarray
        Flat arrays over the flights after an impact with apex above
        :data:`LONG_FLIGHT` alpha and a next impact: apex [rad], take-off
        speed [rad/s], 1 - next impact speed / take-off speed.
    """
    S = ob.S
    with np.errstate(invalid="ignore", divide="ignore"):
        loss = 1.0 - S.vb[:, 1:] / S.va[:, :-1]
    A = S.A[:, :-1]
    ok = np.isfinite(loss) & ob.big[:, :-1] & (A > LONG_FLIGHT * ob.alpha) & np.isfinite(S.va[:, :-1])
    return A[ok], S.va[:, :-1][ok], loss[ok]


def short_flights_only(ob):
    """Why the flights of a series cannot tell a loss in flight from a lower e ("" where they can).

    The derivative filter moves the loss of a flight shorter than its
    windows into the measured e (:func:`rocklab.diagnosis.evidence.filter_loss_bias`):
    only flights above :data:`LONG_FLIGHT` alpha show it apart, and the
    curve needs :data:`MIN_LONG_FLIGHTS` of them.
    """
    n = long_flights(ob)[0].size
    if n >= MIN_LONG_FLIGHTS:
        return ""
    return (
        f"{n} flights above {LONG_FLIGHT:g} alpha ({MIN_LONG_FLIGHTS} needed): on shorter flights the derivative "
        "filter reads a loss in flight as a lower e"
    )


def starts(sig):
    return {"zeta": max(sig.get(CAUSE.name, {}).get("zeta", 0.0), 1e-4)}


CAUSE = Cause(
    name="flight_damping",
    law="-2 zeta p thetadot between impacts",
    params=(ZETA,),
    laws=laws,
    signature=signature,
    starts=starts,
    not_identifiable=short_flights_only,
    short="zeta",
)
