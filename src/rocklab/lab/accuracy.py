"""Measured accuracy of each instrument against the virtual lab's truth.

The same walls, released and rocking as the simulator says, recorded by
transducers, by a motion-capture system or by an inertial sensor
(:mod:`rocklab.lab.virtual_lab`), reduced as the workflow reduces them
(:func:`rocklab.lab.reduction.reduce_test`,
:func:`rocklab.lab.motion.stored_motion`), and compared with the truth:

* the per-impact coefficient of restitution e_k = thetadot_after /
  thetadot_before of each impact found, against the simulator's impact at
  the same instant (:func:`impact_errors`);
* theta against the true rotation, root mean square over the record.

The workflow's job ``instrument_accuracy`` (part of ``all``) writes
:func:`accuracy_summary` as ``results/summaries/instruments.json``;
``docs/instruments.md`` quotes it.
"""

from __future__ import annotations

import tempfile
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from rocklab.summaries import LAST_DIGIT

#: The instruments and sampling rates measured by default [Hz]: the labs' ranges (docs/raw-format.md).
RATES = {"transducers": (100.0, 400.0), "rotation": (100.0, 240.0, 500.0), "inertial": (200.0, 1000.0, 2000.0)}
#: How far two machines may take the summary apart: the simulator and the fits
#: in floating point, which no floating-point environment moved
#: (bench/environments.py): the last digit kept.
TOLERANCES = {"*": LAST_DIGIT}
#: Largest distance in time between a found impact and the true one it is compared with [s].
MATCH_S = 0.02
#: An impact whose e is found within this of the truth is resolved (:func:`smallest_resolved`).
RESOLVED_E = 0.05


def _matches(found: pd.DataFrame, truth: pd.DataFrame, tol_s: float) -> tuple[pd.DataFrame, np.ndarray, np.ndarray]:
    """The impacts found with velocities, which of them match a true impact, and the true impact of each."""
    found = found[np.isfinite(found.e_velocity)]
    if not len(found) or not len(truth):
        return found, np.zeros(len(found), bool), np.zeros(len(found), int)
    t_true = truth.t.to_numpy(float)
    j = np.clip(np.searchsorted(t_true, found.t_s.to_numpy(float)), 1, len(t_true) - 1)
    j = np.where(np.abs(t_true[j - 1] - found.t_s) < np.abs(t_true[j] - found.t_s), j - 1, j)
    near = np.abs(t_true[j] - found.t_s.to_numpy(float)) <= tol_s
    return found, near, j


def impact_errors(found: pd.DataFrame, truth: pd.DataFrame, tol_s: float = MATCH_S) -> np.ndarray:
    """e_k found minus the true e_k of the impact at the same instant, one per impact matched.

    Parameters
    ----------
    found : DataFrame
        ``t_s`` [s, record time] and ``e_velocity`` of the impacts found
        (:attr:`rocklab.lab.motion.Motion.impacts`); those without velocities are left out.
    truth : DataFrame
        ``t`` [s, record time] and ``e`` of the simulator's impacts.
    tol_s : float
        Largest distance in time of a match [s].
    """
    found, near, j = _matches(found, truth, tol_s)
    return found.e_velocity.to_numpy(float)[near] - truth.e.to_numpy(float)[j[near]]


def smallest_resolved(found: pd.DataFrame, truth: pd.DataFrame, tol_s: float = MATCH_S) -> float:
    """The slowest true impact whose e was found within :data:`RESOLVED_E`: its |thetadot_before| [rad/s].

    ``truth`` also gives ``thetadot_before`` [rad/s]; NaN when no impact is resolved.
    """
    found, near, j = _matches(found, truth, tol_s)
    err = found.e_velocity.to_numpy(float)[near] - truth.e.to_numpy(float)[j[near]]
    speed = np.abs(truth.thetadot_before.to_numpy(float)[j[near]])[np.abs(err) <= RESOLVED_E]
    return float(speed.min()) if speed.size else np.nan


def instrument_accuracy(
    instrument: str, fs: float, n_tests: int = 4, seed: int = 0, resolution: bool = False, **options: Any
) -> dict[str, Any]:
    """Per-impact e error and theta error of one instrument at one sampling rate.

    ``n_tests`` two-sided tests of the default specimens with the default
    effects of each instrument, their hidden causes off.

    Returns
    -------
    dict
        ``n_tests``, ``n_impacts`` (matched), ``e_error_median`` (signed),
        ``e_abs_error_median``, ``e_abs_error_p90``, ``theta_rms_rad``
        (median over the tests), ``theta_rms_over_alpha``, and for an
        inertial record ``bound_rad`` (median stated bound) and ``bound_held``
        (tests whose largest error is within it); with ``resolution``,
        ``smallest_resolved_rad_s`` (the slowest impact of all the tests
        whose e was found within :data:`RESOLVED_E`, :func:`smallest_resolved`)
        and ``first_impact_rad_s`` (the median first impact's, for scale).
        ``options``: further :class:`~rocklab.lab.virtual_lab.VirtualTest`
        fields of every test (``video``, ``markers``, ...).
    """
    from rocklab.lab.campaign import open_campaign
    from rocklab.lab.motion import motion_from_dataset, stored_motion
    from rocklab.lab.reduction import reduce_test
    from rocklab.lab.virtual_lab import DEFAULT_SPECIMENS, VirtualTest, simulate_virtual_test, write_campaign

    specs = DEFAULT_SPECIMENS.specimen.tolist()
    plan = [
        VirtualTest(f"A{k:02d}", specimen=specs[k % len(specs)], fs=fs, instrument=instrument, **options)
        for k in range(n_tests)
    ]
    errors: list[np.ndarray] = []
    rms: list[float] = []
    rms_alpha: list[float] = []
    bounds: list[float] = []
    resolved: list[float] = []
    first: list[float] = []
    held = 0
    truths: dict[str, dict[str, Any]] = {}

    def simulate(test: VirtualTest, *args: Any) -> tuple[Any, Any, dict[str, Any]]:
        # the truth of the record written, kept rather than simulated a second time
        t, readings, truths[test.test_id] = simulate_virtual_test(test, *args)
        return t, readings, truths[test.test_id]

    with tempfile.TemporaryDirectory() as tmp:
        write_campaign(tmp, plan, seed=seed, simulate=simulate)
        campaign = open_campaign(tmp)
        for test in plan:
            truth = truths[test.test_id]
            ds = reduce_test(campaign, test.test_id)
            motion = motion_from_dataset(stored_motion(ds))
            errors.append(impact_errors(motion.impacts, truth["impacts"]))
            if resolution and len(truth["impacts"]):
                resolved.append(smallest_resolved(motion.impacts, truth["impacts"]))
                first.append(abs(float(truth["impacts"].thetadot_before.iloc[0])))
            diff = ds.theta.values - truth["theta"]
            rms.append(float(np.sqrt(np.mean(diff**2))))
            rms_alpha.append(rms[-1] / truth["alpha"])
            if instrument == "inertial":
                bounds.append(float(ds.attrs["theta_error_bound_rad"]))
                held += int(np.max(np.abs(diff)) <= bounds[-1])
    e = np.concatenate(errors)
    out: dict[str, Any] = {
        "n_tests": n_tests,
        "n_impacts": int(e.size),
        "e_error_median": float(np.median(e)) if e.size else None,
        "e_abs_error_median": float(np.median(np.abs(e))) if e.size else None,
        "e_abs_error_p90": float(np.percentile(np.abs(e), 90)) if e.size else None,
        "theta_rms_rad": float(np.median(rms)),
        "theta_rms_over_alpha": float(np.median(rms_alpha)),
    }
    if resolution:
        out.update(
            smallest_resolved_rad_s=float(np.nanmin(resolved)) if np.isfinite(resolved).any() else None,
            first_impact_rad_s=float(np.median(first)) if first else None,
        )
    if instrument == "inertial":
        out.update(bound_rad=float(np.median(bounds)), bound_held=held)
    return out


def accuracy_summary(
    rates: Mapping[str, Sequence[float]] | None = None, n_tests: int = 4, seed: int = 0
) -> dict[str, dict[str, dict[str, Any]]]:
    """:func:`instrument_accuracy` of every instrument and rate: {instrument: {"<fs>": dict}}."""
    rates = RATES if rates is None else rates
    return {
        kind: {f"{fs:g}": instrument_accuracy(kind, fs, n_tests, seed) for fs in fss} for kind, fss in rates.items()
    }
