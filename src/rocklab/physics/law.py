"""What a cause does to a rocking wall, as composable laws.

A cause of the diagnosis (:mod:`rocklab.diagnosis.causes`) declares its
physics once, as a tuple of these laws (``Cause.laws(values)``); every
consumer reads the laws rather than the cause's name:

- the diagnosis' per-test wall model (:meth:`rocklab.diagnosis.wall_model.ModelParams.under`),
  from which the exact simulator's :class:`rocklab.simulation.rocking_model.RockingModel`
  is derived (:func:`rocklab.diagnosis.wall_model.simulator`) and with it the
  calibrated walls of the maps (:mod:`rocklab.seismic.calibrated`);
- the shake-table block (:func:`rocklab.shake_table.block.block_model`: its extra loss, ``restitution_scale``);
- the limestone block tables (:meth:`rocklab.diagnosis.block_tests.BlockProblem.model_e`).

A law holds the change, not the wall: a factor on what the base model has
(the rocking angle, e), a term it adds (a loss in flight), or a rule
(a gap, a stop).  Its values are floats, or per-test arrays where a cause
takes one value per test (a stop threshold left out test by test).  The
laws of several causes compose by acting in turn, in the catalogue's order
(:data:`rocklab.diagnosis.catalogue.CAUSES`): factors multiply, a term or a
rule is that of the last law to set it.  Null values leave the base model
as it is.

Beyond the speeds it was fitted on, every law is its own closed form
(Eq. 17's parabola, the last segment of :class:`SpeedFactor` continued),
never held flat, and every law of e is within the physical bounds of
:func:`rocklab.physics.impact.bounded_factor`: e keeps the sign of the base
law and |e| <= 1.  A loss in flight only takes energy (its parameters are
not negative, :class:`FlightLoss`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Restitution:
    """e times ``scale`` exp(+-``asymmetry``/2) on leaving hinge +-1 (Sect. 3, Figs. 14b, 15).

    A scale c of e_an is ``Restitution(c)``; hinges that differ by a ratio
    exp(s_e) of their e, ``Restitution(asymmetry=s_e)``.  A ``drift`` d
    (None: none) makes the factors follow the test's place n in its series
    (0 first, 1 last) or in the range of the test log's column ``along``:
    times exp(d (n - 1/2)).
    """

    scale: float = 1.0
    asymmetry: float = 0.0
    drift: float | None = None
    along: str | None = None

    def factors(self, place=None):
        """The factors (hinge +1, hinge -1) of a wall at its place n [-] (read only with a drift)."""
        pos, neg = self.scale * math.exp(self.asymmetry / 2), self.scale * math.exp(-(self.asymmetry / 2))
        if self.drift is None:
            return pos, neg
        f = np.exp(self.drift * (place - 0.5))
        return pos * f, neg * f

    def on_impacts(self, leaving_plus):
        """The factor of each impact, ``leaving_plus`` (bool array) where it leaves hinge +1 [-]."""
        return self.scale * np.exp(np.where(leaving_plus, 0.5, -0.5) * self.asymmetry)


@dataclass(frozen=True)
class HousnerLoss:
    """e = 1 - fraction (1 - |e_an|) - constant, with the sign of e_an: a fraction of the loss
    Eq. 2 gives the slenderness plus a constant loss per impact (issue 12); |e| within [0, 1]."""

    fraction: float = 1.0
    constant: float = 0.0

    def restitution(self, e_an):
        """The base e [-] from the analytic one, ``e_an`` (array_like, signed)."""
        return np.sign(e_an) * np.clip(1.0 - self.fraction * (1.0 - np.abs(e_an)) - self.constant, 0.0, 1.0)


@dataclass(frozen=True)
class Amplitude:
    """Eq. 17: e times a - b (thetadot^-/thetadot_r)^2, the bracket clipped to [0, 1/|e|]
    (:func:`rocklab.physics.impact.amplitude_factor`); ``a`` multiplies, ``b`` is set."""

    a: float = 1.0
    b: float = 0.0


@dataclass(frozen=True)
class SpeedFactor:
    """e times g(thetadot^-/thetadot_r), g piecewise linear between its values ``knots`` at
    :data:`KNOTS` (its last segment continued beyond them, :func:`hats`; e within the bounds of
    :func:`rocklab.physics.impact.bounded_factor`): a law of the impact speed no closed form
    dictates.  The exact simulator's law is :class:`rocklab.physics.impact.SpeedLaw` (the
    reference integrator only: the maps' engines have none)."""

    knots: tuple = (1.0, 1.0, 1.0, 1.0)


#: Knots of :class:`SpeedFactor` in thetadot^- / thetadot_r [-].
KNOTS = np.array([0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0])


def hats(x):
    """Piecewise-linear basis at :data:`KNOTS` of speeds x [thetadot_r], shape (..., knots).

    Beyond the last knot the last segment goes on (the convention of every
    law past its fitted speeds, module docstring); speeds are not negative.
    """
    x = np.maximum(np.asarray(x, float), KNOTS[0])[..., None]
    h = KNOTS[1] - KNOTS[0]
    inside = np.maximum(1.0 - np.abs(np.minimum(x, KNOTS[-1]) - KNOTS) / h, 0.0)
    past = np.maximum(x - KNOTS[-1], 0.0) / h
    return inside + past * np.r_[np.zeros(KNOTS.size - 2), -1.0, 1.0]


def speed_factor(x, knots):
    """g(x) of :class:`SpeedFactor` [-]: the piecewise-linear law of its values ``knots`` at :data:`KNOTS`
    (:func:`hats`), at speeds x [thetadot_r]; ``knots`` (..., knots) one law per leading index of x
    (a law per test of (tests, impacts) speeds) or one for all."""
    h = hats(x)
    k = np.asarray(knots, float)
    if 1 < k.ndim < h.ndim:
        k = k.reshape(k.shape[:-1] + (1,) * (h.ndim - k.ndim) + k.shape[-1:])
    return np.sum(h * k, axis=-1)


@dataclass(frozen=True)
class Hinge:
    """The rocking angles times ``ratio`` exp(+-``asymmetry``/2) on hinge +-1: a rounded or indented
    hinge (alpha_r = r alpha, Sect. 3), hinges that differ.  With ``rounding`` k the angle of a
    flight of apex A is a (1 - k) + k A (:func:`rocklab.physics.flight.flight_angle`)."""

    ratio: float = 1.0
    asymmetry: float = 0.0
    rounding: float | None = None

    def angles(self, a_pos, a_neg):
        """The rocking angles [rad] of hinges +1 and -1 of angles ``a_pos``, ``a_neg``."""
        h = self.asymmetry / 2
        return self.ratio * a_pos * math.exp(h), self.ratio * a_neg * math.exp(-h)


@dataclass(frozen=True)
class FlightLoss:
    """Losses between impacts (:func:`rocklab.physics.flight.loss_deceleration`): viscous ``zeta``
    [-], dry friction at the hinge ``mu_over_alpha`` (mu / alpha) and quadratic drag
    ``kappa_alpha`` (kappa alpha), set (not added) by the law."""

    zeta: float = 0.0
    mu_over_alpha: float = 0.0
    kappa_alpha: float = 0.0


@dataclass(frozen=True)
class Gap:
    """A one-sided wall swings inwards through g = ``over_alpha`` alpha before it strikes the
    transverse walls (Fig. 12): base impacts of Eq. 2, the transverse impact of Eqs. 12-13."""

    over_alpha: float = 0.0


@dataclass(frozen=True)
class Stop:
    """A landing slower than ``v_stop`` thetadot_r (Eq. 16) sticks: e = 0
    (:class:`rocklab.physics.impact.Sticking`)."""

    v_stop: float | np.ndarray = 0.0
