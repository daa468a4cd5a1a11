"""What a model gets wrong, in measures an engineer reads: impacts, duration, decay, periods, lag.

The free run of a model (:func:`rocklab.diagnosis.wall_model.free_run`) from
each test's measured release against the measured motion
(:func:`engineering_rows`), summarised over a series
(:func:`summarise_rows`, :func:`rocklab.diagnosis.extended.engineering_errors`
for a model of named causes) and stated in words (:func:`what_is_wrong`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, TypedDict

import numpy as np

from rocklab.diagnosis.estimation import finite_mean
from rocklab.diagnosis.evidence import MeasuredTest, TestStack, log_ratio, residuals
from rocklab.diagnosis.result import Errors
from rocklab.diagnosis.wall_model import ModelParams, free_run, simulate_test
from rocklab.simulation.rocking_model import RockingModel


class EngineeringRow(TypedDict):
    """The measures of one test's free run (:func:`engineering_rows`): (measured, model) pairs, or numbers."""

    n_impacts: tuple[int, int]
    duration_s: tuple[float, float]
    decay_pct: tuple[float, float]
    first_quarter_p: tuple[float, float]
    flight_time_pct: float
    lag_s: float
    lag_cycles: float
    common_impacts: int
    log_peak_rms: float


def engineering_rows(tests: Sequence[MeasuredTest], mp: ModelParams, n_max: int = 600) -> list[EngineeringRow]:
    """Per-test measures of the free run of the model ``mp`` of ``tests`` against the measured motion.

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
    S = TestStack.of(tests)
    run = free_run(S, mp, n_max)
    R = residuals(S, mp)
    rows: list[EngineeringRow] = []
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
            F = log_ratio(np.r_[M, np.zeros(max(n_meas - M.size, 0))][:n_meas], ts.peaks, ts.floor)
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


def history_rms(test: MeasuredTest, model: RockingModel) -> float:
    """RMS of (theta_model - theta_measured) / alpha over the measured motion (the simulator ``model``,
    run by the numba engine where it holds the wall, within its stated tolerance of the exact one:
    :func:`rocklab.diagnosis.wall_model.simulate_test`)."""
    if test.t is None or test.theta is None:
        return np.nan
    t, th = simulate_test(test, model, engine=True)
    sel = (test.t >= test.t_release) & (test.t <= test.t_end)
    m = np.interp(test.t[sel], t, th, right=0.0)
    return float(np.sqrt(np.mean((m - test.theta[sel]) ** 2)) / test.alpha)


def summarise_rows(rows: Sequence[Mapping[str, object]]) -> Errors:
    """Means over tests of :func:`engineering_rows` (measured, model)."""
    out: Errors = {}
    for key in rows[0]:
        vals = [r[key] for r in rows]
        if isinstance(vals[0], tuple):
            arr = np.array(vals, float)
            out[key] = {"measured": finite_mean(arr[:, 0]), "model": finite_mean(arr[:, 1])}
        else:
            out[key] = finite_mean(np.array(vals, float))
    return out


def what_is_wrong(errors: Errors, model: str = "the simulation") -> tuple[str, bool]:
    """Plain statement, in numbers, of where a model's free run departs from the tests.

    Returns
    -------
    (str, bool)
        The statement and whether any measure departs beyond its tolerance
        (duration 20 %, decay 1 point, quarter period 10 %, flight time 3 %,
        lag 0.5 cycle).
    """
    # each measure's kind (a pair, a number) is known by its key: read as such
    e: Mapping[str, Any] = errors
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
