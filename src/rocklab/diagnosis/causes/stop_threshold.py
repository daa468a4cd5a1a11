"""Walls that stop dead: below a landing speed the wall sticks (:class:`rocklab.physics.impact.Sticking`).

A stop is no residual of a flight but the absence of the next one, so it is
not fitted with the residual groups: once the chosen model is known and
the walls stop where that model rocks on (:func:`end_of_motion`), each wall
brackets the landing speed it stuck at (:func:`stop_speeds`) and
:func:`estimate` gives the series' threshold, named when it at least
halves the held-out error of the free run in the number of impacts.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, TypedDict, cast

import numpy as np

from rocklab._imports import lazy_module
from rocklab.diagnosis.causes import BOTH, Cause, Stage
from rocklab.diagnosis.errors import EngineeringRow, engineering_rows
from rocklab.diagnosis.evidence import MeasuredTest, TestStack
from rocklab.diagnosis.parameters import Param
from rocklab.diagnosis.result import Finding, Structure
from rocklab.diagnosis.wall_model import ModelParams, next_flight
from rocklab.inference.intervals import MIN_BOOTSTRAP, expanded, percentile_interval, t_interval
from rocklab.lab.motion import odd_samples
from rocklab.physics.flight import landing_speed, quarter_period
from rocklab.physics.law import Stop
from rocklab.physics.wall import overturning_velocity

if TYPE_CHECKING:
    from rocklab.diagnosis.result import Number

signal = lazy_module("scipy.signal")

NAME = "stop_threshold"
V_STOP = Param("v_stop_over_vr", 0.0, 1.0, 0.0)


class StopThreshold(TypedDict):
    """The stop threshold of a series and what it gains (:func:`threshold`)."""

    v_stop_over_vr: float
    ci95: list[float]
    common_bracket: bool
    spread_log: float
    n_observed: int
    n_tests: int
    n_impacts_rms: tuple[float, float]
    duration_pct_rms: tuple[float, float]
    named: bool


class StopEstimate(TypedDict):
    """What :func:`estimate` gives the diagnosis (:attr:`rocklab.diagnosis.causes.Cause.estimate`)."""

    named: bool
    values: dict[str, float]
    finding: Finding


def laws(v: Mapping[str, float]) -> tuple[Stop]:
    # a value per test is allowed: the threshold of each test taken from the others (estimate)
    return (Stop(v["v_stop_over_vr"]),)


def _largest_apex_after_end(
    S: TestStack, mp: ModelParams, idx: Sequence[int] | np.ndarray, window_s: float, n_max: int = 200
) -> np.ndarray:
    """Largest apex the model predicts after the end of each test ``idx`` of ``S``, apexes from
    ``window_s`` / 10 to ``window_s`` after the end [rad] (0 if none).

    From the last measured apex the flights follow by :func:`rocklab.diagnosis.wall_model.next_flight`,
    all tests together, each until an apex past the window or below its noise threshold
    (:func:`end_of_motion`).
    """
    if not idx:
        return np.zeros(0)
    idx = np.asarray(idx)
    tests = [S.tests[i] for i in idx]
    m = mp.row(idx)
    last = np.array([ts.n_impacts - 1 for ts in tests])
    side = np.where(m.one_sided, S.side[idx, last], -S.side[idx, last])
    A = np.array([ts.peaks[k] for ts, k in zip(tests, last)])
    t = np.array([ts.t_after[k] for ts, k in zip(tests, last)])
    end, floor = np.array([ts.t_end for ts in tests]), np.array([ts.floor for ts in tests])
    lo, hi = end + 0.1 * window_s, end + window_s
    a = m.flight(A, side)
    pred, live = np.zeros(idx.size), np.ones(idx.size, bool)
    for _ in range(n_max):
        quarter = quarter_period(A, a, m.p)
        t_apex = t + quarter
        live &= ~((t_apex > hi) | (A < floor))
        if not live.any():
            break
        pred = np.where(live & (t_apex > lo), np.maximum(pred, A), pred)
        t = t_apex + quarter
        A, side, a, _, tau = next_flight(landing_speed(A, a, m.p, **m.flight_loss()), side, m)
        t = t + tau
    return pred


def end_of_motion(S: TestStack, mp: ModelParams, min_ratio: float = 3.0, window_s: float = 1.0) -> list[Structure]:
    """Whether the walls stop earlier than the model can.

    The reduction ends the motion at the last flight it can measure; a wall
    that keeps rocking leaves smaller flights in the record after that, a
    wall that sticks does not.  From the last measured apex the model
    predicts the flights that follow (:func:`rocklab.diagnosis.wall_model.next_flight`);
    their largest apex from a tenth of ``window_s`` after the end (past the
    last return) to ``window_s`` is compared with the largest high-passed
    |theta| of the record there (the settling drift removed).  When in most
    tests the model rises ``min_ratio`` times above both the record and the
    noise threshold, the walls stop dead.

    Returns
    -------
    list of Structure
        One statement, or none.
    """
    ratios, speeds = [], []
    idx = [i for i, ts in enumerate(S.tests) if ts.t is not None and not ts.t[-1] - ts.t_end < 0.5 * window_s]
    pred = _largest_apex_after_end(S, mp, idx, window_s)
    for i, pred_i in zip(idx, pred):
        ts = S.tests[i]
        lo, hi = ts.t_end + 0.1 * window_s, ts.t_end + window_s
        sel = (ts.t > lo) & (ts.t <= hi)
        win = odd_samples(0.25 / ts.dt)
        if sel.sum() < win:
            continue
        hp = ts.theta[sel] - signal.savgol_filter(ts.theta[sel], win, 2)
        seen = float(np.percentile(np.abs(hp), 99))
        ratios.append(pred_i / max(seen, ts.floor))
        speeds.append(ts.v_before[-1] / float(overturning_velocity(ts.alpha, ts.p)))
    r = np.array(ratios)
    if r.size >= 3 and np.mean(r > min_ratio) > 0.5:
        return [
            Structure(
                NAME,
                f"end of motion: the walls stop dead where the model rocks on to {np.median(r):.0f} times what "
                f"the record shows ({int(np.sum(r > min_ratio))} of {r.size} tests; last measured impact at "
                f"{np.median(speeds):.2f} thetadot_r)",
            )
        ]
    return []


def stop_speeds(
    S: TestStack, mp: ModelParams, min_ratio: float = 3.0, tail_s: float = 0.5
) -> tuple[np.ndarray, np.ndarray]:
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
        v_n = landing_speed(ts.peaks[n - 2], mpi.hinge(hinge[0]), mpi.p, **mpi.flight_keywords())
        v_l = landing_speed(ts.peaks[n - 1], mpi.hinge(hinge[1]), mpi.p, **mpi.flight_keywords())
        if next_flight(v_l, hinge[1], mpi)[0] < min_ratio * ts.floor:
            continue
        if v_l >= v_n:  # a last flight higher than the one before: noise, no bracket
            continue
        vr = float(overturning_velocity(ts.alpha, ts.p))
        lo[i], hi[i] = v_l / vr, v_n / vr
    return lo, hi


def bracket_centre(lo: np.ndarray, hi: np.ndarray) -> tuple[float, bool]:
    """Threshold of brackets (lo, hi] and whether they share a common part:
    the geometric centre of that part if they have one, else the geometric
    mean of their centres."""
    L, U = np.max(lo), np.min(hi)
    if L < U:
        return float(np.sqrt(L * U)), True
    return float(np.exp(0.5 * np.mean(np.log(lo) + np.log(hi)))), False


def threshold(
    tests: list[MeasuredTest], mp: ModelParams, *, n_boot: int = 200, seed: int = 0, min_tests: int = 3
) -> StopThreshold | None:
    """The landing speed below which the walls of a series stop dead, and what it gains.

    Each test brackets its own stop speed (:func:`stop_speeds`, a bracket as
    narrow as e); the series' threshold is the geometric mean of the bracket
    centres, with a bootstrap (over tests) 95 % interval and the test-to-test
    spread of log speed (Fig. 18's scatter of the number of cycles); from
    fewer than :data:`~rocklab.inference.intervals.MIN_BOOTSTRAP` stops
    the t interval of the mean log speed on their few degrees of freedom.  Where
    the brackets share a common part, one threshold fits every wall: the
    estimate is that part's geometric centre and the interval spans it
    (:func:`bracket_centre`, also used for the tests left out).  Gain:
    the free run of the model ``mp`` of ``tests`` (:class:`rocklab.diagnosis.wall_model.ModelParams`,
    :func:`rocklab.diagnosis.errors.engineering_rows`) with each test's threshold
    taken from the other tests (leave one out) against the model without it,
    in the number of impacts and the duration of rocking.

    Returns
    -------
    dict or None
        None when fewer than ``min_tests`` tests (or half of them) show a
        stop; otherwise ``v_stop_over_vr``, ``ci95``, ``spread_log``,
        ``n_observed``, held-out rms errors ``n_impacts_rms`` and
        ``duration_pct_rms`` as (base, with threshold), and ``named`` (the
        held-out error in the number of impacts at least halved).
    """
    S = TestStack.of(tests)
    lo, hi = stop_speeds(S, mp)
    ok = np.isfinite(lo)
    if ok.sum() < max(min_tests, 3, 0.5 * len(tests)):
        return None
    lo, hi = lo[ok], hi[ok]
    x = 0.5 * (np.log(lo) + np.log(hi))
    if x.size >= MIN_BOOTSTRAP:
        rng = np.random.default_rng(seed)
        boots = [rng.choice(x, x.size).mean() for _ in range(n_boot)]
        ci = [float(v) for v in np.exp(expanded(percentile_interval(boots), x.mean(), x.size))]
    else:
        # too few stops to resample: Student's t on their few degrees of freedom (issue 24)
        lo_x, hi_x, _ = t_interval(x.mean(), x.std(ddof=1) / math.sqrt(x.size), x.size - 1)
        ci = [float(np.exp(lo_x)), float(np.exp(hi_x))]
    centre, common = bracket_centre(lo, hi)
    if common:
        # one threshold fits every wall: it is known only within the common
        # bracket, however alike the walls' brackets are
        ci = [min(ci[0], float(np.max(lo))), max(ci[1], float(np.min(hi)))]
    obs, m = [tests[i] for i in np.flatnonzero(ok)], mp.row(np.flatnonzero(ok))
    keep = ~np.eye(x.size, dtype=bool)
    loo = np.array([bracket_centre(lo[k], hi[k])[0] for k in keep])

    def errors(rows: Sequence[EngineeringRow]) -> tuple[float, float]:
        n = np.array([r["n_impacts"][1] - r["n_impacts"][0] for r in rows], float)
        d = np.array([100.0 * (r["duration_s"][1] / r["duration_s"][0] - 1.0) for r in rows], float)
        return float(np.sqrt(np.mean(n**2))), float(np.sqrt(np.mean(d**2)))

    # the stop acts last in the catalogue's order: on the chosen model as it is
    (n0, d0), (n1, d1) = errors(engineering_rows(obs, m)), errors(engineering_rows(obs, m.under(Stop(loo))))
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


def finding(stop: StopThreshold) -> Finding:
    """The finding (:class:`rocklab.diagnosis.result.Finding`) of a threshold of :func:`threshold`."""
    (n0, n1), (d0, d1) = stop["n_impacts_rms"], stop["duration_pct_rms"]
    n = stop["n_observed"]
    note = f"t interval of {n} stops ({n - 1} degrees of freedom)" if n < MIN_BOOTSTRAP else ""
    return Finding(
        effect=NAME,
        params={"v_stop_over_vr": stop["v_stop_over_vr"], "spread_log": stop["spread_log"]},
        ci95={"v_stop_over_vr": cast("list[Number]", stop["ci95"])},
        n_tests=stop["n_observed"],
        ci_note=note or None,
        evidence={
            "signature": f"{stop['n_observed']} of {stop['n_tests']} walls stop dead at a landing of "
            f"{stop['v_stop_over_vr']:.3f} thetadot_r (test to test x/÷ "
            f"{math.exp(stop['spread_log']):.2f}) where the model's next flight would "
            f"be 3 times the noise",
            "fit": f"held-out rms error of the number of impacts {n0:.1f} -> {n1:.1f}, "
            f"of the rocking duration {d0:.1f} % -> {d1:.1f} %",
        },
        error_heldout={"deviance_per_obs": None, "n_impacts_rms": n1, "duration_pct_rms": d1},
        gain={"deviance_per_obs": None, "n_impacts_rms": n0 - n1, "duration_pct_rms": d0 - d1},
    )


def estimate(tests: list[MeasuredTest], mp: ModelParams, seed: int = 0) -> StopEstimate | None:
    """The stage after selection: :func:`threshold` of the chosen model ``mp`` as a finding, or None
    where none is found."""
    stop = threshold(tests, mp, seed=seed)
    if stop is None:
        return None
    return {"named": stop["named"], "values": {V_STOP.name: stop["v_stop_over_vr"]}, "finding": finding(stop)}


CAUSE = Cause(
    name=NAME,
    law="the wall sticks on landings slower than v_stop thetadot_r",
    params=(V_STOP,),
    laws=laws,
    boundaries=BOTH,
    stage=Stage.AFTER_SELECTION,
    unexplained=end_of_motion,
    estimate=estimate,
    short="stop",
)
