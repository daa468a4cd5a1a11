"""The one wall model: the base rocking model and what the causes' laws change.

Base model: a rigid block on the nominal alpha with the analytic e of its
boundary (Eq. 2 two-sided, Eq. 14 one-sided), released from rest at the
measured theta0.  A cause declares what it does to a wall once, as laws of
:mod:`rocklab.physics.law` (``Cause.laws(values)``), each of which says
what it does to the per-test arrays of the model
(:meth:`rocklab.physics.law.Law.act_on`, through :meth:`ModelParams.under`):
a law that acts in flight with a term of its own sets it with
:meth:`ModelParams.with_term`, and the closed forms and the simulators
read it from its declaration (:class:`rocklab.physics.law.FlightTerm`).  The
closed forms of a flight (:mod:`rocklab.physics.flight`) then give the
one-step predictions (:mod:`rocklab.diagnosis.evidence`), the
flight-by-flight free run (:func:`next_flight`, :func:`free_run`).

Design: the diagnosis needs the model of a whole series at once (per-test
arrays, a value per test where a cause takes one), the exact simulator one
wall; so :class:`ModelParams` is the model and the simulator's
:class:`~rocklab.simulation.rocking_model.RockingModel` is derived from one of its
rows by :func:`simulator`, the one place where the model's restitution,
gap and stop become impact laws of :mod:`rocklab.physics.impact`.  There is
no second mapping of the causes: the calibrated walls of the maps are
:func:`simulator` of the maps' wall (:mod:`rocklab.seismic.calibrated`).
This module knows no cause by name: the catalogue resolves names to laws
(:func:`rocklab.diagnosis.extended.model_params`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from rocklab.physics import impact as _impact
from rocklab.physics import law as _law
from rocklab.physics import restitution
from rocklab.physics.boundary import Boundary
from rocklab.physics.flight import (
    apex,
    apex_after,
    excursion_time,
    flight_angle,
    landing_speed,
    potential,
    quarter_period,
    quarter_period_linear,
)
from rocklab.physics.wall import overturning_velocity
from rocklab.simulation.batch import free_record
from rocklab.simulation.reference import simulate_free
from rocklab.simulation.rocking_model import RockingModel

#: A model wall is released at most this fraction below its instability angle.
RELEASE_MARGIN = 1e-3


@dataclass
class ModelParams:
    """Per-test arrays (shape (tests,)) of an extended model (:meth:`under` applies a law).

    ``extra`` holds the test log's columns a drift may follow
    (``"log:<column>"``, the test's place in the series' range, 0 to 1);
    ``terms`` the terms in flight of laws beyond the losses zeta, mu, kappa:
    ``(term, values)`` pairs, ``term`` a
    :class:`rocklab.physics.law.FlightTerm` and ``values`` a per-test array
    for each of its parameters (:meth:`with_term`); ``walls`` what the walls
    alone give (:meth:`of_walls`), shared with the models the laws make of
    this one.
    """

    alpha: np.ndarray
    p: np.ndarray
    one_sided: np.ndarray
    gap_model: np.ndarray  # one-sided walls modelled through the gap (Fig. 12)
    e0: np.ndarray  # signed base e, nominal alpha: Eq. 14, or Eq. 2 (two-sided, gap model)
    c_pos: np.ndarray  # multipliers of e on the hinge being left
    c_neg: np.ndarray
    amp_a: np.ndarray
    amp_b: np.ndarray
    a_pos: np.ndarray  # rocking angles of the hinges [rad]
    a_neg: np.ndarray
    rounding: np.ndarray  # dependence of the rocking angle on the flight's amplitude (flight.flight_angle)
    zeta: np.ndarray
    gap: np.ndarray  # [rad]
    stop: np.ndarray  # landing speed [thetadot_r] below which the wall stops dead (0: never)
    order: np.ndarray  # the test's place in its series, 0 (first) to 1 (last)
    # None: none, zeros of the shape of zeta once made
    mu: np.ndarray = None  # type: ignore[assignment]  # dry friction at the hinge [-] (flight.loss_deceleration)
    kappa: np.ndarray = None  # type: ignore[assignment]  # quadratic drag in flight [1/rad]
    extra: dict = field(default_factory=dict)
    speed_knots: np.ndarray | None = None  # (tests, knots): e / e_an at the knots of physics.law.SpeedFactor
    terms: tuple = ()
    walls: dict = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self):
        for name in ("mu", "kappa"):
            if getattr(self, name) is None:
                setattr(self, name, np.zeros_like(self.zeta))

    def of_walls(self):
        """What the walls alone give, per test: ``v_r``, thetadot_r of Eq. 16 [rad/s]; ``e_2s``,
        Housner's e (Eq. 2) and ``e_tr``, that of the transverse walls (Eqs. 12-13) [-].

        Made once for a model and the models its laws make of it (``walls`` goes with
        :func:`dataclasses.replace`), which keep its alpha and p: a fit evaluates thousands of them.
        A model of other alpha or p makes its own.
        """
        w = self.walls
        if w.get("alpha") is not self.alpha or w.get("p") is not self.p:
            w.clear()
            w.update(
                alpha=self.alpha,
                p=self.p,
                v_r=overturning_velocity(self.alpha, self.p),
                e_2s=restitution.two_sided(self.alpha),
                e_tr=restitution.transverse(self.alpha),
            )
        return w

    def flight_loss(self, like=None):
        """zeta, mu, kappa of the losses in flight (:func:`rocklab.physics.flight.loss_deceleration`),
        per test, broadcast against ``like``, and the laws' own ``terms`` where there are any: the
        keywords of the flight's closed forms on a flight's own angle (:meth:`flight`)."""
        out = {k: per_test(getattr(self, k), like) for k in ("zeta", "mu", "kappa")}
        if self.terms:
            out["terms"] = tuple((t, tuple(per_test(v, like) for v in values)) for t, values in self.terms)
        return out

    def flight_keywords(self, like=None):
        """:meth:`flight_loss` and k, the dependence of the rocking angle on the amplitude
        (:func:`rocklab.physics.flight.flight_angle`): the keywords of the flight's closed forms on
        the hinge's angle (:meth:`hinge`), which find the flight's own."""
        return {**self.flight_loss(like), "k": per_test(self.rounding, like)}

    def hinge(self, side):
        """Rocking angle of hinge ``side`` (array of +1 / -1) [rad]."""
        return np.where(side > 0, per_test(self.a_pos, side), per_test(self.a_neg, side))

    def flight(self, A, side):
        """Rocking angle [rad] of a flight of apex A [rad] on hinge ``side``
        (:func:`rocklab.physics.flight.flight_angle`)."""
        return flight_angle(A, self.hinge(side), per_test(self.rounding, side))

    def log_columns(self):
        """The columns of the test log the model holds (``extra``): :func:`log_columns` of its tests."""
        return tuple(k[4:] for k in self.extra if k.startswith("log:"))

    def place(self, column=None):
        """n of each test: its place in the series, or in the range of the test log's ``column``
        (0 to 1); a wall without the column (the maps' wall) stands for the middle of the series."""
        return self.order if column is None else self.extra.get(f"log:{column}", 0.5 + 0 * self.order)

    def under(self, law):
        """The model as ``law`` changes it (:meth:`rocklab.physics.law.Law.act_on`, the law's own
        declaration: this model knows no law by name).

        Raises
        ------
        TypeError
            For an object that is no :class:`rocklab.physics.law.Law`.
        """
        if not isinstance(law, _law.Law):
            raise TypeError(f"{type(law).__name__} is no law of rocklab.physics.law")
        return law.act_on(self)

    def with_term(self, term, *values):
        """The model with the term in flight ``term`` (:class:`rocklab.physics.law.FlightTerm`) at
        ``values``, one per-test array per parameter of the term: set, not added, as the losses are."""
        if len(values) != len(term.params):
            raise ValueError(f"{term.name} has the parameters {', '.join(term.params)}: {len(values)} values given")
        values = tuple(np.broadcast_to(np.asarray(v, float), self.alpha.shape) for v in values)
        return replace(self, terms=(*(tv for tv in self.terms if tv[0] != term), (term, values)))

    def with_base(self, base="analytic"):
        """The model on a literature base: ``"analytic"`` (itself), ``"zero"`` (e = 0, Liberatore &
        Spera 2003) or ``"two-sided-e"`` (e_an,2s for a one-sided wall, Hogan 1992)."""
        if base == "zero":
            return replace(self, e0=0.0 * self.e0, gap_model=np.zeros_like(self.gap_model))
        if base == "two-sided-e":
            return replace(self, e0=np.where(self.one_sided, -restitution.two_sided(self.alpha), self.e0))
        return self

    def row(self, i):
        """The model of test ``i`` (scalars)."""
        arrays = {k: np.asarray(v)[i] for k, v in vars(self).items() if isinstance(v, np.ndarray)}
        terms = tuple((t, tuple(np.asarray(v)[i] for v in values)) for t, values in self.terms)
        extra = {k: np.asarray(v)[i] for k, v in self.extra.items()}
        return replace(self, **arrays, extra=extra, terms=terms, walls={})


def stacked(models: Sequence[ModelParams]) -> ModelParams:
    """The models of several parameter vectors of one set of tests as one model of their tests
    repeated (:class:`ModelParams` of the same laws, their per-test arrays concatenated in order):
    the closed forms act element by element, so one call on the stack gives each model's values
    at the cost of one call."""
    first = models[0]
    names = [k for k, v in vars(first).items() if isinstance(v, np.ndarray)]
    arrays = {k: np.concatenate([getattr(m, k) for m in models]) for k in names}
    extra = {k: np.concatenate([m.extra[k] for m in models]) for k in first.extra}
    terms = tuple(
        (t, tuple(np.concatenate([m.terms[j][1][i] for m in models]) for i in range(len(values))))
        for j, (t, values) in enumerate(first.terms)
    )
    return replace(first, **arrays, extra=extra, terms=terms, walls={})


def branches(mp: ModelParams) -> tuple[bool, ...]:
    """Which branches of the closed forms of a flight the model ``mp`` takes: whether any test has a
    rocking angle that depends on the amplitude, viscous damping, dry friction, drag, each parameter
    of a term in flight, a law of the impact speed.  The closed forms choose a method on the whole
    array (:mod:`rocklab.physics.flight`: Newton's passes with friction or drag, fixed-point passes
    with viscous damping alone), so only models of one branch evaluate stacked
    (:func:`stacked`) as each alone."""
    arrays = (mp.rounding, mp.zeta, mp.mu, mp.kappa, *(v for _, values in mp.terms for v in values))
    return (*(bool(np.count_nonzero(x)) for x in arrays), mp.speed_knots is None)


def log_columns(tests):
    """The columns of the test log that the tests share (those :func:`rocklab.diagnosis.evidence.in_series_order`
    kept; none for a wall without a log)."""
    return tuple(sorted(set.intersection(*(set(getattr(t, "log", {})) for t in tests)))) if tests else ()


def per_test(x, like):
    """Per-test array broadcast against a (tests, impacts) array."""
    x = np.asarray(x)
    # getattr, not np.ndim: called a million times in a diagnosis, on arrays and scalars
    return x[:, None] if x.ndim == 1 and getattr(like, "ndim", 0) == 2 else x


def base_params(tests) -> ModelParams:
    """ModelParams of the base model (every cause at its null value)."""
    alpha = np.array([t.alpha for t in tests], float)
    ones = np.ones_like(alpha)
    return ModelParams(
        alpha=alpha,
        p=np.array([t.p for t in tests], float),
        one_sided=np.array([t.boundary == Boundary.ONE_SIDED for t in tests]),
        gap_model=np.zeros(alpha.shape, bool),
        e0=restitution.analytic([t.boundary for t in tests], alpha),
        c_pos=ones,
        c_neg=ones,
        amp_a=ones,
        amp_b=0.0 * ones,
        a_pos=alpha,
        a_neg=alpha,
        rounding=0.0 * ones,
        zeta=0.0 * ones,
        gap=0.0 * alpha,
        stop=0.0 * ones,
        order=np.array([t.order for t in tests], float),
        # the test log's columns a drift may follow (their place in the series' range, 0 to 1)
        extra={f"log:{c}": np.array([t.log[c] for t in tests], float) for c in log_columns(tests)},
    )


def model_of(tests, laws=(), base=None) -> ModelParams:
    """The base model of ``tests`` (``base``: its :func:`base_params`, already made) as ``laws`` change
    it, in their order (:meth:`ModelParams.under`)."""
    mp = base_params(tests) if base is None else base
    for law in laws:
        mp = mp.under(law)
    return mp


def release_rotation(theta0, a):
    """Rotation from which a model wall of instability angle a is released [rad]."""
    return np.minimum(theta0, (1.0 - RELEASE_MARGIN) * a)


def impact_speeds(v, side, mp: ModelParams, timed=True):
    """Take-off speed after an impact at speed v leaving hinge ``side``.

    Two-sided and gap-less one-sided walls: one impact, |e| v with e the
    base e times the scale, hinge factor and Eq. 17 bracket (clipped to
    |e| <= 1, as :mod:`rocklab.physics.impact`).  One-sided walls with a gap
    (Fig. 12): base impact (Eq. 2), flight on the inner hinge to the
    transverse walls (or back, if it cannot reach them), their impact,
    back to the base, base impact (Eq. 2).  The calibration of one-sided
    rocking (scale, Eq. 17) is that of the transverse impact, at its own
    velocity: it carries the dissipation that sets e_an,1s apart from
    e_an,2s (Sect. 3), and as the gap closes the sequence tends to Eq. 14
    with the same calibration.  A law of the impact speed
    (:class:`rocklab.physics.law.SpeedFactor`) acts last.  ``timed=False`` gives the take-off
    speed alone (the excursion's depth, duration and speeds returned as 0), for a caller that
    needs no more.

    Returns
    -------
    v_out : ndarray
        [rad/s]
    depth, duration : ndarray
        Depth [rad] and duration [s] of the excursion past theta = 0.
    v_in, v_back : ndarray
        Speeds just before and after the impact on the transverse walls
        (0 where there is none) [rad/s].
    """
    c_s = np.where(side > 0, per_test(mp.c_pos, side), per_test(mp.c_neg, side))
    amp_a, amp_b = per_test(mp.amp_a, side), per_test(mp.amp_b, side)
    walls = mp.of_walls()
    # thetadot_r (Eq. 16): Eq. 17's bracket and a law of the impact speed read the speeds against it
    vr = per_test(walls["v_r"], side)
    gm = per_test(mp.gap_model, side)
    through = gm.any()
    # every impact swings through the gap (a one-sided series with one): no impact on the base alone,
    # and the excursion's values are the impacts' own
    every = through and gm.all()
    if not every:
        e = per_test(mp.e0, side) * c_s
        v_out = np.abs(e * _impact.amplitude_factor_at(e, amp_a, amp_b, np.abs(v) / vr)) * v
    if through:
        p, a_in, g = per_test(mp.p, side), per_test(mp.a_neg, side), per_test(mp.gap, side)
        e_b = per_test(walls["e_2s"], side)
        e_tr = per_test(walls["e_tr"], side) * c_s
        v1 = e_b * v
        U = potential(np.minimum(g, a_in), a_in, p)
        reach = 0.5 * v1**2 > U
        vg = np.sqrt(np.maximum(v1**2 - 2 * U, 0.0))
        wg = np.abs(e_tr * _impact.amplitude_factor_at(e_tr, amp_a, amp_b, np.abs(vg) / vr)) * vg
        v2 = np.where(reach, np.sqrt(wg**2 + 2 * U), v1)
        v_out = e_b * v2 if every else np.where(gm, e_b * v2, v_out)
    if through and timed:
        d = np.where(reach, g, apex(0.5 * v1**2, a_in, p))
        on = reach if every else gm & reach
        depth = d if every else np.where(gm, d, 0.0)
        duration = np.where(gm, excursion_time(v1, v2, d, a_in, p), 0.0)
        v_in, w = np.where(on, vg, 0.0), np.where(on, wg, 0.0)
    else:
        depth, duration, v_in, w = (np.zeros(np.shape(v_out)) for _ in range(4))
    if mp.speed_knots is not None:
        # e / e_an = g(v / thetadot_r), after the base law of the other causes
        g = _law.speed_factor(np.asarray(v) / vr, mp.speed_knots)
        with np.errstate(invalid="ignore", divide="ignore"):
            # within the physical bounds of the impact as a whole: no faster take-off than landing
            v_out = v_out * _impact.bounded_factor(np.where(v > 0, v_out / v, 0.0), g)
    return v_out, depth, duration, v_in, w


def next_flight(v, side, mp: ModelParams):
    """One step of the free run: a landing at speed v leaving hinge ``side``, the impact, the next flight.

    A landing slower than the stop threshold (``mp.stop``) sticks.

    Returns
    -------
    A : ndarray
        Apex of the next flight [rad].
    side, a : ndarray
        Its hinge (+1 / -1) and the angle it rocks on [rad] (that hinge's,
        or :meth:`ModelParams.flight` of its apex where the angle depends on
        the amplitude).
    depth, duration : ndarray
        The excursion past theta = 0 of the impact (:func:`impact_speeds`).
    """
    v = np.where(v < mp.stop * mp.of_walls()["v_r"], 0.0, v)
    v_out, d, tau, _, _ = impact_speeds(v, side, mp)
    side = np.where(mp.one_sided, side, -side)
    a = mp.hinge(side)
    A = apex_after(v_out, a, mp.p, **mp.flight_keywords())
    return A, side, flight_angle(A, a, mp.rounding), d, tau


def release(S, mp: ModelParams, timed=True):
    """Speed at the first impact [rad/s] and time to it [s] from the measured release.

    From min(theta0, (1 - delta) alpha_s) with the screw's speed v0 towards
    the vertical: the energy adds v0^2 / 2; the time is the exact quarter
    period from rest, shortened by what v0 saves on the linearised fall
    (:func:`rocklab.physics.flight.quarter_period_linear`): most of the
    first quarter when the wall leaves the screw at its instability angle
    (:mod:`rocklab.lab.motion`, "Release and first quarter period").
    ``S`` is a :class:`rocklab.diagnosis.evidence.TestStack`; ``timed=False``
    skips the time (returned as None), for a caller that needs the speed only.
    """
    a0 = mp.hinge(S.side0)
    th = release_rotation(S.theta0, a0)
    # the fall from the release is a flight of apex th: on its angle where the angle depends on the amplitude
    v = np.sqrt(landing_speed(th, a0, mp.p, **mp.flight_keywords()) ** 2 + S.v0**2)
    if not timed:
        return v, None
    a0 = mp.flight(th, S.side0)
    saved = quarter_period_linear(th / a0) - quarter_period_linear(th / a0, S.v0 / (mp.p * a0))
    return v, quarter_period(th, a0, mp.p) - saved / mp.p


def free_run(S, mp: ModelParams, n_max=600):
    """Free run of the model from each test's release, flight by flight (:func:`next_flight`).

    Returns
    -------
    dict
        ``peaks``, ``t_before``, ``t_after``, ``depth`` as (tests, n_max)
        arrays (times from the measured release instant [s]) and ``t_first``
        (tests,).
    """
    T = len(S.tests)
    side = S.side0.copy()
    out = {k: np.zeros((T, n_max)) for k in ("peaks", "t_before", "t_after", "depth")}
    v, t = release(S, mp)
    first = t.copy()
    A = a = None  # apex and own angle of the previous flight, from the first impact on
    loss = mp.flight_loss()
    for k in range(n_max):
        if k:
            v = landing_speed(A, a, mp.p, **loss)
        A, side, a, d, tau = next_flight(v, side, mp)
        out["t_before"][:, k] = t
        out["t_after"][:, k] = t + tau
        out["depth"][:, k] = d
        out["peaks"][:, k] = A
        t = t + tau + 2.0 * quarter_period(A, a, mp.p)
        if np.all(A < 0.5 * S.floor):
            for key in out:
                out[key] = out[key][:, : k + 1]
            break
    out["t_first"] = first
    return out


def simulator(mp: ModelParams, base="analytic") -> RockingModel:
    """The exact simulator's :class:`rocklab.simulation.rocking_model.RockingModel` of one wall of the model
    (a row of :class:`ModelParams`, :meth:`ModelParams.row`).

    ``base``: as :meth:`ModelParams.with_base`.  The impact laws are the
    base law of the boundary under the model's restitution and Eq. 17
    (:func:`rocklab.physics.impact.calibrated`), the transverse impact of
    Eqs. 12-13 under them where the wall swings through a gap, and a stop
    (:class:`rocklab.physics.impact.Sticking`).  A law of the impact speed
    and a change of the base e (:class:`~rocklab.physics.law.SpeedFactor`,
    :class:`~rocklab.physics.law.HousnerLoss`) are the base e of the model
    (``mp.e0``) and a law of the impact speed after the others
    (:class:`rocklab.physics.impact.SpeedLaw`), as :func:`impact_speeds` reads
    them: on a wall swinging through a gap, a law of the excursion as a whole,
    read at the return from it (``excursion``).
    """
    one = bool(mp.one_sided)
    law: _impact.ImpactLaw
    if base == "zero":
        law = _impact.Zero()
    elif base == "two-sided-e" and one:
        law = _impact.Constant(-restitution.two_sided(float(mp.alpha)))
    else:
        # the model's base e: Eq. 14, or Eq. 2 (two-sided, or through a gap), as a change of it left it
        law = _impact.Constant(float(mp.e0))
    calibrated = _impact.calibrated(
        _impact.Transverse() if mp.gap_model else law, mp.c_pos, mp.c_neg, mp.amp_a, mp.amp_b
    )
    law, transverse = (law, calibrated) if mp.gap_model else (calibrated, None)
    if mp.speed_knots is not None:
        # through a gap the law acts on the excursion as a whole, as impact_speeds reads it
        law = _impact.SpeedLaw(law, mp.speed_knots, excursion=bool(mp.gap_model))
    if mp.stop > 0:
        # the landing from the outer hinge only, as free_run and stop_speeds
        # read it: with a gap the base law also serves the return from it
        sticking = _impact.Sticking(law, float(mp.stop))
        law = _impact.Sided(sticking, law) if mp.gap_model else sticking
    return RockingModel(
        alpha=float(mp.alpha),
        p=float(mp.p),
        boundary=Boundary.ONE_SIDED if one else Boundary.TWO_SIDED,
        impact=law,
        alpha_rock=float(mp.a_pos),
        alpha_neg=float(mp.a_neg),
        zeta=float(mp.zeta),
        mu=float(mp.mu),
        kappa=float(mp.kappa),
        terms=tuple((t, tuple(float(v) for v in values)) for t, values in mp.terms),
        gap=float(mp.gap),
        transverse_impact=transverse,
        hinge_rounding=float(mp.rounding),
    )


def simulate_test(test, model: RockingModel, t_end=None, fs=None, engine: bool = False):
    """Free run of a wall's simulator ``model`` (:func:`simulator`) from a measured test's release, on its clock.

    Released from the measured rotation and speed (:func:`release_rotation`).  ``engine``: run by the
    numba engine (:func:`rocklab.simulation.batch.free_record`, 8 RK4 steps per sample interval) where
    it holds the wall and the wall does not overturn, else by the exact reference.  Tolerance: the two
    records differed by 5.5e-9 rad at most on the 556 records the embedded campaign's diagnosis
    simulates (:func:`rocklab.diagnosis.extended.simulated_tests` and the RMS of theta/alpha of
    :func:`rocklab.diagnosis.extended.engineering_errors`; 2e-9 rad on a run of each cause,
    tests/test_every_law.py), a measured bound, not a proven one; the engine some ten times faster.

    Returns
    -------
    t, theta : ndarray
        Time [s] from the start of the record and rotation [rad] (NaN-free).
    """
    a0 = model.alpha_side(test.side0)
    fs = 1.0 / test.dt if fs is None else fs
    t_end = (test.t_end - test.t_release) * 1.2 + 1.0 if t_end is None else t_end
    theta0 = test.side0 * float(release_rotation(test.theta0, a0))
    if engine:
        try:
            run = free_record(model, theta0, -test.side0 * test.v_release, t_end=t_end, fs=fs)
        except NotImplementedError:
            run = None
        if run is not None:
            return run[0] + test.t_release, np.nan_to_num(run[1])
    h = simulate_free(
        model,
        theta0,
        -test.side0 * test.v_release,
        t_end=t_end,
        fs=fs,
        rtol=1e-9,
        atol=1e-12,
        # the record is all a caller reads: the apexes of the impacts' table are not searched for
        apexes=False,
    )
    return h.t + test.t_release, np.nan_to_num(h.theta)
