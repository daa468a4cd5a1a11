"""How the fits of a record's flights read a flight with losses: the diagnosis' model of its measurement.

:mod:`rocklab.lab.motion` measures an impact's instant and speeds off the
linearised flights it fits either side of it.  A flight with losses is no
such curve, so the fits read a loss in flight into the measured durations
and speeds (:func:`filter_reading`), by an amount that depends on the fits'
windows: the transducers' defaults, or a rotation record's
(:func:`rocklab.lab.motion.instrument_fits`).  The causes of losses in
flight (:mod:`rocklab.diagnosis.causes.flight_damping`,
:mod:`~rocklab.diagnosis.causes.flight_loss`) predict what is measured
through it.
"""

from __future__ import annotations

import functools
import inspect
import math

import numpy as np

from rocklab._imports import lazy_module
from rocklab.lab import motion as chain
from rocklab.lab.flight_fit import local_fit
from rocklab.physics.flight import loss_deceleration

integrate = lazy_module("scipy.integrate")

# the fit windows of the derivative filter (rocklab.lab.motion.extract_motion's defaults)
_FILTER = {k: v.default for k, v in inspect.signature(chain.extract_motion).parameters.items()}


#: The losses in flight, in the order of :func:`filter_reading`'s columns.
LOSSES = ("zeta", "mu", "kappa")

#: n of each of :data:`LOSSES`: its deceleration grows with the speed as v^n
#: (:func:`rocklab.physics.flight.loss_deceleration`).
SPEED_POWER = np.array([1.0, 0.0, 2.0])

#: Points of the fine grid on which a flight's deflection by a loss is integrated.
_GRID = 257


def _deflection(tau, d, p):
    """delta(tau) = -int_0^tau sinh(p (tau - s)) / p d(s) ds on the grid ``tau`` (from 0, either way):
    the solution of delta'' = p^2 delta - d with delta = delta' = 0 at tau = 0, by column of ``d``."""
    ch, sh = np.cosh(p * tau)[:, None], np.sinh(p * tau)[:, None]
    ic = integrate.cumulative_trapezoid(ch * d, tau, axis=0, initial=0.0)
    is_ = integrate.cumulative_trapezoid(sh * d, tau, axis=0, initial=0.0)
    return -(sh * ic - ch * is_) / p


def filter_reading(T, v, p, fs, *, from_rest=False, phases=4, fits=None):
    """How the derivative filter reads a flight with losses, per unit of each loss, to first order.

    The filter (:func:`rocklab.lab.motion.extract_motion`) reads an impact's
    instant and speed off the linearised flight it fits on each side of it
    (:func:`rocklab.lab.flight_fit.local_fit`, over the windows of
    :func:`rocklab.lab.motion.takeoff_window` and
    :func:`~rocklab.lab.motion.landing_window`).  A flight with losses is no
    such curve: it decelerates more while rising than it accelerates while
    falling (dry friction shifts the rise's asymptote by +mu and the fall's
    by -mu; a viscous loss and drag by the speed), so the fitted curve bends
    where the window reaches across the apex, and within one half where the
    loss changes with the speed.  To first order in the loss the flight is
    the lossless one of duration T and speed v at theta = 0 plus a deflection
    delta, delta'' = p^2 delta - d(thetadot), d the loss's deceleration
    (:func:`rocklab.physics.flight.loss_deceleration`), nil with its slope at
    the root a fit reads (:func:`_deflection`).  The fit of delta over the
    window, of value c_0 and slope c_1 at that root, moves the root by
    dt = -c_0 / thetadot and reads the speed there off by c_1 + thetadot'' dt,
    |thetadot''| = p v coth(p T / 2) at the roots of the lossless flight.
    Averaged over ``phases`` placements of the samples.  The deflection
    grows with the loss's deceleration, as v^n (:data:`SPEED_POWER`), so
    the reading is computed at v = 1 and scaled by v^(n - 1), for
    durations rounded to :data:`DURATION_STEP` (shared by the flights of a
    wall, and cached).

    On the stocky wall's short flights (T = 0.13 s, 200 Hz) dry friction of
    mu = 0.02 alpha lengthens the measured flight by 0.9 %, as the virtual
    lab's records show; a viscous loss reads e low by 0.23-0.50 zeta over
    the amplitudes and walls of the campaign, the median 0.35 zeta measured
    on the virtual lab's records before this model
    (tests/test_filter_reading.py).

    Parameters
    ----------
    T : float
        Duration of the flight, take-off to landing [s]; with ``from_rest``,
        of the fall from the release at rest to the first landing.
    v : float
        Its speed at theta = 0 [rad/s].
    p : float
        Frequency parameter [rad/s].
    fs : float
        Sampling rate [Hz].
    from_rest : bool
        The fall from the release: a landing and no take-off.
    fits : mapping, optional
        The fits' settings where they are not the transducers' defaults
        (``ring_guard_s``, ``window_p``: a rotation record's,
        :func:`rocklab.lab.motion.instrument_fits`).

    Returns
    -------
    ndarray of shape (3, len(LOSSES))
        Per unit of each of :data:`LOSSES` (zeta [-], mu [rad], kappa
        [1/rad]): the measured duration's change [s], and the take-off's and
        the landing's measured speed's change over v [-].
    """
    # computed once per duration, to a step of DURATION_STEP, which one wall's flights share
    step = math.exp(round(math.log(T) / DURATION_STEP) * DURATION_STEP)
    f = {**_FILTER, **(fits or {})}
    reading = _reading_at_unit_speed(
        step, float(p), float(fs), bool(from_rest), phases, float(f["ring_guard_s"]), float(f["window_p"])
    )
    return reading * v ** (SPEED_POWER - 1.0)


#: Relative step of the flight durations at which :func:`filter_reading` is computed [-].
DURATION_STEP = 0.005


@functools.lru_cache(maxsize=65536)
def _reading_at_unit_speed(T, p, fs, from_rest, phases, guard, window_p):
    """:func:`filter_reading` of a flight of speed 1 rad/s at theta = 0."""
    W, hum = window_p / p, _FILTER["hum_hz"]
    tau = np.linspace(0.0, T, _GRID)
    # the lossless flight's speed and |thetadot''| at its roots
    if from_rest:
        thetadot, acc = -np.sinh(p * tau) / np.sinh(p * T), p / np.tanh(p * T)
    else:
        h = 0.5 * T
        thetadot, acc = np.sinh(p * (h - tau)) / np.sinh(p * h), p / np.tanh(p * h)
    d = np.column_stack([loss_deceleration(thetadot, p, **{k: 1.0}) for k in LOSSES])
    up = _deflection(tau, d, p)
    down = _deflection(tau[::-1] - T, d[::-1], p)[::-1]
    out = np.zeros((3, len(LOSSES)))
    for ph in (np.arange(phases) + 0.5) / phases:
        t = (np.arange(int(T * fs) + 2) + ph) / fs
        c_b = local_fit(t, _on(t, tau, down), T, *chain.landing_window(0.0, T, fs, W, guard), p, fs, hum)
        if c_b is None:
            return np.zeros((3, len(LOSSES)))
        dt_b = c_b[0]
        out[2] += (-c_b[1] + acc * dt_b) / phases
        if from_rest:
            continue
        c_a = local_fit(t, _on(t, tau, up), 0.0, *chain.takeoff_window(0.0, 0.5 * T, W, guard), p, fs, hum)
        if c_a is None:
            return np.zeros((3, len(LOSSES)))
        dt_a = -c_a[0]
        out[0] += (dt_b - dt_a) / phases
        out[1] += (c_a[1] - acc * dt_a) / phases
    return out


def _on(t, tau, x):
    """The columns of ``x`` (on ``tau``) at the samples ``t``."""
    return np.column_stack([np.interp(t, tau, c) for c in x.T])
