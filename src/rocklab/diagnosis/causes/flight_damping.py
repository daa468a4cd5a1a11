"""Loss in flight: a viscous moment -2 zeta p thetadot between impacts."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from rocklab._imports import lazy_module
from rocklab.diagnosis import flight_filter
from rocklab.diagnosis.causes import Cause, Signature
from rocklab.diagnosis.parameters import Param
from rocklab.physics.flight import flight_angle, quarter_period, speed_loss
from rocklab.physics.law import FlightLoss

if TYPE_CHECKING:
    from rocklab.diagnosis.evidence import Observed

stats = lazy_module("scipy.stats")

ZETA = Param("zeta", 0.0, 0.2, 0.0, practical=2e-4)

#: Flights above this fraction of alpha: the filter's windows stay within one half of them.
LONG_FLIGHT = 0.3

#: Fewest long flights the flight-loss curve is read on.
MIN_LONG_FLIGHTS = 5


def laws(v: Mapping[str, float]) -> tuple[FlightLoss]:
    return (FlightLoss(v["zeta"]),)


def signature(ob: Observed) -> Signature | None:
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
    A, v, loss, read = long_flights(ob)
    if v.size >= MIN_LONG_FLIGHTS:
        fl, which = 1.0 - loss, f"{v.size} flights above {LONG_FLIGHT:g} alpha"
        zeta, _ = curve_scale(viscous_curve(A, float(np.median(ob.alpha)), float(np.median(ob.p)), read), loss)
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


def filter_reading(
    A: npt.ArrayLike,
    a: npt.ArrayLike,
    p: float,
    v: npt.ArrayLike,
    *,
    zeta: float = 0.0,
    mu: float = 0.0,
    kappa: float = 0.0,
    k: float = 0.0,
    read: np.ndarray | None = None,
    fs: float | None = None,
    fits: Mapping[str, float] | None = None,
) -> np.ndarray:
    """The speed a flight of apex A [rad] and take-off speed v [rad/s] loses by its next impact, over v, as
    the derivative filter reads it [-].

    The speed loss (:func:`rocklab.physics.flight.speed_loss`) and what the
    filter reads of each loss: its take-off speed's share less its landing
    speed's (:func:`rocklab.diagnosis.flight_filter.filter_reading`, per unit of
    each loss, linear), ``read`` (flights, losses) where the flights were
    measured (:func:`long_flights`), else of the flight of apex A on its
    own angle, sampled at ``fs`` [Hz] and read by the fits of ``fits`` (the
    record's instrument's, :func:`rocklab.lab.motion.instrument_fits`; the
    transducers' by default).
    """
    if read is None:
        T = 2.0 * quarter_period(A, flight_angle(A, a, k), p)
        read = np.array(
            [_loss_read(Tj, vj, p, fs, fits) for Tj, vj in zip(np.ravel(T), np.broadcast_to(v, np.shape(T)).ravel())]
        )
        read = read.reshape(*np.shape(T), len(flight_filter.LOSSES))
    losses = np.array([zeta, mu, kappa], float)
    return speed_loss(A, a, p, zeta, mu=mu, kappa=kappa, k=k) + read @ losses


def _loss_read(T: float, v: float, p: float, fs: float | None, fits: Mapping[str, float] | None) -> np.ndarray:
    """What the filter reads of each loss in the speed loss of one flight, per unit: take-off less landing."""
    r = flight_filter.filter_reading(T, v, p, fs, fits=fits)
    return r[1] - r[2]


def viscous_curve(A: np.ndarray, alpha: float, p: float, read: np.ndarray | None) -> np.ndarray:
    """The viscous loss's :func:`filter_reading` per unit zeta on the flights of ``read``: linear in zeta
    for the small losses of a wall."""
    u = 1e-3
    return filter_reading(A, alpha, p, 0.0, zeta=u, read=read) / u


def curve_scale(curve: np.ndarray, loss: np.ndarray) -> tuple[float, float]:
    """The scale c >= 0 of a loss curve per unit of its parameter that fits the losses best (least
    squares through the origin), and the mean square of what it leaves."""
    c = max(float(curve @ loss / (curve @ curve)), 0.0)
    return c, float(np.mean((loss - c * curve) ** 2))


def long_flights(ob: Observed) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Apex, take-off speed and relative speed loss of the flights the filter reads within one half.

    Returns
    -------
    A, v, loss : ndarray
        Flat arrays over the flights after an impact with apex above
        :data:`LONG_FLIGHT` alpha and a next impact: apex [rad], take-off
        speed [rad/s], 1 - next impact speed / take-off speed.
    read : ndarray
        (flights, losses): what the filter reads of each loss in the speed
        loss of those flights, per unit of the loss (:func:`filter_reading`).
    """
    S = ob.S
    ok, loss = _long(ob)
    R = S.filter_reading()
    # the take-off of flight j is impact j's, its landing impact j + 1's
    read = R["takeoff"][:, :-1] - R["landing"][:, 1:]
    return S.A[:, :-1][ok], S.va[:, :-1][ok], loss[ok], read[ok]


def _long(ob: Observed) -> tuple[np.ndarray, np.ndarray]:
    """Which flights :func:`long_flights` reads, (tests, impacts - 1), and the speed each loses."""
    S = ob.S
    with np.errstate(invalid="ignore", divide="ignore"):
        loss = 1.0 - S.vb[:, 1:] / S.va[:, :-1]
    ok = np.isfinite(loss) & ob.big[:, :-1] & (S.A[:, :-1] > LONG_FLIGHT * ob.alpha) & np.isfinite(S.va[:, :-1])
    return ok, loss


def short_flights_only(ob: Observed) -> str:
    """Why the flights of a series cannot tell a loss in flight from a lower e ("" where they can).

    The derivative filter moves the loss of a flight shorter than its
    windows into the measured e (:func:`rocklab.diagnosis.flight_filter.filter_reading`):
    only flights above :data:`LONG_FLIGHT` alpha show it apart, and the
    curve needs :data:`MIN_LONG_FLIGHTS` of them.
    """
    n = int(_long(ob)[0].sum())
    if n >= MIN_LONG_FLIGHTS:
        return ""
    return (
        f"{n} flights above {LONG_FLIGHT:g} alpha ({MIN_LONG_FLIGHTS} needed): on shorter flights the derivative "
        "filter reads a loss in flight as a lower e"
    )


def starts(sig: Mapping[str, Signature]) -> dict[str, float]:
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
