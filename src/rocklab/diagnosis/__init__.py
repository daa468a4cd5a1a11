"""Model diagnosis: what the literature model gets wrong, and why (Sect. 3, Figs. 14-15).

The paper does it once, by hand: Housner's e decays too slowly (Fig. 14a),
an experimentally calibrated e or the amplitude law of Eq. 17 fixes it
(Figs. 14b, 15b).  This module does it for any campaign, series by series.

Base model
----------
The model the literature would use: a rigid block on the nominal alpha,
Housner's e (Eq. 2) for two-sided walls and Eq. 14 for one-sided walls,
released from rest at the measured theta0.  Its free run is compared with
the measured motion by measures that mean something to an engineer
(:func:`engineering_errors`): impacts, duration, peak decay per impact, the
first quarter period, the flight time at a given amplitude, the lag of the
impacts and the RMS of theta/alpha over the motion.

Candidate causes (:data:`EFFECTS`), each a physical extension with its own
parameters and null value:

``restitution_scale``     e = c e_an                                  (c = 1)
``restitution_amplitude`` e/e_an = a - b (thetadot^-/thetadot_r)^2, Eq. 17   (b = 0)
``instability_angle``     the wall rocks on alpha_r = r alpha < alpha        (r = 1)
                          (rounded hinge, indented mortar, Sect. 3)
``flight_damping``        -2 zeta p thetadot between impacts               (zeta = 0)
``hinge_asymmetry``       two-sided: alpha_+- = alpha_r exp(+-s_alpha/2),
                          e_+- = e exp(+-s_e/2) on the hinge being left  (s = 0)
``contact_gap``           one-sided: the wall swings inwards through a gap
                          g = gamma alpha (two-sided rocking on the inner
                          hinge, Eq. 2 at the base, Eqs. 12-13 on the
                          transverse walls, Fig. 12)                     (gamma = 0)

A wall cannot stand beyond its instability angle: every model is released
from min(theta0, (1 - delta) alpha_s), delta = :data:`RELEASE_MARGIN`, at
rest.  The walls of the campaign were pushed by the screw until they fell,
so with the instability angle fitted their release is at alpha_r and the
fit is free on both sides of theta0.

Evidence
--------
Every flight of a test is seen through what :mod:`rocklab.lab.motion` measures:
the impact velocity thetadot^-_k and take-off velocity thetadot^+_k, the
apex |theta_k|, the impact instants and, for one-sided walls, the duration
of the excursion past theta = 0.  Each is predicted one step ahead from the
measured state before it (:func:`residuals`), so each group of residuals
(log ratios, model over measured) sees its own part of the physics:

==========  =================================================  =====================
group       prediction                                         carries
==========  =================================================  =====================
impact      thetadot^+_k from thetadot^-_k (the impact law)    c, a, b, s_e, gap
peak        |theta_k| from |theta_k-1| (theta0 for k = 1):     all, e and zeta
            fall, impact, rise                                 by their amplitude
time        flight time 2 T_1/4(|theta_k|, alpha_s)            r, s_alpha (not e)
gap_time    duration of the excursion past theta = 0           gap (one-sided)
==========  =================================================  =====================

A restitution change moves the impact and peak groups; an instability
angle moves the period-amplitude relation (time) and the energy-amplitude
relation (peak) and leaves the measured e alone; a loss in flight moves the
peaks and not the impact, so the causes are told apart by data a fit of
peaks alone would confound.  Velocities enter only through the impact ratio:
the derivative filter of :mod:`rocklab.lab.motion` assumes an undamped flight
and reads a damped one with a bias (:data:`FILTER_DAMPING_BIAS`), which the
impact group corrects; apexes and instants have none.  Each cause also has a
signature in the data that needs no fit (:func:`signatures`): the spread of
the measured e with the impact velocity, the instability angle that
Housner's arccosh(1/(1 - |theta|/alpha)) gives each flight time and the
fall from the release, the speed lost between take-off and the next impact,
e and alpha by hinge and push/pull release, the negative rotations.  A cause
is only named when its signature agrees.

Statistics
----------
Each group has its own noise, with a constant part and a part that grows
as the noise threshold over the amplitude (:func:`noise_variance`): the
likelihood is Gaussian with those variances, maximised by iteratively
reweighted least squares (:func:`fit`).  Causes are selected greedily
(:func:`select_effects`), the candidates in the order of BIC: one enters
when BIC drops by more than 10, its signature agrees, it lowers the
held-out deviance (tests left out, K-fold) beyond the noise of the paired
per-test differences, and its bootstrap (over tests) 95 % interval clears
the null value by the smallest effect worth naming (:data:`PRACTICAL`: at
the noise of these records a change of e by a thousandth is significant,
but it is no cause an engineer would model); after each entry the causes
already in are tested for removal.  ``unexplained`` flags what survives the
chosen model: a bias, or a trend with the impact index or the amplitude, of
a residual group, significant across tests (cluster-robust) and larger than
1 % and than the group's resolution; or walls that stop dead where the
model rocks on (:func:`end_of_motion`), unless a stop threshold explains
them.

Stopping dead
-------------
A stop is no residual of a flight but the absence of the next one, so it is
not fitted with the groups: once the chosen model is known and the walls
stop dead, each wall brackets the landing speed it stuck at
(:func:`stop_speeds`) and :func:`stop_threshold` estimates the series'
threshold (:class:`rocklab.physics.impact.Sticking`), named when it at least
halves the held-out error of the free run in the number of impacts.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from scipy import optimize, stats
from scipy.signal import savgol_filter

from rocklab.lab.motion import extract_motion, odd_samples
from rocklab.physics import impact as _impact
from rocklab.physics import restitution
from rocklab.physics.flight import (
    apex,
    apex_after,
    landing_speed,
    potential,
    quarter_period,
    transit_time,
)
from rocklab.physics.wall import overturning_velocity
from rocklab.simulation.model import RockingModel
from rocklab.simulation.reference import simulate_free

#: Candidate causes, in the order they are reported when tied.
EFFECTS = (
    "restitution_scale",
    "restitution_amplitude",
    "instability_angle",
    "flight_damping",
    "hinge_asymmetry",
    "contact_gap",
)

#: Parameters of each extension: (name, lower, upper, null value).
PARAMS = {
    "restitution_scale": [("c", 0.2, 2.0, 1.0)],
    "restitution_amplitude": [("a", 0.2, 2.5, 1.0), ("b", -3.0, 3.0, 0.0)],
    "instability_angle": [("alpha_r_over_alpha", 0.3, 1.2, 1.0)],
    "flight_damping": [("zeta", 0.0, 0.2, 0.0)],
    "hinge_asymmetry": [("s_alpha", -0.5, 0.5, 0.0), ("s_e", -0.5, 0.5, 0.0)],
    "contact_gap": [("gap_over_alpha", 0.0, 0.3, 0.0)],
}

#: Smallest departure from the null worth naming a cause for (a parameter whose
#: 95 % interval stays closer to the null than this is no cause).  ``a`` of
#: Eq. 17 has no null of its own: it is the scale.
PRACTICAL = {
    "c": 0.005,
    "b": 0.01,
    "alpha_r_over_alpha": 0.005,
    "zeta": 2e-4,
    "s_alpha": 0.005,
    "s_e": 0.003,
    "gap_over_alpha": 0.002,
}

#: The derivative filter of :mod:`rocklab.lab.motion` fits undamped flights: with a
#: viscous loss zeta it reads take-off speeds low and impact speeds high, so the
#: velocity ratio of an impact reads e (1 - 0.35 zeta) (median over impacts and
#: over walls with p = 3.0-4.3 rad/s and zeta = 0.005-0.02, exact simulator;
#: checked in tests/test_diagnosis.py).
FILTER_DAMPING_BIAS = 0.35

#: A model wall is released at most this fraction below its instability angle.
RELEASE_MARGIN = 1e-3

#: Floor of the variance of a residual group [log units^2] (noise-free data).
VAR_FLOOR = 1e-10

#: Residual structure smaller than this [log units over the range] is not reported.
STRUCTURE_MIN = 0.01

#: Significance of residual structure (cluster-robust t-test over tests).
STRUCTURE_P = 1e-3


# ---------------------------------------------------------------------------
# measured tests


@dataclass
class MeasuredTest:
    """What :mod:`rocklab.lab.motion` measured on one free-rocking test.

    Angles and velocities are magnitudes on the side of release (``side0``);
    arrays run over the impacts k = 1..n: ``peaks`` the apex |theta_k| after
    impact k [rad], ``v_before`` / ``v_after`` |thetadot| before and after it
    [rad/s], ``t_before`` / ``t_after`` its arrival at and departure from
    theta = 0 [s] (they differ when a one-sided wall swings into the gap),
    ``depth`` the excursion past theta = 0 [rad]; ``v_release`` the speed
    towards the vertical with which the wall left the screw [rad/s].
    """

    test_id: str
    alpha: float
    p: float
    boundary: str
    direction: str
    side0: int
    theta0: float
    peaks: np.ndarray
    v_before: np.ndarray
    v_after: np.ndarray
    t_before: np.ndarray
    t_after: np.ndarray
    depth: np.ndarray
    t_release: float
    t_end: float
    floor: float
    dt: float = 1.0 / 400.0
    v_release: float = 0.0
    alpha_fall: float = np.nan
    series: str = ""
    t: np.ndarray | None = field(default=None, repr=False)
    theta: np.ndarray | None = field(default=None, repr=False)

    @property
    def n_impacts(self) -> int:
        return int(self.peaks.size)

    @property
    def sides(self) -> np.ndarray:
        """Hinge left at impact k (+1 / -1, sign of theta before it)."""
        k = np.arange(self.n_impacts)
        return self.side0 * (np.ones(k.size) if self.boundary == "one-sided" else (-1.0) ** k)


def measured_test(record) -> MeasuredTest:
    """A :class:`MeasuredTest` from a reduced record.

    Parameters
    ----------
    record : dict
        ``test_id, t, theta, fs, alpha, p, boundary, direction`` (theta in
        rad, t in s), optionally ``series`` and ``motion`` (a
        :class:`rocklab.lab.motion.Motion` already extracted).
    """
    t = np.asarray(record["t"], float)
    theta = np.asarray(record["theta"], float)
    m = record.get("motion")
    if m is None:
        m = extract_motion(t, theta, record["fs"], record["boundary"], record["p"])
    imp = m.impacts
    n = min(len(imp), m.peaks.size)
    col = lambda name: np.abs(imp[name].to_numpy(float)[:n])  # noqa: E731
    return MeasuredTest(
        test_id=str(record.get("test_id", "")),
        alpha=float(record["alpha"]),
        p=float(record["p"]),
        boundary=record["boundary"],
        direction=str(record.get("direction", "push")),
        side0=int(m.sign),
        theta0=float(m.theta0),
        peaks=np.asarray(m.peaks[:n], float),
        v_before=col("thetadot_before"),
        v_after=col("thetadot_after"),
        t_before=imp.t_s.to_numpy(float)[:n],
        t_after=imp.t_after_s.to_numpy(float)[:n],
        depth=col("negative_excursion"),
        t_release=float(m.t_release),
        t_end=float(m.t_end),
        floor=float(m.peak_threshold),
        dt=1.0 / float(record["fs"]),
        v_release=max(float(m.thetadot_release), 0.0),
        alpha_fall=float(m.alpha_fall),
        series=str(record.get("series", "")),
        t=t,
        theta=theta,
    )


def records_by_series(datasets):
    """Group reduced tests (:mod:`rocklab.lab.reduction`) into the records of :func:`diagnose_campaign`."""
    out = {}
    for ds in datasets:
        a = ds.attrs
        out.setdefault(a["series"], []).append(
            {
                "test_id": a["test_id"],
                "series": a["series"],
                "t": ds.time.values,
                "theta": ds.theta.values,
                "fs": float(a["sampling_rate_hz"]),
                "alpha": float(a["alpha"]),
                "p": float(a["p"]),
                "boundary": a["boundary"],
                "direction": a["direction"],
            }
        )
    return dict(sorted(out.items()))


# ---------------------------------------------------------------------------
# the models


@dataclass
class ModelParams:
    """Per-test arrays (shape (tests,)) of an extended model."""

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
    zeta: np.ndarray
    gap: np.ndarray  # [rad]

    def hinge(self, side):
        """Rocking angle of hinge ``side`` (array of +1 / -1) [rad]."""
        return np.where(side > 0, _col(self.a_pos, side), _col(self.a_neg, side))

    def row(self, i):
        return ModelParams(**{k: np.asarray(v)[i] for k, v in vars(self).items()})


def _col(x, like):
    """Per-test array broadcast against a (tests, impacts) array."""
    x = np.asarray(x)
    return x[:, None] if np.ndim(like) == 2 and x.ndim == 1 else x


def null_values():
    """Every parameter at its null value (the base model)."""
    return {name: null for e in EFFECTS for name, _, _, null in PARAMS[e]}


def model_params(tests, ext=(), values=None):
    """ModelParams of the base model extended by ``ext`` with parameter ``values``."""
    v = null_values()
    v.update(values or {})
    alpha = np.array([t.alpha for t in tests], float)
    p = np.array([t.p for t in tests], float)
    one = np.array([t.boundary == "one-sided" for t in tests])
    gap_model = one & ("contact_gap" in ext)
    e0 = np.where(one & ~gap_model, restitution.one_sided(alpha), restitution.two_sided(alpha))
    ones = np.ones_like(alpha)
    ra = v["alpha_r_over_alpha"] * alpha
    return ModelParams(
        alpha=alpha,
        p=p,
        one_sided=one,
        gap_model=gap_model,
        e0=e0,
        c_pos=v["c"] * math.exp(v["s_e"] / 2) * ones,
        c_neg=v["c"] * math.exp(-v["s_e"] / 2) * ones,
        amp_a=v["a"] * ones,
        amp_b=v["b"] * ones,
        a_pos=ra * math.exp(v["s_alpha"] / 2),
        a_neg=ra * math.exp(-v["s_alpha"] / 2),
        zeta=v["zeta"] * ones,
        gap=v["gap_over_alpha"] * alpha,
    )


def release_rotation(theta0, a):
    """Rotation from which a model wall of instability angle a is released [rad]."""
    return np.minimum(theta0, (1.0 - RELEASE_MARGIN) * a)


def _amplitude_factor(e, v, mp, like):
    return _impact.amplitude_factor(
        e, _col(mp.amp_a, like), _col(mp.amp_b, like), v, _col(mp.alpha, like), _col(mp.p, like)
    )


def impact_speeds(v, side, mp: ModelParams):
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
    with the same calibration.

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
    c_s = np.where(side > 0, _col(mp.c_pos, side), _col(mp.c_neg, side))
    e = _col(mp.e0, side) * c_s
    v_out = np.abs(e * _amplitude_factor(e, v, mp, side)) * v
    depth, duration, v_in, w = (np.zeros(np.shape(v_out)) for _ in range(4))
    gm = _col(mp.gap_model, side)
    if np.any(gm):
        p, a_in, g = _col(mp.p, side), _col(mp.a_neg, side), _col(mp.gap, side)
        e_b = _col(restitution.two_sided(mp.alpha), side)
        e_tr = _col(restitution.transverse(mp.alpha), side) * c_s
        v1 = e_b * v
        U = potential(np.minimum(g, a_in), a_in, p)
        reach = 0.5 * v1**2 > U
        vg = np.sqrt(np.maximum(v1**2 - 2 * U, 0.0))
        wg = np.abs(e_tr * _amplitude_factor(e_tr, vg, mp, side)) * vg
        v2 = np.where(reach, np.sqrt(wg**2 + 2 * U), v1)
        d = np.where(reach, g, apex(0.5 * v1**2, a_in, p))
        tau = transit_time(v1, d, a_in, p) + transit_time(v2, d, a_in, p)
        v_out = np.where(gm, e_b * v2, v_out)
        depth = np.where(gm, d, 0.0)
        duration = np.where(gm, tau, 0.0)
        v_in = np.where(gm & reach, vg, 0.0)
        w = np.where(gm & reach, wg, 0.0)
    return v_out, depth, duration, v_in, w


def rocking_model(test: MeasuredTest, ext=(), values=None, base="analytic", stop=0.0) -> RockingModel:
    """The :class:`rocklab.simulation.model.RockingModel` of a diagnosis model, for one test.

    ``base``: ``"analytic"`` (Eq. 2 / Eq. 14), ``"two-sided-e"`` (e_an,2s used
    for a one-sided wall, Hogan 1992) or ``"zero"`` (e = 0, Liberatore & Spera
    2003).  ``stop``: landing speed [thetadot_r] below which the wall stops
    dead at the base (:class:`rocklab.physics.impact.Sticking`, :func:`stop_threshold`).
    """
    mp = model_params([test], ext, values).row(0)
    one = test.boundary == "one-sided"
    if base == "zero":
        law = _impact.Zero()
    elif base == "two-sided-e" and one:
        law = _impact.Constant(-restitution.two_sided(test.alpha))
    elif one and not mp.gap_model:
        law = _impact.OneSided()
    else:
        law = _impact.HousnerTwoSided()
    calibrated = _impact.Transverse() if mp.gap_model else law
    if mp.c_pos != mp.c_neg:
        calibrated = _impact.Sided(
            _impact.Scaled(calibrated, float(mp.c_pos)), _impact.Scaled(calibrated, float(mp.c_neg))
        )
    elif mp.c_pos != 1.0:
        calibrated = _impact.Scaled(calibrated, float(mp.c_pos))
    if mp.amp_b != 0.0 or mp.amp_a != 1.0:
        calibrated = _impact.AmplitudeLaw(calibrated, float(mp.amp_a), float(mp.amp_b))
    law, transverse = (law, calibrated) if mp.gap_model else (calibrated, None)
    if stop > 0:
        # the landing from the outer hinge only, as free_run and stop_speeds
        # read it: with a gap the base law also serves the return from it
        sticking = _impact.Sticking(law, stop)
        law = _impact.Sided(sticking, law) if mp.gap_model else sticking
    return RockingModel(
        alpha=test.alpha,
        p=test.p,
        boundary=test.boundary,
        impact=law,
        alpha_rock=float(mp.a_pos),
        alpha_neg=float(mp.a_neg),
        flight_damping=float(mp.zeta),
        gap=float(mp.gap),
        transverse_impact=transverse,
    )


def simulate_test(test: MeasuredTest, ext=(), values=None, base="analytic", t_end=None, fs=None, stop=0.0):
    """Free run of a diagnosis model from the test's measured release (rotation and speed), on its clock.

    Returns
    -------
    t, theta : ndarray
        Time [s] from the start of the record and rotation [rad] (NaN-free).
    """
    model = rocking_model(test, ext, values, base, stop)
    a0 = model.alpha_side(test.side0)
    fs = 1.0 / test.dt if fs is None else fs
    t_end = (test.t_end - test.t_release) * 1.2 + 1.0 if t_end is None else t_end
    h = simulate_free(
        model,
        test.side0 * float(release_rotation(test.theta0, a0)),
        -test.side0 * test.v_release,
        t_end=t_end,
        fs=fs,
        rtol=1e-9,
        atol=1e-12,
    )
    return h.t + test.t_release, np.nan_to_num(h.theta)


# ---------------------------------------------------------------------------
# one-step predictions and free runs


@dataclass
class _Stack:
    """Measured tests as padded (tests, impacts) arrays."""

    tests: list
    theta0: np.ndarray
    v0: np.ndarray
    side0: np.ndarray
    floor: np.ndarray
    vfloor: np.ndarray
    tfloor: np.ndarray
    A: np.ndarray
    vb: np.ndarray
    va: np.ndarray
    tb: np.ndarray
    ta: np.ndarray
    depth: np.ndarray
    side: np.ndarray
    k: np.ndarray

    @classmethod
    def of(cls, tests):
        n = max(max(t.n_impacts for t in tests), 1)

        def pad(name):
            return np.array([np.r_[getattr(t, name), np.full(n - t.n_impacts, np.nan)] for t in tests])

        side = np.array([np.r_[t.sides, np.full(n - t.n_impacts, np.nan)] for t in tests])
        floor = np.array([t.floor for t in tests])
        return cls(
            tests=list(tests),
            theta0=np.array([t.theta0 for t in tests]),
            v0=np.array([t.v_release for t in tests]),
            side0=np.array([t.side0 for t in tests], float),
            floor=floor,
            vfloor=np.array([t.p * t.floor for t in tests]),
            tfloor=np.array([t.dt for t in tests]),
            A=pad("peaks"),
            vb=pad("v_before"),
            va=pad("v_after"),
            tb=pad("t_before"),
            ta=pad("t_after"),
            depth=pad("depth"),
            side=np.nan_to_num(side, nan=1.0),
            k=np.tile(np.arange(1, n + 1, dtype=float), (len(tests), 1)),
        )

    def subset(self, idx):
        return replace(
            self,
            tests=[self.tests[i] for i in idx],
            **{k: v[idx] for k, v in vars(self).items() if isinstance(v, np.ndarray)},
        )


def _lr(model, meas, floor=0.0):
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.log((model + floor) / (meas + floor))


def residuals(S: _Stack, mp: ModelParams, cache=None):
    """One-step residuals of every group (module docstring), log(model / measured).

    ``cache`` (a dict) keeps the flight times between calls with the same
    hinge angles: a fit of the restitution moves nothing else.

    Returns
    -------
    dict
        Group name -> (tests, impacts) array, NaN where there is no observation.
    """
    f, vf = S.floor[:, None], S.vfloor[:, None]
    p, zeta = mp.p[:, None], mp.zeta[:, None]
    one = mp.one_sided[:, None]
    apex_side = np.where(one, S.side, -S.side)
    a_ap = mp.hinge(apex_side)
    v_hat, _, tau_hat, _, _ = impact_speeds(S.vb, S.side, mp)
    R = {"impact": _lr(v_hat * (1.0 - FILTER_DAMPING_BIAS * zeta), S.va, vf)}
    # peak to peak: from the measured apex before (theta0 at rest for the first), a landing,
    # the impact, a rise
    v_land = landing_speed(S.A[:, :-1], mp.hinge(S.side[:, 1:]), p, zeta)
    v_land = np.c_[release(S, mp)[0], v_land]
    R["peak"] = _lr(apex_after(impact_speeds(v_land, S.side, mp)[0], a_ap, p, zeta), S.A, f)
    key = mp.a_pos.tobytes() + mp.a_neg.tobytes()
    if cache is not None and cache.get("stack") is S and cache.get("angles") == key:
        R["time"] = cache["time"]
    else:
        # flights too close to the noise have apexes too uncertain to time them
        A_t = np.where(S.A[:, :-1] > 3 * f, S.A[:, :-1], np.nan)
        R["time"] = np.where(
            np.isfinite(A_t),
            _lr(2.0 * quarter_period(np.nan_to_num(A_t), a_ap[:, :-1], p), S.tb[:, 1:] - S.ta[:, :-1]),
            np.nan,
        )
        if cache is not None:
            cache.update(stack=S, angles=key, time=R["time"])
    if np.all(mp.one_sided):
        R["gap_time"] = _lr(tau_hat, S.ta - S.tb, S.tfloor[:, None])
    return R


def noise_covariates(S: _Stack):
    """Noise threshold over the amplitude behind each residual of :func:`residuals`.

    Velocities come from fits on the flights either side of an impact (the
    smaller flight sets their noise), apexes and flight times from their own
    flight, the gap from its depth and duration.
    """
    f = S.floor[:, None]
    A0 = np.c_[S.theta0, S.A]
    with np.errstate(invalid="ignore", divide="ignore"):
        x_imp = f / np.fmin(A0[:, :-1], A0[:, 1:])
        X = {
            "impact": x_imp,
            "peak": f / S.A,
            "time": f / S.A[:, :-1],
            "gap_time": S.tfloor[:, None] / (S.ta - S.tb + S.tfloor[:, None]),
        }
    return X


def covariates(S: _Stack):
    """Impact index and log amplitude of each residual of :func:`residuals` (structure tests)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        lv = np.log(S.vb)
    k, lA = S.k, np.log(np.maximum(S.A, 1e-300))
    pair = lambda a, b: {"impact index": a, "amplitude": b}  # noqa: E731
    return {"impact": pair(k, lv), "peak": pair(k, lA), "time": pair(k[:, :-1], lA[:, :-1]), "gap_time": pair(k, lv)}


def release(S: _Stack, mp: ModelParams):
    """Speed at the first impact [rad/s] and time to it [s] from the measured release.

    From min(theta0, (1 - delta) alpha_s) with the screw's speed v0 towards
    the vertical: the energy adds v0^2 / 2; the time is the exact quarter
    period from rest, shortened by what v0 saves on the linearised fall,
    t(w) = ln((alpha_s + sqrt(alpha_s^2 - x0^2 + w^2)) / (x0 + w)) / p with
    x0 = alpha_s - theta0 and w = v0 / p: most of the first quarter when the
    wall leaves the screw at its instability angle (:mod:`rocklab.lab.motion`,
    "Release and first quarter period").
    """
    a0 = mp.hinge(S.side0)
    th = release_rotation(S.theta0, a0)
    v = np.sqrt(landing_speed(th, a0, mp.p, mp.zeta) ** 2 + S.v0**2)

    def linear(w):
        x0 = a0 - th
        return np.log((a0 + np.sqrt(np.maximum(a0**2 - x0**2 + w**2, 0.0))) / (x0 + w)) / mp.p

    return v, quarter_period(th, a0, mp.p) - linear(0.0) + linear(S.v0 / mp.p)


def free_run(S: _Stack, mp: ModelParams, n_max=600, stop=0.0):
    """Free run of the model from each test's release, closed form.

    ``stop`` (scalar or per test): landing speed [thetadot_r] below which
    the wall stops dead (:func:`stop_threshold`).

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
    v_stop = stop * overturning_velocity(mp.alpha, mp.p)
    A = a = None  # apex and hinge of the previous flight, from the first impact on
    for k in range(n_max):
        if k:
            v = landing_speed(A, a, mp.p, mp.zeta)
        v = np.where(v < v_stop, 0.0, v)
        v_out, d, tau, _, _ = impact_speeds(v, side, mp)
        side = np.where(mp.one_sided, side, -side)
        a = mp.hinge(side)
        A = apex_after(v_out, a, mp.p, mp.zeta)
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


def end_of_motion(S: _Stack, mp: ModelParams, min_ratio=3.0, window_s=1.0):
    """Whether the walls stop earlier than the model can.

    The reduction ends the motion at the last flight it can measure; a wall
    that keeps rocking leaves smaller flights in the record after that, a
    wall that sticks does not.  From the last measured apex the model
    predicts the flights that follow; their largest apex from a tenth of
    ``window_s`` after the end (past the last return) to ``window_s`` is
    compared with the largest high-passed |theta| of the record there (the
    settling drift removed).  When in most
    tests the model rises ``min_ratio`` times above both the record and the
    noise threshold, the walls stop dead: a loss no extension of the
    catalogue has (an energy threshold, a stick at the hinge).

    Returns
    -------
    list of str
        One statement, or none.
    """
    ratios, speeds = [], []
    for i, ts in enumerate(S.tests):
        if ts.t is None or ts.t[-1] - ts.t_end < 0.5 * window_s:
            continue
        mpi = mp.row(i)
        k = ts.n_impacts - 1
        side = float(S.side[i, k]) if mpi.one_sided else -float(S.side[i, k])
        A, t, pred = ts.peaks[k], ts.t_after[k], 0.0
        lo, hi = ts.t_end + 0.1 * window_s, ts.t_end + window_s
        for _ in range(200):
            a = mpi.hinge(side)
            t_apex = t + quarter_period(A, a, mpi.p)
            if t_apex > hi or A < ts.floor:
                break
            if t_apex > lo:
                pred = max(pred, A)
            t = t_apex + quarter_period(A, a, mpi.p)
            v, _, tau, _, _ = impact_speeds(landing_speed(A, a, mpi.p, mpi.zeta), side, mpi)
            side = side if mpi.one_sided else -side
            A, t = apex_after(v, mpi.hinge(side), mpi.p, mpi.zeta), t + tau
        sel = (ts.t > lo) & (ts.t <= hi)
        win = odd_samples(0.25 / ts.dt)
        if sel.sum() < win:
            continue
        hp = ts.theta[sel] - savgol_filter(ts.theta[sel], win, 2)
        seen = float(np.percentile(np.abs(hp), 99))
        ratios.append(pred / max(seen, ts.floor))
        speeds.append(ts.v_before[-1] / float(overturning_velocity(ts.alpha, ts.p)))
    r = np.array(ratios)
    if r.size >= 3 and np.mean(r > min_ratio) > 0.5:
        return [
            f"end of motion: the walls stop dead where the model rocks on to {np.median(r):.0f} times what "
            f"the record shows ({int(np.sum(r > min_ratio))} of {r.size} tests; last measured impact at "
            f"{np.median(speeds):.2f} thetadot_r)"
        ]
    return []


def stop_speeds(S: _Stack, mp: ModelParams, min_ratio=3.0, tail_s=0.5):
    """Landing speeds [thetadot_r] between which each wall stopped dead.

    The last measured flight (apex A_n) was launched by a landing at v_n
    (from the apex before it) and lands at v_L < v_n.  Had the wall taken
    off again, the model's next apex would be A_next; where A_next is
    ``min_ratio`` times above the noise floor and the record runs ``tail_s``
    past the end, the reduction would have seen that flight, so the wall
    stuck at a landing speed in (v_L, v_n].

    Returns
    -------
    lo, hi : ndarray (tests,)
        v_L / thetadot_r and v_n / thetadot_r; NaN where the stop cannot be
        told from a flight too small to see.
    """
    T = len(S.tests)
    lo, hi = np.full(T, np.nan), np.full(T, np.nan)
    for i, ts in enumerate(S.tests):
        n = ts.n_impacts
        if n < 2 or ts.t is None or ts.t[-1] - ts.t_end < tail_s:
            continue
        mpi = mp.row(i)
        # hinge of the flight after impact k (0-based)
        hinge = [float(S.side[i, k]) if mpi.one_sided else -float(S.side[i, k]) for k in (n - 2, n - 1)]
        v_n = landing_speed(ts.peaks[n - 2], mpi.hinge(hinge[0]), mpi.p, mpi.zeta)
        v_l = landing_speed(ts.peaks[n - 1], mpi.hinge(hinge[1]), mpi.p, mpi.zeta)
        w = impact_speeds(v_l, hinge[1], mpi)[0]
        nxt = hinge[1] if mpi.one_sided else -hinge[1]
        if apex_after(w, mpi.hinge(nxt), mpi.p, mpi.zeta) < min_ratio * ts.floor:
            continue
        if v_l >= v_n:  # a last flight higher than the one before: noise, no bracket
            continue
        vr = float(overturning_velocity(ts.alpha, ts.p))
        lo[i], hi[i] = v_l / vr, v_n / vr
    return lo, hi


def _stop_estimate(lo, hi):
    """Threshold of brackets (lo, hi]: the geometric centre of their common
    part if they have one, else the geometric mean of their centres."""
    L, U = np.max(lo), np.min(hi)
    if L < U:
        return float(np.sqrt(L * U)), True
    return float(np.exp(0.5 * np.mean(np.log(lo) + np.log(hi)))), False


def stop_threshold(tests, ext=(), values=None, *, n_boot=200, seed=0, min_tests=3):
    """The landing speed below which the walls of a series stop dead, and what it gains.

    Each test brackets its own stop speed (:func:`stop_speeds`, a bracket as
    narrow as e); the series' threshold is the geometric mean of the bracket
    centres, with a bootstrap (over tests) 95 % interval and the test-to-test
    spread of log speed (Fig. 18's scatter of the number of cycles).  Where
    the brackets share a common part, one threshold fits every wall: the
    estimate is that part's geometric centre and the interval spans it
    (:func:`_stop_estimate`, also used for the tests left out).  Gain:
    the free run of the model (:func:`engineering_rows`) with each test's
    threshold taken from the other tests (leave one out) against the model
    without it, in the number of impacts and the duration of rocking.

    Returns
    -------
    dict or None
        None when fewer than ``min_tests`` tests (or half of them) show a
        stop; otherwise ``v_stop_over_vr``, ``ci95``, ``spread_log``,
        ``n_observed``, held-out rms errors ``n_impacts_rms`` and
        ``duration_pct_rms`` as (base, with threshold), and ``named`` (the
        held-out error in the number of impacts at least halved).
    """
    S = _Stack.of(tests)
    lo, hi = stop_speeds(S, model_params(tests, ext, values))
    ok = np.isfinite(lo)
    if ok.sum() < max(min_tests, 3, 0.5 * len(tests)):
        return None
    lo, hi = lo[ok], hi[ok]
    x = 0.5 * (np.log(lo) + np.log(hi))
    rng = np.random.default_rng(seed)
    boots = np.exp([rng.choice(x, x.size).mean() for _ in range(n_boot)])
    ci = [float(np.percentile(boots, 2.5)), float(np.percentile(boots, 97.5))]
    centre, common = _stop_estimate(lo, hi)
    if common:
        # one threshold fits every wall: it is known only within the common
        # bracket, however alike the walls' brackets are
        ci = [min(ci[0], float(np.max(lo))), max(ci[1], float(np.min(hi)))]
    obs = [tests[i] for i in np.flatnonzero(ok)]
    keep = ~np.eye(x.size, dtype=bool)
    loo = np.array([_stop_estimate(lo[k], hi[k])[0] for k in keep])

    def errors(rows):
        n = np.array([r["n_impacts"][1] - r["n_impacts"][0] for r in rows], float)
        d = np.array([100.0 * (r["duration_s"][1] / r["duration_s"][0] - 1.0) for r in rows], float)
        return float(np.sqrt(np.mean(n**2))), float(np.sqrt(np.mean(d**2)))

    (n0, d0), (n1, d1) = (
        errors(engineering_rows(obs, ext, values)),
        errors(engineering_rows(obs, ext, values, stop=loo)),
    )
    return {
        "v_stop_over_vr": centre,
        "ci95": ci,
        "common_bracket": common,
        "spread_log": float(x.std(ddof=1)),
        "n_observed": int(ok.sum()),
        "n_tests": len(tests),
        "n_impacts_rms": (n0, n1),
        "duration_pct_rms": (d0, d1),
        "named": n0 > 0 and n1 <= 0.5 * n0,
    }


# ---------------------------------------------------------------------------
# generic estimation engine: fit, held-out deviance, bootstrap, selection


class Problem:
    """A set of tests and the residual groups of models over them.

    Subclasses define :meth:`residuals` (group -> (tests, k) arrays for a
    subset made by :meth:`subset`), :meth:`candidates`, :meth:`starts`
    (data-driven starting values) and, optionally, :meth:`heldout_measures`
    and :meth:`covariates`.
    """

    n_tests: int

    def subset(self, idx):
        raise NotImplementedError

    def residuals(self, sub, ext, values):
        raise NotImplementedError

    def candidates(self):
        raise NotImplementedError

    def starts(self, ext):
        return {}

    def heldout_measures(self, sub, ext, values):
        return {}

    def covariates(self, sub):
        """Group -> {label: array like its residuals} for the structure tests."""
        return {}

    def noise(self, sub):
        """Noise covariate (threshold over amplitude) of every residual of :meth:`residuals`."""
        raise NotImplementedError

    def extra_structure(self, sub, ext, values):
        """Structure outside the residual groups (list of statements)."""
        return []

    def resolution(self, x):
        """Typical resolution [log units] of a group from its noise covariates ``x``."""
        return float(np.median(x))

    def params(self, ext):
        """Parameters of ``ext`` this problem's data can see."""
        return param_list(ext)


def param_list(ext):
    """Parameters of a combination of extensions, in :data:`EFFECTS` order."""
    return [q for e in EFFECTS if e in ext for q in PARAMS[e]]


def noise_variance(r, x):
    """Maximum-likelihood noise model v = s0^2 + s1^2 x^2 of residuals r [log units^2].

    ``x`` is the observation's noise threshold over its amplitude: records
    are precise to a fixed rotation, so the log residuals of small flights
    are noisier in proportion.  For a ratio rho = s1^2 / s0^2 the best s0^2
    is mean(r^2 / (1 + rho x^2)); the profile likelihood is then minimised
    over log rho (Brent), the ends rho = 0 and s0 = 0 included.
    Returns (s0^2, s1^2).
    """
    r2, x2 = r**2 + VAR_FLOOR, x**2
    n = r.size
    hom = (float(np.mean(r2)), 0.0)
    if n < 4 or np.ptp(x2) <= 1e-12 * max(float(np.max(x2)), 1e-300):
        return hom
    x2 = np.maximum(x2, 1e-300)

    def prof(t):
        d = 1.0 + math.exp(t) * x2
        return n * math.log(float(np.mean(r2 / d))) + float(np.sum(np.log(d)))

    lo, hi = -math.log(float(np.max(x2))) - 12.0, -math.log(float(np.min(x2))) + 12.0
    sol = optimize.minimize_scalar(prof, bounds=(lo, hi), method="bounded", options={"xatol": 1e-3})
    ends = {"hom": n * math.log(hom[0]), "prop": n * math.log(float(np.mean(r2 / x2))) + float(np.sum(np.log(x2)))}
    best = min(ends, key=ends.get)
    if sol.fun <= ends[best]:
        rho = math.exp(sol.x)
        s0 = float(np.mean(r2 / (1.0 + rho * x2)))
        return (s0, rho * s0)
    return hom if best == "hom" else (1e-300, float(np.mean(r2 / x2)))


def _obs(R, X):
    """Finite residuals and their noise covariates, per group."""
    out = {}
    for g, r in R.items():
        ok = np.isfinite(r) & np.isfinite(X[g])
        out[g] = (r[ok], X[g][ok])
    return out


def _variances(R, X):
    return {g: noise_variance(r, x) for g, (r, x) in _obs(R, X).items() if r.size >= 2}


def _deviance(R, X, var):
    """-2 log L (constants dropped) of residuals R under the group noise models ``var``."""
    out = 0.0
    for g, (r, x) in _obs(R, X).items():
        if g in var and r.size:
            v = var[g][0] + var[g][1] * x**2 + VAR_FLOOR
            out += float(np.sum(r**2 / v + np.log(v)))
    return out


@dataclass
class Fit:
    """A fitted model: parameter values, group noise models, -2 log L, observations."""

    ext: tuple
    values: dict
    var: dict
    m2ll: float
    n_obs: int

    @property
    def bic(self):
        return self.m2ll + len(self.values) * math.log(max(self.n_obs, 2))


def fit(problem: Problem, idx, ext, x0=None, n_irls=None) -> Fit:
    """Maximum-likelihood fit of ``ext`` on the tests ``idx``, noise model per group.

    Iteratively reweighted least squares: with the weights of the noise
    model (:func:`noise_variance`) of the previous pass, a bounded
    least-squares fit, then the noise model again; its fixed point is the
    maximum of the likelihood.  Non-convex parameters start both at their
    null and at the value the data suggest (:meth:`Problem.starts`); the
    better end wins.  ``x0`` (a previous fit) gives a single warm start, and
    two passes (``n_irls``, default 5 cold, 2 warm) then suffice.
    """
    sub = problem.subset(idx)
    X = problem.noise(sub)
    plist = problem.params(ext)
    if not plist:
        R = problem.residuals(sub, ext, {})
        var = _variances(R, X)
        return Fit(tuple(ext), {}, var, _deviance(R, X, var), sum(r.size for r, _ in _obs(R, X).values()))
    names = [q[0] for q in plist]
    lo = np.array([q[1] for q in plist], float)
    hi = np.array([q[2] for q in plist], float)
    nulls = np.array([q[3] for q in plist], float)
    inside = lambda x: np.clip(x, lo + 1e-6 * (hi - lo), hi - 1e-6 * (hi - lo))  # noqa: E731
    n_irls = n_irls or (2 if x0 is not None else 5)
    if x0 is not None:
        starts = [inside(np.array([x0[n] for n in names], float))]
    else:
        guess = problem.starts(ext)
        starts = [inside(nulls)]
        if any(n in guess for n in names):
            starts.append(inside(np.array([guess.get(n, nu) for n, nu in zip(names, nulls)], float)))
    R0 = problem.residuals(sub, ext, dict(zip(names, starts[0])))
    masks = {g: np.isfinite(r) & np.isfinite(X[g]) for g, r in R0.items()}
    masks = {g: m for g, m in masks.items() if m.sum() >= 2}
    xm = {g: X[g][m] for g, m in masks.items()}
    best = None
    for x in starts:
        R = problem.residuals(sub, ext, dict(zip(names, x)))
        var = _variances({g: R[g] for g in masks}, X)
        for _ in range(n_irls):
            w = {g: 1.0 / np.sqrt(var[g][0] + var[g][1] * xm[g] ** 2 + VAR_FLOOR) for g in masks}

            def res(xx, w=w):
                R = problem.residuals(sub, ext, dict(zip(names, xx)))
                return np.concatenate(
                    [np.nan_to_num(R[g][m], nan=1.0, posinf=1.0, neginf=-1.0) * w[g] for g, m in masks.items()]
                )

            sol = optimize.least_squares(res, x, bounds=(lo, hi), x_scale="jac", diff_step=1e-5, xtol=1e-9, ftol=1e-9)
            moved = np.max(np.abs(sol.x - x) / (hi - lo))
            x = sol.x
            R = problem.residuals(sub, ext, dict(zip(names, x)))
            var = _variances({g: np.where(m, R[g], np.nan) for g, m in masks.items()}, X)
            if moved < 1e-6:
                break
        R = {g: np.where(m, R[g], np.nan) for g, m in masks.items()}
        m2ll = _deviance(R, X, var)
        if best is None or m2ll < best.m2ll:
            n_obs = int(sum(m.sum() for m in masks.values()))
            best = Fit(tuple(ext), dict(zip(names, map(float, x))), var, m2ll, n_obs)
    return best


def _folds(n, k_max=5):
    k = n if n <= 6 else k_max
    idx = np.arange(n)
    return [idx[idx % k == j] for j in range(k)] if n > 1 else [idx]


def heldout(problem: Problem, ext, start=None):
    """Per-test held-out deviance of ``ext`` fitted on the other tests (K-fold), and measures.

    Returns
    -------
    dict
        ``deviance`` (per test, -2 log L per observation of the held-out test
        under the training fit) and the per-test arrays of
        :meth:`Problem.heldout_measures`.
    """
    n = problem.n_tests
    dev = np.full(n, np.nan)
    meas = {}
    for held in _folds(n):
        train = np.setdiff1d(np.arange(n), held) if n > 1 else held
        f = fit(problem, train, ext, x0=start)
        sub = problem.subset(held)
        X = problem.noise(sub)
        R = {g: r for g, r in problem.residuals(sub, ext, f.values).items() if g in f.var}
        for j, i in enumerate(held):
            Ri = {g: r[j : j + 1] for g, r in R.items()}
            Xi = {g: X[g][j : j + 1] for g in R}
            nobs = sum(r.size for r, _ in _obs(Ri, Xi).values())
            dev[i] = _deviance(Ri, Xi, f.var) / nobs if nobs else np.nan
        for name, x in problem.heldout_measures(sub, ext, f.values).items():
            meas.setdefault(name, np.full(n, np.nan))[held] = x
    return {"deviance": dev, **meas}


def bootstrap_ci(problem: Problem, fitted: Fit, n_boot=40, seed=0):
    """Percentile 95 % intervals of the parameters, whole tests resampled."""
    rng = np.random.default_rng(seed)
    names = list(fitted.values)
    draws = []
    for _ in range(n_boot):
        pick = rng.integers(0, problem.n_tests, problem.n_tests)
        # one reweighting pass: the noise model of the full fit serves the resample
        draws.append([fit(problem, pick, fitted.ext, x0=fitted.values, n_irls=1).values[k] for k in names])
    d = np.array(draws).reshape(len(draws), len(names))
    return {k: [float(np.percentile(d[:, i], 2.5)), float(np.percentile(d[:, i], 97.5))] for i, k in enumerate(names)}


def _paired(d):
    d = d[np.isfinite(d)]
    se = float(np.std(d, ddof=1) / math.sqrt(d.size)) if d.size > 1 else np.inf
    return float(np.mean(d)) if d.size else 0.0, se


def _improves(d):
    """Whether paired per-test improvements ``d`` are beyond the noise.

    The mean exceeds twice its standard error, or every one of at least five
    tests improved (one-sided sign test, p <= 1/32): with few tests that
    differ in how much they gain, the standard error alone is too strict.
    """
    d = d[np.isfinite(d)]
    gain, se = _paired(d)
    return gain > 2 * se or (d.size >= 5 and bool(np.all(d > 0)))


def _null_excluded(effect, ci):
    """Whether some parameter of ``effect`` stays clear of its null by a practical margin."""
    for name, _, _, null in PARAMS[effect]:
        if name in PRACTICAL and name in ci:
            lo, hi = ci[name]
            if lo > null + PRACTICAL[name] or hi < null - PRACTICAL[name]:
                return True
    return False


def _with(current, eff):
    """``current`` plus ``eff``; Eq. 17 replaces the plain scale (its a is the scale)."""
    new = set(current) | {eff}
    if eff == "restitution_amplitude":
        new.discard("restitution_scale")
    if eff == "restitution_scale" and "restitution_amplitude" in current:
        return None
    return tuple(e for e in EFFECTS if e in new)


def structure(problem: Problem, idx, ext, values):
    """Residual structure left by a model: bias and trends of each group, across tests.

    For each group, the per-test median (bias) and the within-test slopes on
    the covariates of :meth:`Problem.covariates` (impact index, log
    amplitude), each with a cluster-robust (by test) t-test, or for a
    covariate that is a property of the test the regression of the per-test
    means on it; reported when p < :data:`STRUCTURE_P` and the effect
    over the observed range exceeds :data:`STRUCTURE_MIN` and the median
    noise covariate of the group (its resolution, :meth:`Problem.resolution`).

    Returns
    -------
    list of str
    """
    sub = problem.subset(idx)
    R = problem.residuals(sub, ext, values)
    X = problem.noise(sub)
    cov = problem.covariates(sub)
    found = []
    for g, r in R.items():
        ok = np.isfinite(r)
        tests_with = np.flatnonzero(ok.sum(axis=1) >= 1)
        if tests_with.size < 3 or ok.sum() < 6:
            continue
        # structure below the group's typical resolution is no structure worth a cause
        size = max(STRUCTURE_MIN, problem.resolution(X[g][ok]))
        # per-test medians: one wild impact must not make a bias
        means = np.array([np.median(r[i][ok[i]]) for i in tests_with])
        t = stats.ttest_1samp(means, 0.0)
        if np.isfinite(t.pvalue) and t.pvalue < STRUCTURE_P and abs(means.mean()) > size:
            found.append(f"{g}: bias {means.mean():+.3f} (p = {t.pvalue:.1g})")
        for label, x in cov.get(g, {}).items():
            x = np.broadcast_to(x, r.shape)
            xo = np.where(ok, x, np.nan)[tests_with]
            if np.all(np.nanmax(xo, axis=1) == np.nanmin(xo, axis=1)):
                # a property of the test (a slenderness): its per-test medians against it
                xm = np.array([x[i][ok[i]][0] for i in tests_with])
                fit = stats.linregress(xm, means) if np.ptp(xm) > 0 else None
                slope, p_val = (fit.slope, fit.pvalue) if fit is not None else (0.0, np.nan)
                span = float(np.subtract(*np.percentile(xm, [90, 10])))
            else:
                slope, p_val, span = _within_slope(r, x, ok)
            if np.isfinite(p_val) and p_val < STRUCTURE_P and abs(slope * span) > size:
                found.append(f"{g}: trend with {label} {slope * span:+.3f} over the range (p = {p_val:.1g})")
    return found + problem.extra_structure(sub, ext, values)


def _within_slope(r, x, ok):
    """Within-test slope of r on x, cluster-robust p-value and the 10-90 % span of x."""
    ok = ok & np.isfinite(x)
    rows = [i for i in range(r.shape[0]) if ok[i].sum() >= 3]
    if len(rows) < 3:
        return 0.0, np.nan, 0.0
    xs = [x[i][ok[i]] - x[i][ok[i]].mean() for i in rows]
    rs = [r[i][ok[i]] - r[i][ok[i]].mean() for i in rows]
    sxx = sum(float(a @ a) for a in xs)
    if sxx <= 0:
        return 0.0, np.nan, 0.0
    beta = sum(float(a @ b) for a, b in zip(xs, rs)) / sxx
    meat = sum(float(a @ (b - beta * a)) ** 2 for a, b in zip(xs, rs))
    se = math.sqrt(meat) / sxx
    allx = np.concatenate([x[i][ok[i]] for i in rows])
    span = float(np.subtract(*np.percentile(allx, [90, 10])))
    if se == 0:
        return beta, 0.0 if beta else 1.0, span
    return beta, float(2 * stats.t.sf(abs(beta / se), len(rows) - 1)), span


def select_effects(problem: Problem, *, signature=None, n_boot=40, max_effects=4, seed=0, bic_margin=10.0):
    """Greedy forward selection of the causes the data carry, with removal tests.

    Parameters
    ----------
    problem : Problem
    signature : dict, optional
        effect -> {"supports": bool, ...}; an effect whose signature does not
        support it is never named.
    n_boot : int
        Bootstrap resamples for the 95 % intervals.
    bic_margin : float
        BIC must drop by more than this (strong evidence, Kass & Raftery 1995).

    Returns
    -------
    dict
        ``effects`` (chosen, in order of entry), ``fit`` (:class:`Fit`),
        ``ci`` (parameter intervals), ``base``/``final`` held-out results,
        ``steps`` (the held-out result after each entry), ``rejected``
        (effect -> reason), ``structure`` (what the chosen model leaves) and
        ``weak`` (candidates turned down that would remove all of it).
    """
    all_idx = np.arange(problem.n_tests)
    signature = signature or {}
    fits = {}

    def fit_of(ext):
        # a fit is deterministic: the rounds, the removals and the weak-evidence
        # pass meet the same models again
        if ext not in fits:
            fits[ext] = fit(problem, all_idx, ext)
        return fits[ext]

    current = ()
    cur_fit = fit_of(current)
    cur_ho = heldout(problem, current)
    base_ho = cur_ho
    steps, rejected, ci = {}, {}, {}
    for _ in range(max_effects):
        # candidates in the order of their information criterion; the held-out test and the
        # bootstrap, the costly steps, only until one passes
        cands = []
        for eff in problem.candidates():
            ext = _with(current, eff) if eff not in current else None
            if ext is None or ext == current or rejected.get(eff, "").startswith("95%"):
                continue
            f = fit_of(ext)
            dbic = f.bic - cur_fit.bic
            if dbic > -bic_margin:
                rejected[eff] = f"BIC {dbic:+.1f}"
            elif not signature.get(eff, {}).get("supports", True):
                rejected[eff] = f"BIC {dbic:+.1f} but its signature in the data is absent"
            else:
                cands.append((dbic, eff, ext, f))
        accepted = False
        for dbic, eff, ext, f in sorted(cands, key=lambda c: c[0]):
            ho = heldout(problem, ext, start=f.values)
            d = cur_ho["deviance"] - ho["deviance"]
            gain, se = _paired(d)
            if not _improves(d):
                rejected[eff] = f"held-out deviance gain {gain:.3g} within the noise (standard error {se:.2g})"
                continue
            c = bootstrap_ci(problem, f, n_boot=n_boot, seed=seed)
            if not _null_excluded(eff, c):
                rejected[eff] = "95% interval within the smallest effect worth naming of its null value"
                continue
            rejected.pop(eff, None)
            current, cur_fit, cur_ho, ci = ext, f, ho, c
            steps[eff] = {"heldout": ho, "gain": gain, "se": se, "dbic": dbic}
            accepted = True
            break
        if not accepted:
            break
        # removal: a cause that entered earlier may be carried by the new one
        for old in [e for e in current if e != eff and e in steps]:
            ext = tuple(e for e in current if e != old)
            f = fit_of(ext)
            ho = heldout(problem, ext, start=f.values)
            loss, se = _paired(ho["deviance"] - cur_ho["deviance"])
            if not _improves(ho["deviance"] - cur_ho["deviance"]) or f.bic - cur_fit.bic < bic_margin:
                rejected[old] = f"carried by {eff} (removing it costs {loss:.3g} +- {se:.2g} held out)"
                steps.pop(old)
                current, cur_fit, cur_ho = ext, f, ho
                ci = bootstrap_ci(problem, f, n_boot=n_boot, seed=seed) if ext else {}
    found = structure(problem, all_idx, current, cur_fit.values)
    # structure that a candidate turned down by the held-out test or the bootstrap would remove
    # is weak evidence for it, not something outside the catalogue
    weak = {}
    if found:
        for eff in problem.candidates():
            ext = _with(current, eff) if eff not in current else None
            if ext is not None and ext != current and signature.get(eff, {}).get("supports", True):
                f = fit_of(ext)
                if not structure(problem, all_idx, ext, f.values):
                    weak[eff] = {"params": f.values, "reason": rejected.get(eff, "")}
    return {
        "effects": list(current),
        "fit": cur_fit,
        "ci": ci,
        "base": base_ho,
        "final": cur_ho,
        "steps": steps,
        "rejected": rejected,
        "structure": found,
        "weak": weak,
    }


# ---------------------------------------------------------------------------
# the rocking-wall problem


class WallProblem(Problem):
    """Free-rocking tests of one boundary condition (a series) as a :class:`Problem`."""

    def __init__(self, tests):
        self.tests = list(tests)
        self.n_tests = len(self.tests)
        self.S = _Stack.of(self.tests)
        self.boundary = self.tests[0].boundary
        self._sig = None
        self._cache = {}

    def subset(self, idx):
        return self.S.subset(np.asarray(idx))

    def residuals(self, sub, ext, values):
        return residuals(sub, model_params(sub.tests, ext, values), self._cache)

    def covariates(self, sub):
        return covariates(sub)

    def noise(self, sub):
        return noise_covariates(sub)

    def extra_structure(self, sub, ext, values):
        return end_of_motion(sub, model_params(sub.tests, ext, values))

    def candidates(self):
        if self.boundary == "one-sided":
            return [e for e in EFFECTS if e != "hinge_asymmetry"]
        return [e for e in EFFECTS if e != "contact_gap"]

    @property
    def signature(self):
        if self._sig is None:
            self._sig = signatures(self.tests)
        return self._sig

    def starts(self, ext):
        s = self.signature
        return {
            "alpha_r_over_alpha": s["instability_angle"]["value"],
            "zeta": max(s.get("flight_damping", {}).get("zeta", 0.0), 1e-4),
            "gap_over_alpha": max(s.get("contact_gap", {}).get("value", 0.0), 1e-3),
            "c": s.get("restitution_scale", {}).get("value", 1.0),
            "a": s.get("restitution_scale", {}).get("value", 1.0),
            **{k: s.get("hinge_asymmetry", {}).get(k, 0.0) for k in ("s_alpha", "s_e")},
        }

    def heldout_measures(self, sub, ext, values):
        mp = model_params(sub.tests, ext, values)
        run = free_run(sub, mp, n_max=sub.A.shape[1])
        R = residuals(sub, mp)
        M = run["peaks"][:, : sub.A.shape[1]]
        F = _lr(M, sub.A[:, : M.shape[1]], sub.floor[:, None])
        rms = lambda x: np.sqrt(np.nanmean(x**2, axis=1))  # noqa: E731
        with np.errstate(invalid="ignore"):
            return {
                "free_run_log_peak_rms": rms(F),
                "impact_rms": rms(R["impact"]),
                "time_rms": rms(R["time"]) if np.isfinite(R["time"]).any() else np.full(len(sub.tests), np.nan),
                "peak_rms": rms(R["peak"]),
            }


# ---------------------------------------------------------------------------
# signatures in the data, independent of the fits


def series_level(x, ok):
    """Mean over tests of the per-test medians of x where ok: one level per test, robust within it."""
    med = [np.median(x[i][ok[i]]) for i in range(x.shape[0]) if ok[i].any()]
    return float(np.mean(med)) if med else np.nan


def flight_time_alpha(A, T, p):
    """Instability angle that Housner's closed form gives a flight of apex A and duration T [rad].

    Inverts T = (2/p) arccosh(1 / (1 - A/a)): a = A / (1 - sech(p T / 2)).
    """
    return A / (1.0 - 1.0 / np.cosh(0.5 * p * T))


def signatures(tests):
    """Evidence for each cause that needs no model fit.

    Returns
    -------
    dict
        effect -> {"value": ..., "supports": bool, "text": str} (plus
        ``zeta`` for flight damping, a starting value).
    """
    S = _Stack.of(tests)
    one = tests[0].boundary == "one-sided"
    alpha = np.array([t.alpha for t in tests])[:, None]
    p = np.array([t.p for t in tests])[:, None]
    e_an = np.abs(np.where(one, restitution.one_sided(alpha), restitution.two_sided(alpha)))
    big = S.A > 3 * S.floor[:, None]
    out = {}
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = (S.va / S.vb) / e_an
        vr = S.vb / overturning_velocity(alpha, p)
    ok = np.isfinite(ratio) & big
    e, v2 = ratio[ok], vr[ok] ** 2
    if e.size >= 3:
        level = series_level(ratio, ok)
        lo, hi = np.percentile(e, [25, 75])
        out["restitution_scale"] = {
            "value": level,
            "supports": bool(abs(level - 1) > PRACTICAL["c"]),
            "text": f"measured e/e_an = {level:.3f} (mean over tests of their medians; "
            f"IQR of the {e.size} impacts {lo:.3f}-{hi:.3f})",
        }
        if np.ptp(v2) > 0:
            sl = stats.linregress(v2, e)
            out["restitution_amplitude"] = {
                "value": float(-sl.slope),
                "supports": bool(sl.pvalue < 0.01 and abs(sl.slope) > PRACTICAL["b"]),
                "text": f"e/e_an against (thetadot^-/thetadot_r)^2: slope {sl.slope:+.3f} (p = {sl.pvalue:.2g})",
            }
    # period-amplitude: Housner's closed form inverted on every flight between two impacts
    with np.errstate(invalid="ignore", divide="ignore"):
        a_T = flight_time_alpha(S.A[:, :-1], S.tb[:, 1:] - S.ta[:, :-1], p) / alpha
    a_T = np.where(big[:, :-1], a_T, np.nan)
    r0 = S.theta0 / alpha[:, 0]
    fall = np.array([t.alpha_fall / t.alpha for t in tests])
    med_T = float(np.nanmedian(a_T)) if np.isfinite(a_T).any() else np.nan
    med_f = float(np.nanmedian(fall)) if np.isfinite(fall).any() else np.nan
    value = med_T if np.isfinite(med_T) else (med_f if np.isfinite(med_f) else 1.0)
    out["instability_angle"] = {
        "value": float(value),
        "supports": bool(
            (np.isfinite(med_T) and med_T < 1 - PRACTICAL["alpha_r_over_alpha"])
            or (np.isfinite(med_f) and med_f < 1 - PRACTICAL["alpha_r_over_alpha"])
        ),
        "text": f"flight times give alpha_r/alpha = {med_T:.3f} (Housner's closed form, median of "
        f"{int(np.isfinite(a_T).sum())} flights); the fall from the release {med_f:.3f}; "
        f"theta0/alpha = {np.median(r0):.3f}",
    }
    with np.errstate(invalid="ignore", divide="ignore"):
        fl = S.vb[:, 1:] / S.va[:, :-1]
    fl = fl[np.isfinite(fl) & big[:, :-1]]
    if fl.size >= 3:
        med = float(np.median(fl))
        w = stats.wilcoxon(fl - 1.0, alternative="less") if np.ptp(fl) > 0 else None
        pv = float(w.pvalue) if w is not None else 1.0
        # 1 - v_land/v_off ~ 4 zeta p int|thetadot| / v_off^2 ~ zeta pi / 2 at small amplitude
        out["flight_damping"] = {
            "value": med,
            "zeta": float(max(2.0 * (1.0 - med) / math.pi, 0.0)),
            "supports": bool(pv < 0.01 and med < 1 - 2e-4),
            "text": f"impact speed / previous take-off speed = {med:.4f} (median of {fl.size} flights, "
            f"Wilcoxon p = {pv:.2g}; 1 = no loss in flight)",
        }
    if not one:
        out["hinge_asymmetry"] = _asymmetry_signature(tests, S, ratio, a_T, ok, big)
    else:
        d = S.depth[np.isfinite(S.depth)]
        f = np.broadcast_to(S.floor[:, None], S.depth.shape)[np.isfinite(S.depth)]
        seen = d > f
        med = float(np.median((S.depth / alpha)[np.isfinite(S.depth)][seen])) if seen.any() else 0.0
        out["contact_gap"] = {
            "value": med,
            "supports": bool(seen.size and seen.mean() >= 0.25),
            "text": f"{int(seen.sum())} of {d.size} impacts with negative rotations (median depth {med:.4f} alpha)",
        }
    return out


def _asymmetry_signature(tests, S, ratio, a_T, ok, big):
    parts, ps, start = [], [], {}
    plus = S.side > 0
    a_, b_ = ratio[ok & plus], ratio[ok & ~plus]
    if a_.size >= 3 and b_.size >= 3:
        u = stats.mannwhitneyu(a_, b_)
        ps.append((u.pvalue, abs(np.median(a_) / np.median(b_) - 1)))
        start["s_e"] = float(np.log(np.median(a_) / np.median(b_)))
        parts.append(f"e/e_an leaving hinge +/-: {np.median(a_):.3f} / {np.median(b_):.3f} (p = {u.pvalue:.2g})")
    # the apex of flight k is on hinge -side_k
    ta, tb = a_T[~plus[:, :-1]], a_T[plus[:, :-1]]
    ta, tb = ta[np.isfinite(ta)], tb[np.isfinite(tb)]
    if ta.size >= 3 and tb.size >= 3:
        u = stats.mannwhitneyu(ta, tb)
        ps.append((u.pvalue, abs(np.median(ta) / np.median(tb) - 1)))
        start["s_alpha"] = float(np.log(np.median(ta) / np.median(tb)))
        parts.append(
            f"alpha_r/alpha from flights on hinge +/-: {np.median(ta):.3f} / {np.median(tb):.3f} (p = {u.pvalue:.2g})"
        )
    push = np.array([t.side0 > 0 for t in tests])
    if push.sum() >= 2 and (~push).sum() >= 2:
        r0 = S.theta0 / np.array([t.alpha for t in tests])
        w = stats.ttest_ind(r0[push], r0[~push], equal_var=False)
        ps.append((w.pvalue, abs(np.mean(r0[push]) / np.mean(r0[~push]) - 1)))
        parts.append(
            f"theta0/alpha pushed / pulled: {np.mean(r0[push]):.3f} / {np.mean(r0[~push]):.3f} (p = {w.pvalue:.2g})"
        )
    sup = any(pv < 0.01 and size > PRACTICAL["s_e"] for pv, size in ps)
    return {
        "value": float(min((pv for pv, _ in ps), default=1.0)),
        "supports": bool(sup),
        **start,
        "text": "; ".join(parts) if parts else "one hinge only",
    }


# ---------------------------------------------------------------------------
# engineering measures


def engineering_rows(tests, ext=(), values=None, base="analytic", n_max=600, stop=0.0):
    """Per-test measures of a model's free run against the measured motion.

    Returns
    -------
    list of dict
        ``n_impacts``, ``duration_s``, ``decay_pct`` (mean peak decay per
        impact over the impacts both have), ``first_quarter_p`` (p T_1/4),
        ``flight_time_pct`` (model flight time at the measured apex over the
        measured one, minus 1), ``lag_s`` / ``lag_cycles`` (model minus
        measured instant of the last impact both have), ``log_peak_rms``;
        each as a (measured, model) pair where both exist.
    """
    S = _Stack.of(tests)
    mp = model_params(tests, ext, values)
    if base == "zero":
        mp = replace(mp, e0=0.0 * mp.e0, gap_model=np.zeros_like(mp.gap_model))
    elif base == "two-sided-e":
        mp = replace(mp, e0=np.where(mp.one_sided, -restitution.two_sided(mp.alpha), mp.e0))
    run = free_run(S, mp, n_max, stop)
    R = residuals(S, mp)
    rows = []
    for i, ts in enumerate(tests):
        M = run["peaks"][i]
        # the model is observed like the wall: flights above the noise threshold
        seen = M >= ts.floor
        n_mod = int(np.argmax(~seen)) if not seen.all() else M.size
        n_meas = ts.n_impacts
        N = min(n_mod, n_meas)
        dur_mod = run["t_before"][i, n_mod] if n_mod < M.size else run["t_before"][i, -1]
        rel = lambda x, n, ts=ts: 100.0 * (1.0 - (x / ts.theta0) ** (1.0 / n)) if n else np.nan  # noqa: E731
        t_meas = ts.t_before - ts.t_release
        lag = run["t_before"][i, N - 1] - t_meas[N - 1] if N else np.nan
        cyc = 2.0 * (t_meas[N - 1] - t_meas[0]) / (N - 1) if N > 1 else 2.0 * t_meas[0]
        ft = R["time"][i]
        with np.errstate(invalid="ignore"):
            F = _lr(np.r_[M, np.zeros(max(n_meas - M.size, 0))][:n_meas], ts.peaks, ts.floor)
        rows.append(
            {
                "n_impacts": (n_meas, n_mod),
                "duration_s": (ts.t_end - ts.t_release, dur_mod),
                "decay_pct": (rel(ts.peaks[N - 1], N), rel(M[N - 1], N)) if N else (np.nan, np.nan),
                "first_quarter_p": (ts.p * t_meas[0], ts.p * run["t_first"][i]) if n_meas else (np.nan, np.nan),
                "flight_time_pct": 100.0 * (math.exp(np.nanmedian(ft)) - 1.0) if np.isfinite(ft).any() else np.nan,
                "lag_s": lag,
                "lag_cycles": lag / cyc if N else np.nan,
                "common_impacts": N,
                "log_peak_rms": float(np.sqrt(np.nanmean(F**2))) if n_meas else np.nan,
            }
        )
    return rows


def history_rms(test: MeasuredTest, ext=(), values=None, base="analytic", stop=0.0):
    """RMS of (theta_model - theta_measured) / alpha over the measured motion (exact simulator)."""
    if test.t is None:
        return np.nan
    t, th = simulate_test(test, ext, values, base, stop=stop)
    sel = (test.t >= test.t_release) & (test.t <= test.t_end)
    m = np.interp(test.t[sel], t, th, right=0.0)
    return float(np.sqrt(np.mean((m - test.theta[sel]) ** 2)) / test.alpha)


def summarise_rows(rows):
    """Means over tests of :func:`engineering_rows` (measured, model)."""
    out = {}
    for key in rows[0]:
        vals = [r[key] for r in rows]
        if isinstance(vals[0], tuple):
            arr = np.array(vals, float)
            out[key] = {"measured": finite_mean(arr[:, 0]), "model": finite_mean(arr[:, 1])}
        else:
            out[key] = finite_mean(np.array(vals, float))
    return out


def engineering_errors(tests, ext=(), values=None, base="analytic", n_history=2, stop=0.0):
    """Series means of :func:`engineering_rows` and the RMS of theta/alpha on ``n_history`` tests."""
    out = summarise_rows(engineering_rows(tests, ext, values, base, stop=stop))
    rms = [history_rms(t, ext, values, base, stop) for t in tests[:n_history]]
    out["rms_theta_over_alpha"] = finite_mean(rms) if rms else None
    return out


def what_is_wrong(errors, model="the simulation"):
    """Plain statement, in numbers, of where a model's free run departs from the tests.

    Returns
    -------
    (str, bool)
        The statement and whether any measure departs beyond its tolerance
        (duration 20 %, decay 1 point, quarter period 10 %, flight time 3 %,
        lag 0.5 cycle).
    """
    e = errors
    n, T, d, q = e["n_impacts"], e["duration_s"], e["decay_pct"], e["first_quarter_p"]
    parts, off = [], False
    # the duration decides: the reduction cannot resolve the last, shortest flights, so the
    # counts of impacts may differ where the motions end together
    if T["model"] > 1.2 * T["measured"]:
        parts.append(
            f"{model} keeps rocking for {T['model']:.1f} s ({n['model']:.0f} impacts) where the wall "
            f"stops after {T['measured']:.1f} s ({n['measured']:.0f} impacts)"
        )
        off = True
    elif T["model"] < 0.8 * T["measured"]:
        parts.append(
            f"{model} comes to rest after {T['model']:.1f} s ({n['model']:.0f} impacts) where the wall "
            f"rocks for {T['measured']:.1f} s ({n['measured']:.0f} impacts)"
        )
        off = True
    else:
        parts.append(
            f"{model} rocks for {T['model']:.1f} s ({n['model']:.0f} impacts), the wall for "
            f"{T['measured']:.1f} s ({n['measured']:.0f} impacts)"
        )
    if d["measured"] is not None:
        parts.append(
            f"over the impacts both have its peak decays {d['model']:.1f}% per impact against "
            f"{d['measured']:.1f}% measured"
        )
        off |= abs(d["model"] - d["measured"]) > 1.0
    if q["measured"] is not None:
        parts.append(f"its first quarter period is p T = {q['model']:.2f} against {q['measured']:.2f}")
        off |= abs(q["model"] / q["measured"] - 1) > 0.1
    ft = e["flight_time_pct"]
    if ft is not None:
        parts.append(
            f"at the measured amplitudes its flights are {abs(ft):.1f}% "
            f"{'longer' if ft > 0 else 'shorter'} than the wall's"
        )
        off |= abs(ft) > 3.0
    if e["lag_cycles"] is not None and abs(e["lag_cycles"]) > 0.1:
        parts.append(
            f"by the last impact both have its impacts come {abs(e['lag_s']):.2f} s "
            f"({abs(e['lag_cycles']):.1f} cycles) {'late' if e['lag_s'] > 0 else 'early'}"
        )
        off |= abs(e["lag_cycles"]) > 0.5
    if e.get("rms_theta_over_alpha") is not None:
        parts.append(f"RMS error of theta/alpha over the motion {e['rms_theta_over_alpha']:.3f}")
    return "; ".join(parts) + ".", off


# ---------------------------------------------------------------------------
# diagnosis of a series, a boundary condition, a campaign


def _base_name(boundary):
    return (
        "Housner e_an,2s (Eq. 2), nominal alpha, released from rest at theta0"
        if boundary == "two-sided"
        else "one-sided e_an,1s (Eq. 14), nominal alpha, released from rest at theta0"
    )


def finite_mean(x):
    """Mean of the finite values of x, None if there are none."""
    x = np.asarray(x, float)
    return float(np.nanmean(x)) if np.isfinite(x).any() else None


def _gain(before, after):
    """Held-out engineering errors of the base model minus those after an extension (per measure)."""
    out = {}
    for k in before:
        b, a = finite_mean(before[k]), finite_mean(after[k])
        if k != "deviance":
            out[k] = None if b is None or a is None else b - a
    return out


def _heldout_summary(ho):
    return {
        "deviance_per_obs": finite_mean(ho["deviance"]),
        **{k: finite_mean(v) for k, v in ho.items() if k != "deviance"},
    }


def diagnose_series(tests, *, key="", scope="series", n_boot=40, n_history=2, seed=0):
    """Diagnosis of one series: base model, what it gets wrong, causes, gain.

    Parameters
    ----------
    tests : list of MeasuredTest or of record dicts (see :func:`measured_test`)
        All of one boundary condition.
    key, scope : str
        Identify the entry.
    n_boot : int
        Bootstrap resamples (of tests) for the 95 % intervals.
    n_history : int
        Tests simulated in time (:func:`rocklab.simulation.reference.simulate_free`) for the
        RMS of theta/alpha.

    Returns
    -------
    dict
        One entry of results/diagnosis.json.
    """
    tests = [t if isinstance(t, MeasuredTest) else measured_test(t) for t in tests]
    tests = [t for t in tests if t.n_impacts >= 2]
    if not tests:
        raise ValueError("a diagnosis needs tests with at least two impacts")
    boundary = tests[0].boundary
    if any(t.boundary != boundary for t in tests):
        raise ValueError("a diagnosis needs tests of one boundary condition")
    problem = WallProblem(tests)
    sig = problem.signature
    sel = select_effects(problem, signature=sig, n_boot=n_boot, seed=seed)
    base_err = engineering_errors(tests, n_history=n_history)
    base = {"model": _base_name(boundary), "errors": base_err}
    if boundary == "one-sided":
        base["alternatives"] = {
            "two-sided e (Hogan 1992)": engineering_errors(tests, base="two-sided-e", n_history=0),
            "e = 0 (Liberatore & Spera 2003)": engineering_errors(tests, base="zero", n_history=0),
        }
    statement, off = what_is_wrong(base_err, "the simulation")
    effects, values = sel["effects"], sel["fit"].values
    findings = []
    for eff in effects:
        own = [q[0] for q in PARAMS[eff]]
        st = sel["steps"][eff]
        findings.append(
            {
                "effect": eff,
                "params": {k: values[k] for k in own},
                "ci95": {k: sel["ci"][k] for k in own if k in sel["ci"]},
                "evidence": {
                    "signature": sig.get(eff, {}).get("text", ""),
                    "fit": f"held-out deviance per observation lowered by {st['gain']:.3g} "
                    f"(standard error {st['se']:.2g}), dBIC = {st['dbic']:.1f}",
                },
                "error_heldout": _heldout_summary(st["heldout"]),
                "gain": _gain(sel["base"], st["heldout"]) | {"deviance_per_obs": st["gain"]},
            }
        )
    findings.sort(key=lambda f: -f["gain"]["deviance_per_obs"])
    structure = list(sel["structure"])
    stop = None
    if any(st.startswith("end of motion") for st in structure):
        stop = stop_threshold(tests, effects, values, seed=seed)
    if stop is not None and stop["named"]:
        structure = [st for st in structure if not st.startswith("end of motion")]
        findings.append(_stop_finding(stop))
    unexplained = bool(structure) and not sel["weak"]
    if not findings and not unexplained and not off:
        verdict_text = "the base model explains the data within the noise"
    elif not findings and not unexplained:
        verdict_text = "none of the candidate causes is carried by the data"
    else:
        verdict_text = ""
    entry = {
        "scope": scope,
        "key": key,
        "boundary": boundary,
        "n_tests": len(tests),
        "n_impacts": int(sum(t.n_impacts for t in tests)),
        "base": base,
        "what_is_wrong": (verdict_text + ": " if verdict_text else "") + statement,
        "verdict": [f["effect"] for f in findings],
        "unexplained": unexplained,
        "residual_structure": structure,
        "findings": findings,
        "weak_evidence": {k: v["reason"] for k, v in sel["weak"].items()},
        "rejected": sel["rejected"],
        "signatures": {k: v["text"] for k, v in sig.items()},
        "heldout": {"base": _heldout_summary(sel["base"]), "model": _heldout_summary(sel["final"])},
    }
    v_stop = stop["v_stop_over_vr"] if stop is not None and stop["named"] else 0.0
    if effects or v_stop:
        ext_err = engineering_errors(tests, effects, values, n_history=n_history, stop=v_stop)
        entry["extended"] = {
            "effects": effects + (["stop_threshold"] if v_stop else []),
            "params": {**values, **({"v_stop_over_vr": v_stop} if v_stop else {})},
            "errors": ext_err,
            "statement": what_is_wrong(ext_err, "the extended model")[0],
        }
    entry["sample_test"] = tests[int(np.argmax([t.n_impacts for t in tests]))].test_id
    return entry


def _stop_finding(stop):
    """A finding of :func:`diagnose_series` from :func:`stop_threshold`."""
    (n0, n1), (d0, d1) = stop["n_impacts_rms"], stop["duration_pct_rms"]
    return {
        "effect": "stop_threshold",
        "params": {"v_stop_over_vr": stop["v_stop_over_vr"], "spread_log": stop["spread_log"]},
        "ci95": {"v_stop_over_vr": stop["ci95"]},
        "evidence": {
            "signature": f"{stop['n_observed']} of {stop['n_tests']} walls stop dead at a landing of "
            f"{stop['v_stop_over_vr']:.3f} thetadot_r (test to test x/÷ "
            f"{math.exp(stop['spread_log']):.2f}) where the model's next flight would "
            f"be 3 times the noise",
            "fit": f"held-out rms error of the number of impacts {n0:.1f} -> {n1:.1f}, "
            f"of the rocking duration {d0:.1f} % -> {d1:.1f} %",
        },
        "error_heldout": {"deviance_per_obs": None, "n_impacts_rms": n1, "duration_pct_rms": d1},
        "gain": {"deviance_per_obs": None, "n_impacts_rms": n0 - n1, "duration_pct_rms": d0 - d1},
    }


def _wmean(vals, w):
    """Weighted mean of the finite values (None counts as missing); None if there are none."""
    vals = np.array([np.nan if v is None else v for v in vals], float)
    w = np.asarray(w, float)
    ok = np.isfinite(vals)
    return float(np.sum(vals[ok] * w[ok]) / np.sum(w[ok])) if ok.any() else None


def _merge_errors(errors, w):
    """Weighted means over series of :func:`engineering_errors` dicts."""
    return {
        k: (
            {s: _wmean([e[k][s] for e in errors], w) for s in v}
            if isinstance(v, dict)
            else _wmean([e[k] for e in errors], w)
        )
        for k, v in errors[0].items()
    }


def diagnose_boundary(entries, boundary, *, n_boot=2000, seed=0):
    """One boundary condition from the diagnoses of its series.

    The series are different walls and set-ups, so their parameters are not
    pooled into one fit: a cause is in the verdict when it is named in at
    least half of the series, with the test-weighted mean of its parameters
    over the series that name it and a bootstrap (over those series) 95 %
    interval of that mean; errors are test-weighted means over all series.
    """
    ser = [e for e in entries if e["scope"] == "series" and e["boundary"] == boundary]
    if not ser:
        return None
    rng = np.random.default_rng(seed)
    w_all = np.array([e["n_tests"] for e in ser], float)
    n_tests = int(w_all.sum())
    base_err = _merge_errors([e["base"]["errors"] for e in ser], w_all)
    counts = {}
    for e in ser:
        for f in e["findings"]:
            counts.setdefault(f["effect"], []).append((e, f))
    findings = []
    for eff, lst in counts.items():
        if len(lst) < 0.5 * len(ser):
            continue
        w = np.array([e["n_tests"] for e, _ in lst], float)
        params, ci = {}, {}
        for name in lst[0][1]["params"]:
            x = np.array([f["params"][name] for _, f in lst])
            params[name] = _wmean(x, w)
            boots = [_wmean(x[i], w[i]) for i in (rng.integers(0, x.size, x.size) for _ in range(n_boot))]
            ci[name] = [float(np.percentile(boots, 2.5)), float(np.percentile(boots, 97.5))]
        findings.append(
            {
                "effect": eff,
                "params": params,
                "ci95": ci,
                "evidence": {
                    "series": f"named in {len(lst)} of {len(ser)} series",
                    "range": {
                        n: [float(min(f["params"][n] for _, f in lst)), float(max(f["params"][n] for _, f in lst))]
                        for n in params
                    },
                },
                "error_heldout": {
                    "deviance_per_obs": _wmean([f["error_heldout"]["deviance_per_obs"] for _, f in lst], w)
                },
                "gain": {k: _wmean([f["gain"].get(k) for _, f in lst], w) for k in lst[0][1]["gain"]},
                "n_series": len(lst),
            }
        )
    findings.sort(key=lambda f: (-f["n_series"], -(f["gain"]["deviance_per_obs"] or 0)))
    flagged = [e["key"] for e in ser if e["unexplained"]]
    kinds = {}
    for e in ser:
        for k in {st.split(":")[0] for st in e["residual_structure"]}:
            kinds[k] = kinds.get(k, 0) + 1
    ho = {
        m: {k: _wmean([e["heldout"][m][k] for e in ser], w_all) for k in ser[0]["heldout"][m]}
        for m in ("base", "model")
    }
    statement, off = what_is_wrong(base_err, "the simulation")
    verdicts = {e["key"]: e["verdict"] for e in ser}
    extended = [e for e in ser if e.get("extended")]
    ext_statement = None
    if extended:
        ext_err = _merge_errors([e["extended"]["errors"] for e in extended], [e["n_tests"] for e in extended])
        ext_statement = what_is_wrong(ext_err, "the extended model")[0]
    if not findings and not flagged and not off:
        statement = "the base model explains the data within the noise: " + statement
    return {
        "scope": "boundary",
        "key": boundary,
        "boundary": boundary,
        "n_tests": n_tests,
        "n_series": len(ser),
        "n_impacts": int(sum(e["n_impacts"] for e in ser)),
        "base": {"model": _base_name(boundary), "errors": base_err},
        "what_is_wrong": statement,
        "verdict": [f["effect"] for f in findings],
        "unexplained": len(flagged) >= 0.5 * len(ser),
        "residual_structure": [
            f"{k} in {n} of {len(ser)} series" for k, n in sorted(kinds.items(), key=lambda x: -x[1])
        ],
        "unexplained_series": flagged,
        "findings": findings,
        "heldout": ho,
        "series_verdicts": verdicts,
        **({"extended": {"statement": ext_statement, "n_series": len(extended)}} if ext_statement else {}),
    }


def diagnose_records(records, key, *, n_boot=40, n_history=2, seed=0):
    """:func:`diagnose_series` of one series' records, or None when fewer than
    two of its tests have two impacts or more (nothing to diagnose)."""
    tests = [r if isinstance(r, MeasuredTest) else measured_test(r) for r in records]
    tests = [t for t in tests if t.n_impacts >= 2]
    if len(tests) < 2:
        return None
    return diagnose_series(tests, key=str(key), n_boot=n_boot, n_history=n_history, seed=seed)


def with_boundaries(entries, *, seed=0):
    """Series entries followed by one entry per boundary condition (:func:`diagnose_boundary`)."""
    out = list(entries)
    for b in ("two-sided", "one-sided"):
        e = diagnose_boundary(out, b, seed=seed)
        if e is not None:
            out.append(e)
    return out


def diagnose_campaign(series_records, *, n_boot=40, n_history=2, by_boundary=True, seed=0):
    """Diagnose every series and every boundary condition of a campaign.

    Parameters
    ----------
    series_records : dict
        series id -> list of test records (dicts for :func:`measured_test`)
        or :class:`MeasuredTest`.
    by_boundary : bool
        Add one entry per boundary condition (:func:`diagnose_boundary`).

    Returns
    -------
    list of dict
        The content of results/diagnosis.json.
    """
    entries = [
        diagnose_records(recs, sid, n_boot=n_boot, n_history=n_history, seed=seed)
        for sid, recs in series_records.items()
    ]
    entries = [e for e in entries if e is not None]
    return with_boundaries(entries, seed=seed) if by_boundary else entries


def jsonable(x):
    """``x`` with NumPy scalars as Python numbers and non-finite floats as None (JSON)."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return None if not np.isfinite(x) else float(x)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def write_diagnosis(entries, json_path, md_path=None):
    """Write results/diagnosis.json (and diagnosis.md) from :func:`diagnose_campaign` entries."""
    Path(json_path).write_text(json.dumps(jsonable(entries), indent=1))
    if md_path is not None:
        Path(md_path).write_text(diagnosis_markdown(entries))


def _fmt_params(f):
    return ", ".join(f"{k} = {v:.4g}" for k, v in f["params"].items())


def _fmt_ci(f):
    return ", ".join(f"[{a:.4g}, {b:.4g}]" for a, b in f["ci95"].values())


def diagnosis_markdown(entries) -> str:
    """Readable report (results/diagnosis.md) of :func:`diagnose_campaign` entries."""
    out = [
        "# Model diagnosis",
        "",
        "Per series and per boundary condition: what the base simulation gets wrong, the causes the "
        "data carry (parameters, bootstrap 95 % intervals), and the held-out gain. "
        "Method: `rocklab.diagnosis`.",
        "",
    ]
    order = sorted(entries, key=lambda e: (e["scope"] != "boundary", e["key"]))
    for e in order:
        title = f"{'boundary condition' if e['scope'] == 'boundary' else 'series'} {e['key']}"
        out += [
            f"## {title} ({e['boundary']}, {e['n_tests']} tests)",
            "",
            f"Base model: {e['base']['model']}.",
            "",
            f"What it gets wrong: {e['what_is_wrong']}",
            "",
        ]
        v = ", ".join(e["verdict"]) if e["verdict"] else "none"
        line = f"**Verdict: {v}**"
        if e["unexplained"]:
            line += " — **unexplained** structure remains: " + "; ".join(e.get("residual_structure", []))
        elif e.get("weak_evidence"):
            line += (
                " — structure remains ("
                + "; ".join(e["residual_structure"])
                + ") that "
                + " or ".join(e["weak_evidence"])
                + " would remove, short of the evidence to name it: "
                + "; ".join(e["weak_evidence"].values())
            )
        out += [line, ""]
        if e["findings"]:
            out += [
                "| effect | parameters | 95% CI | held-out deviance/obs "
                "| gain (deviance/obs; free-run log-peak rms) | evidence |",
                "|---|---|---|---|---|---|",
            ]
            for f in e["findings"]:
                g = f["gain"]
                fr = g.get("free_run_log_peak_rms")
                ev = f["evidence"].get("signature") or f["evidence"].get("series", "")
                out.append(
                    f"| {f['effect']} | {_fmt_params(f)} | {_fmt_ci(f)} | "
                    f"{_f(f['error_heldout']['deviance_per_obs'], '.3g')} | "
                    f"{_f(g['deviance_per_obs'], '.3g')}; {'' if fr is None else f'{fr:.3f}'} | {ev} "
                    f"{f['evidence'].get('fit', '') if f['effect'] == 'stop_threshold' else ''} |"
                )
            out.append("")
        h = e.get("heldout")
        if h and h["base"].get("free_run_log_peak_rms") is not None:
            hb, hm = h["base"], h["model"]
            out += [
                f"Held-out (tests left out): free-run log-peak rms {hb['free_run_log_peak_rms']:.3f} base, "
                f"{hm['free_run_log_peak_rms']:.3f} chosen model; one-step impact-velocity rms "
                f"{hb['impact_rms']:.4f} → {hm['impact_rms']:.4f}; flight-time rms "
                f"{_f(hb.get('time_rms'))} → {_f(hm.get('time_rms'))}.",
                "",
            ]
        if e.get("extended"):
            out += [f"Extended model: {e['extended']['statement']}", ""]
        if e.get("series_verdicts"):
            out += [
                "Series verdicts: "
                + "; ".join(f"{k}: {', '.join(v) or 'none'}" for k, v in e["series_verdicts"].items()),
                "",
            ]
        alt = e["base"].get("alternatives")
        if alt:
            for name, er in alt.items():
                out.append(
                    f"- literature alternative {name}: {er['n_impacts']['model']:.0f} impacts, "
                    f"{er['duration_s']['model']:.2f} s, free-run log-peak rms {er['log_peak_rms']:.3f}"
                )
            out.append("")
    return "\n".join(out)


def _f(x, fmt=".4f"):
    return "n/a" if x is None else format(x, fmt)
