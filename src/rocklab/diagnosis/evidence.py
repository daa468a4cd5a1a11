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

import functools
from dataclasses import dataclass, field, replace

import numpy as np

from rocklab.diagnosis.flight_filter import LOSSES, filter_reading
from rocklab.diagnosis.wall_model import ModelParams, impact_speeds, log_columns, per_test, release
from rocklab.io import valid_tests
from rocklab.lab import motion as chain
from rocklab.lab.campaign import order_in_series
from rocklab.physics import restitution
from rocklab.physics.boundary import Boundary
from rocklab.physics.flight import apex_after, landing_speed, quarter_period, quarter_period_linear
from rocklab.physics.wall import overturning_velocity


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
    instrument: str = "transducers"

    @property
    def fits(self) -> dict:
        """The settings of the fits that measured this test's flights (:func:`rocklab.lab.motion.instrument_fits`)."""
        return dict(chain.instrument_fits(self.instrument, 1.0 / self.dt))

    @property
    def n_impacts(self) -> int:
        return int(self.peaks.size)

    @functools.cached_property
    def filter_reading(self) -> dict:
        """How the filter reads this test's flights, per unit of each loss in flight (:func:`filter_reading`).

        Returns
        -------
        dict
            ``time`` (impacts - 1, losses): each flight's measured duration
            [s]; ``takeoff``, ``landing`` (impacts, losses): the speed
            measured after and before each impact, relative [-].  The fall
            from the release lands at the first impact; the last flight, with
            no landing, is timed by its apex and take-off speed (the
            linearised flight: a = (v^2 / p^2 + A^2) / (2 A)).
        """
        n, p, fs, fits = self.n_impacts, self.p, 1.0 / self.dt, self.fits
        out = {k: np.zeros((max(m, 0), len(LOSSES))) for k, m in (("time", n - 1), ("takeoff", n), ("landing", n))}
        if n == 0:
            return out
        T = np.r_[self.t_before[1:] - self.t_after[:-1], np.nan]
        v = np.r_[0.5 * (self.v_after[:-1] + self.v_before[1:]), self.v_after[-1]]
        A, va = self.peaks[-1], self.v_after[-1]
        a = ((va / p) ** 2 + A**2) / (2.0 * A) if A > 0 else np.nan
        T[-1] = 2.0 * float(quarter_period_linear(A / a)) / p if a > A else np.nan
        for j in range(n):
            if np.isfinite(T[j]) and np.isfinite(v[j]) and T[j] > 0 and v[j] > 0:
                r = filter_reading(T[j], v[j], p, fs, fits=fits)
                out["takeoff"][j] = r[1]
                if j < n - 1:
                    out["time"][j], out["landing"][j + 1] = r[0], r[2]
        fall, vb = self.t_before[0] - self.t_release, self.v_before[0]
        if np.isfinite(fall) and np.isfinite(vb) and fall > 0 and vb > 0:
            out["landing"][0] = filter_reading(fall, vb, p, fs, from_rest=True, fits=fits)[2]
        return out

    @property
    def sides(self) -> np.ndarray:
        """Hinge left at impact k (+1 / -1, sign of theta before it)."""
        return self.side0 * (-1.0) ** (np.arange(self.n_impacts) * (self.boundary == Boundary.TWO_SIDED))


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
    instrument = str(record.get("instrument", "transducers"))
    m = record.get("motion")
    if m is None:
        fits = chain.instrument_fits(instrument, record["fs"])
        m = chain.extract_motion(t, theta, record["fs"], record["boundary"], record["p"], **fits)
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
        instrument=instrument,
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
        motion stored in the workflow's ``results/tests/<job>/<test_id>.nc``, :func:`rocklab.lab.motion.read_motion`);
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
                "instrument": a.get("instrument", "transducers"),
                "log": {k[4:]: float(v) for k, v in a.items() if k.startswith("log_")},
            }
        )
    return dict(sorted(out.items()))


def stored_records(paths, qc_path=None):
    """:func:`records_by_series` of the valid reduced tests at ``paths``, with the motions stored in them.

    Each file (``results/tests/<job>/<test_id>.nc``) is opened once for its
    rotation and its motion group (:func:`rocklab.lab.motion.write_test_with_motion`):
    netCDF-C spends longer opening a reduced test than reading both.  Valid
    as :func:`rocklab.io.valid_tests` says (``qc_path``, or each test's own verdict).
    """
    datasets, motions = [], {}
    for ds, motion in valid_tests(paths, qc_path, variables=("theta",), also=chain.MOTION_GROUP):
        datasets.append(ds)
        motions[ds.attrs["test_id"]] = chain.motion_from_dataset(motion)
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
    resolved: np.ndarray

    @classmethod
    def of(cls, tests):
        n = max(max(t.n_impacts for t in tests), 1)

        def padded(x, m):
            return np.concatenate([x, np.full(n - m, np.nan)])

        def pad(name):
            return np.array([padded(getattr(t, name), t.n_impacts) for t in tests])

        side = np.array([padded(t.sides, t.n_impacts) for t in tests])
        floor = np.array([t.floor for t in tests])
        A = pad("peaks")
        par = np.array([[t.alpha, t.p, 1.0 / t.dt] for t in tests]).T[..., None]
        return cls(
            resolved=chain.apex_resolved(A, *par),
            tests=list(tests),
            theta0=np.array([t.theta0 for t in tests]),
            v0=np.array([t.v_release for t in tests]),
            side0=np.array([t.side0 for t in tests], float),
            floor=floor,
            vfloor=np.array([t.p * t.floor for t in tests]),
            tfloor=np.array([t.dt for t in tests]),
            A=A,
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

    def filter_reading(self):
        """:attr:`MeasuredTest.filter_reading` of each test, as (tests, flights or impacts, losses)
        arrays, 0 past a test's last."""
        n = self.A.shape[1]
        out = {k: np.zeros((len(self.tests), n - (k == "time"), len(LOSSES))) for k in ("time", "takeoff", "landing")}
        for i, t in enumerate(self.tests):
            for k, x in t.filter_reading.items():
                out[k][i, : len(x)] = x
        return out


def log_ratio(model, meas, floor=0.0):
    """log((model + floor) / (measured + floor)), NaN where undefined."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.log((model + floor) / (meas + floor))


def residuals(S: TestStack, mp: ModelParams, cache=None):
    """One-step residuals of every group (module docstring), log(model / measured).

    ``mp`` is a :class:`rocklab.diagnosis.wall_model.ModelParams` of the tests of ``S``.

    ``cache`` (a dict) keeps the flight times between calls with the same
    hinge angles (a fit of the restitution moves nothing else) and how the
    filter reads the flights of ``S`` under losses in flight
    (:meth:`TestStack.filter_reading`).

    Returns
    -------
    dict
        Group name -> (tests, impacts) array, NaN where there is no observation.
    """
    f, vf = S.floor[:, None], S.vfloor[:, None]
    p, loss = mp.p[:, None], mp.flight_keywords(S.A)
    one = mp.one_sided[:, None]
    apex_side = np.where(one, S.side, -S.side)
    a_ap = mp.hinge(apex_side)
    v_hat, _, tau_hat, _, _ = impact_speeds(S.vb, S.side, mp)
    cache = {} if cache is None else cache
    lossy = any(np.count_nonzero(loss[k]) for k in LOSSES)
    if lossy:
        # the losses in flight move what the filter reads of a flight: its speeds and its duration
        if cache.get("read_of") is not S:
            cache.update(read_of=S, reading=S.filter_reading())
        read = {
            k: sum(x[..., j] * per_test(getattr(mp, name), x[..., j]) for j, name in enumerate(LOSSES))
            for k, x in cache["reading"].items()
        }
        v_hat = v_hat * (1.0 + read["takeoff"]) / (1.0 + read["landing"])
    R = {"impact": log_ratio(v_hat, S.va, vf)}
    # peak to peak: from the measured apex before (theta0 at rest for the first), a landing,
    # the impact, a rise
    v_land = landing_speed(S.A[:, :-1], mp.hinge(S.side[:, 1:]), p, **loss)
    v_land = np.concatenate([release(S, mp, timed=False)[0][:, None], v_land], axis=1)
    R["peak"] = log_ratio(apex_after(impact_speeds(v_land, S.side, mp, timed=False)[0], a_ap, p, **loss), S.A, f)
    R["peak"][~S.resolved] = np.nan
    key = mp.a_pos.tobytes() + mp.a_neg.tobytes() + mp.rounding.tobytes()
    if cache.get("angles") != key or cache.get("timed") is not S:
        # flights too close to the noise have apexes too uncertain to time them
        A_t = np.where((S.A[:, :-1] > 3 * f) & S.resolved[:, :-1], S.A[:, :-1], np.nan)
        A0 = np.nan_to_num(A_t)
        cache.update(
            timed=S,
            angles=key,
            time=np.where(np.isfinite(A_t), 2.0 * quarter_period(A0, mp.flight(A0, apex_side[:, :-1]), p), np.nan),
        )
    T = cache["time"] + read["time"] if lossy else cache["time"]
    R["time"] = log_ratio(T, S.tb[:, 1:] - S.ta[:, :-1])
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
        one_sided=tests[0].boundary == Boundary.ONE_SIDED,
        alpha=alpha,
        p=p,
        big=big,
        ratio=ratio,
        vr=vr,
        ok=np.isfinite(ratio) & big,
        a_T=np.where(big[:, :-1], a_T, np.nan),
    )
