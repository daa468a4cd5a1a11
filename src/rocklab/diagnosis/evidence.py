"""What the diagnosis sees of a test: its measured flights and the one-step residuals of a model.

Every flight of a test is seen through what :mod:`rocklab.lab.motion`
measures (:class:`MeasuredTest`): impact and take-off velocities, apexes,
impact instants and, for one-sided walls, the excursion past theta = 0.
Each is predicted one step ahead from the measured state before it
(:func:`residuals`), in four groups that each see their own part of the
physics (impact, peak, time, gap_time; docs/diagnosis-method.md).
:func:`observe` gathers the arrays the causes' fit-free signatures read.
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass, field, replace

import numpy as np

from rocklab.diagnosis.model import ModelParams, impact_speeds, log_columns, release
from rocklab.io import valid_tests
from rocklab.lab.campaign import order_in_series
from rocklab.lab.motion import MOTION_GROUP, extract_motion, motion_from_dataset
from rocklab.physics import restitution
from rocklab.physics.flight import apex_after, landing_speed, quarter_period, speed_loss
from rocklab.physics.wall import overturning_velocity

#: The derivative filter of :mod:`rocklab.lab.motion` fits undamped flights: with a
#: viscous loss zeta it reads take-off speeds low and impact speeds high, so the
#: velocity ratio of an impact reads e (1 - 0.35 zeta) (median over impacts and
#: over walls with p = 3.0-4.3 rad/s and zeta = 0.005-0.02, exact simulator;
#: checked in tests/test_diagnosis.py).
FILTER_DAMPING_BIAS = 0.35

# the fit windows of the derivative filter (rocklab.lab.motion.extract_motion's defaults)
_FILTER = {k: v.default for k, v in inspect.signature(extract_motion).parameters.items()}


def filter_loss_bias(S, mp: ModelParams):
    """Factor by which the derivative filter reads the velocity ratio of each impact under dry friction and drag.

    The filter (:mod:`rocklab.lab.flight_fit`) fits each side of an impact
    with the linearised flight through the apex, one symmetric curve: where
    its window reaches past the apex into the other half of the flight,
    which the losses make slower (falling) or faster (rising), the speed it
    reads is lowered (take-off) or raised (impact) by that share s of the
    window times the flight's relative speed loss l (:func:`rocklab.physics.flight.speed_loss`,
    dry friction and drag; the viscous part is :data:`FILTER_DAMPING_BIAS`):
    (1 - s_a l_after) / (1 + s_b l_before).  A short flight, inside one
    window, reads l/2 on each side: the loss of a flight moves into the
    measured e, as a lower restitution would.  Within one half, a constant
    moment (dry friction) is what the fitted curve's free acceleration
    absorbs; drag, like a viscous loss of zeta = kappa v / (2 p) at the
    impact speed v, biases it by :data:`FILTER_DAMPING_BIAS` times that, in
    the share 1 - 2 s_a of the window the flight's other half leaves.

    Returns
    -------
    ndarray
        (tests, impacts); 1 without dry friction or drag.
    """
    if not (np.any(mp.mu) or np.any(mp.kappa)):
        return 1.0
    p = mp.p[:, None]
    loss = {k: v for k, v in mp.flight_loss(S.A).items() if k != "zeta"}
    W = _FILTER["window_p"] / p
    guard, pre = _FILTER["ring_guard_s"], 2.5 * S.tfloor[:, None]
    # each flight on its own angle (ModelParams.flight, where the angle depends on the amplitude)
    A = np.nan_to_num(S.A)
    a_after = mp.flight(A, np.where(mp.one_sided[:, None], S.side, -S.side))
    T = quarter_period(A, a_after, p)
    g = np.minimum(guard, 0.8 * T)
    end = np.minimum(g + W, 1.8 * T)
    s_a = np.where(end > g, np.maximum(end - T, 0.0) / np.maximum(end - g, 1e-300), 0.0)
    l_a = speed_loss(A, a_after, p, **loss)
    # the flight before impact k + 1 is the flight after impact k, on the hinge it lands from
    a_b = mp.flight(A[:, :-1], S.side[:, 1:])
    Tb = quarter_period(A[:, :-1], a_b, p)
    start = np.maximum(np.minimum(guard, 0.8 * Tb), 2.0 * Tb - W)
    stop = 2.0 * Tb - pre
    s_b = np.where(stop > start, np.maximum(Tb - start, 0.0) / np.maximum(stop - start, 1e-300), 0.0)
    l_b = speed_loss(A[:, :-1], a_b, p, **loss)
    # the first impact ends the fall from the release: no rise in its window
    up = np.c_[np.zeros(len(S.tests)), s_b * l_b]
    within = 1.0 - FILTER_DAMPING_BIAS * loss["kappa"] * np.nan_to_num(S.vb) / (2.0 * p) * (1.0 - 2.0 * s_a)
    return within * (1.0 - s_a * np.nan_to_num(l_a)) / (1.0 + np.nan_to_num(up))


@dataclass
class MeasuredTest:
    """What :mod:`rocklab.lab.motion` measured on one free-rocking test.

    Angles and velocities are magnitudes on the side of release (``side0``);
    arrays run over the impacts k = 1..n: ``peaks`` the apex |theta_k| after
    impact k [rad], ``v_before`` / ``v_after`` |thetadot| before and after it
    [rad/s], ``t_before`` / ``t_after`` its arrival at and departure from
    theta = 0 [s] (they differ when a one-sided wall swings into the gap),
    ``depth`` the excursion past theta = 0 [rad]; ``v_release`` the speed
    towards the vertical with which the wall left the screw [rad/s];
    ``order`` its place in its series, 0 (first) to 1 (last)
    (:func:`in_series_order`); ``log`` the numbers of its row of the test
    log (:func:`rocklab.lab.reduction.log_values`, by column), each its
    place between the series' least and largest value (0 to 1) once
    :func:`in_series_order` has read the series.
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
    order: float = 0.5
    log: dict = field(default_factory=dict)
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
        log=dict(record.get("log", {})),
        t=t,
        theta=theta,
    )


def in_series_order(tests):
    """The tests with their place in the series (``order``, 0 to 1), from the order of their ids.

    Test ids of a campaign grow with the date of the test (``T0001``...), so
    their order is the order of the tests: what a drift between tests
    (wear, debris) follows.
    """
    order = order_in_series([t.test_id for t in tests])
    # a column of the test log that every test has and that varies over the series: its place in its range
    cols = sorted(set.intersection(*(set(t.log) for t in tests))) if tests else []
    span = {c: (min(t.log[c] for t in tests), max(t.log[c] for t in tests)) for c in cols}
    span = {c: (lo, hi) for c, (lo, hi) in span.items() if hi > lo}
    return [
        replace(
            t,
            order=order[t.test_id],
            log={c: (t.log[c] - lo) / (hi - lo) for c, (lo, hi) in span.items()},
        )
        for t in tests
    ]


def records_by_series(datasets, motions=None):
    """Group reduced tests (:mod:`rocklab.lab.reduction`) into the records of :func:`diagnose_campaign`.

    Parameters
    ----------
    datasets : iterable of xarray.Dataset
        Reduced tests.
    motions : mapping, optional
        Test id -> :class:`rocklab.lab.motion.Motion` already extracted (the
        motion stored in the workflow's ``results/tests/<test_id>.nc``, :func:`rocklab.lab.motion.read_motion`);
        a test without one has its motion extracted from theta by :func:`measured_test`.
    """
    motions = motions or {}
    out = {}
    for ds in datasets:
        a = ds.attrs
        out.setdefault(a["series"], []).append(
            {
                "motion": motions.get(a["test_id"]),
                "test_id": a["test_id"],
                "series": a["series"],
                "t": ds.time.values,
                "theta": ds.theta.values,
                "fs": float(a["sampling_rate_hz"]),
                "alpha": float(a["alpha"]),
                "p": float(a["p"]),
                "boundary": a["boundary"],
                "direction": a["direction"],
                "log": {k[4:]: float(v) for k, v in a.items() if k.startswith("log_")},
            }
        )
    return dict(sorted(out.items()))


def stored_records(paths, qc_path=None):
    """:func:`records_by_series` of the valid reduced tests at ``paths``, with the motions stored in them.

    Each file (``results/tests/<test_id>.nc``) is opened once for its
    rotation and its motion group (:func:`rocklab.lab.motion.write_test_with_motion`):
    netCDF-C spends longer opening a reduced test than reading both.  Valid
    as :func:`rocklab.io.valid_tests` says (``qc_path``, or each test's own verdict).
    """
    datasets, motions = [], {}
    for ds, motion in valid_tests(paths, qc_path, variables=("theta",), also=MOTION_GROUP):
        datasets.append(ds)
        motions[ds.attrs["test_id"]] = motion_from_dataset(motion)
    return records_by_series(datasets, motions)


# ---------------------------------------------------------------------------
# one-step predictions


@dataclass
class TestStack:
    """Measured tests as padded (tests, impacts) arrays (NaN past a test's last impact)."""

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
    order: np.ndarray

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
            order=np.array([t.order for t in tests], float),
        )

    def subset(self, idx):
        return replace(
            self,
            tests=[self.tests[i] for i in idx],
            **{k: v[idx] for k, v in vars(self).items() if isinstance(v, np.ndarray)},
        )


def log_ratio(model, meas, floor=0.0):
    """log((model + floor) / (measured + floor)), NaN where undefined."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.log((model + floor) / (meas + floor))


def residuals(S: TestStack, mp: ModelParams, cache=None):
    """One-step residuals of every group (module docstring), log(model / measured).

    ``mp`` is a :class:`rocklab.diagnosis.model.ModelParams` of the tests of ``S``.

    ``cache`` (a dict) keeps the flight times between calls with the same
    hinge angles: a fit of the restitution moves nothing else.

    Returns
    -------
    dict
        Group name -> (tests, impacts) array, NaN where there is no observation.
    """
    f, vf = S.floor[:, None], S.vfloor[:, None]
    p, zeta, loss = mp.p[:, None], mp.zeta[:, None], mp.flight_keywords(S.A)
    one = mp.one_sided[:, None]
    apex_side = np.where(one, S.side, -S.side)
    a_ap = mp.hinge(apex_side)
    v_hat, _, tau_hat, _, _ = impact_speeds(S.vb, S.side, mp)
    R = {"impact": log_ratio(v_hat * (1.0 - FILTER_DAMPING_BIAS * zeta) * filter_loss_bias(S, mp), S.va, vf)}
    # peak to peak: from the measured apex before (theta0 at rest for the first), a landing,
    # the impact, a rise
    v_land = landing_speed(S.A[:, :-1], mp.hinge(S.side[:, 1:]), p, **loss)
    v_land = np.c_[release(S, mp, timed=False)[0], v_land]
    R["peak"] = log_ratio(apex_after(impact_speeds(v_land, S.side, mp, timed=False)[0], a_ap, p, **loss), S.A, f)
    key = mp.a_pos.tobytes() + mp.a_neg.tobytes() + mp.rounding.tobytes()
    if cache is not None and cache.get("stack") is S and cache.get("angles") == key:
        R["time"] = cache["time"]
    else:
        # flights too close to the noise have apexes too uncertain to time them
        A_t = np.where(S.A[:, :-1] > 3 * f, S.A[:, :-1], np.nan)
        R["time"] = np.where(
            np.isfinite(A_t),
            log_ratio(
                2.0 * quarter_period(np.nan_to_num(A_t), mp.flight(np.nan_to_num(A_t), apex_side[:, :-1]), p),
                S.tb[:, 1:] - S.ta[:, :-1],
            ),
            np.nan,
        )
        if cache is not None:
            cache.update(stack=S, angles=key, time=R["time"])
    if np.all(mp.one_sided):
        R["gap_time"] = log_ratio(tau_hat, S.ta - S.tb, S.tfloor[:, None])
    return R


def noise_covariates(S: TestStack):
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


def covariates(S: TestStack):
    """Impact index, log amplitude and test order of each residual of :func:`residuals` (structure tests)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        lv = np.log(S.vb)
    k, lA = S.k, np.log(np.maximum(S.A, 1e-300))
    # a property of the test: its per-test medians against it (a drift between tests)
    order = S.order[:, None] + 0.0 * k
    logs = {f"test log {c}": np.array([t.log[c] for t in S.tests])[:, None] + 0.0 * k for c in log_columns(S.tests)}

    def pair(a, b, o, cut=None):
        return {"impact index": a, "amplitude": b, "test order": o, **{n: x[:, :cut] for n, x in logs.items()}}

    return {
        "impact": pair(k, lv, order),
        "peak": pair(k, lA, order),
        "time": pair(k[:, :-1], lA[:, :-1], order[:, :-1], -1),
        "gap_time": pair(k, lv, order),
    }


def series_level(x, ok):
    """Mean over tests of the per-test medians of x where ok: one level per test, robust within it."""
    med = [np.median(x[i][ok[i]]) for i in range(x.shape[0]) if ok[i].any()]
    return float(np.mean(med)) if med else np.nan


def flight_time_alpha(A, T, p):
    """Instability angle that Housner's closed form gives a flight of apex A and duration T [rad].

    Inverts T = (2/p) arccosh(1 / (1 - A/a)): a = A / (1 - sech(p T / 2)).
    """
    return A / (1.0 - 1.0 / np.cosh(0.5 * p * T))


@dataclass
class Observed:
    """The arrays of a series that the causes' signatures read (:func:`observe`).

    ``alpha``, ``p`` as (tests, 1) columns; ``ratio`` the measured e over the
    analytic e of the boundary, ``vr`` the impact speed over thetadot_r,
    ``big`` the flights 3 times above the noise threshold, ``ok`` the
    impacts with a finite ratio after a big flight, ``a_T`` the instability
    angle over alpha that Housner's closed form gives each flight time
    (:func:`flight_time_alpha`).
    """

    tests: list
    S: TestStack
    one_sided: bool
    alpha: np.ndarray
    p: np.ndarray
    big: np.ndarray
    ratio: np.ndarray
    vr: np.ndarray
    ok: np.ndarray
    a_T: np.ndarray


def observe(tests) -> Observed:
    """:class:`Observed` of the tests of one series (one boundary condition)."""
    S = TestStack.of(tests)
    alpha = np.array([t.alpha for t in tests])[:, None]
    p = np.array([t.p for t in tests])[:, None]
    e_an = np.abs(restitution.analytic(tests[0].boundary, alpha))
    big = S.A > 3 * S.floor[:, None]
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = (S.va / S.vb) / e_an
        vr = S.vb / overturning_velocity(alpha, p)
        # period-amplitude: Housner's closed form inverted on every flight between two impacts
        a_T = flight_time_alpha(S.A[:, :-1], S.tb[:, 1:] - S.ta[:, :-1], p) / alpha
    return Observed(
        tests=list(tests),
        S=S,
        one_sided=tests[0].boundary == "one-sided",
        alpha=alpha,
        p=p,
        big=big,
        ratio=ratio,
        vr=vr,
        ok=np.isfinite(ratio) & big,
        a_T=np.where(big[:, :-1], a_T, np.nan),
    )
