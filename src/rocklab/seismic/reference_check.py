"""The overturning maps checked against the event-driven reference (:mod:`rocklab.simulation.reference`).

The maps' batch engine decides each cell in closed form per record
interval; the scipy reference integrates the same wall with events at every
impact.  :func:`reference_decisions` runs the reference on chosen cells,
:func:`check_against_reference` compares a map with it and explains each
difference by the overturning boundary (``bench/maps_reference.py``).
"""

from __future__ import annotations

from collections.abc import Sequence
from multiprocessing.pool import Pool
from typing import Any

import numpy as np
import numpy.typing as npt

from rocklab.simulation.reference import simulate_ground
from rocklab.simulation.rocking_model import OVERTURN, RockingModel


def _reference_one(
    args: tuple[RockingModel, npt.NDArray[np.float64], float, float, float, float, float, float, float],
) -> bool:
    """Whether the reference overturns the wall at one cell (one job of :func:`reference_decisions`)."""
    model, ag, dt, a, d, rtol, atol, overturn, tail = args
    return simulate_ground(model, a * ag, dt * d, overturn=overturn, rtol=rtol, atol=atol, tail=tail).overturned


def reference_decisions(
    ag: npt.ArrayLike,
    dt: float,
    model: RockingModel,
    cells: Sequence[tuple[float, float]],
    *,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    overturn: float = OVERTURN,
    tail: float = 120.0,
    pool: Pool | None = None,
) -> npt.NDArray[np.bool_]:
    """Overturning of the scipy event-driven reference at given (A_S/A, D_S/D) cells.

    Parameters
    ----------
    ag, dt : array_like, float
        Record [m/s^2] (polarity applied) and sample interval [s].
    model : rocklab.simulation.rocking_model.RockingModel
    cells : sequence of (float, float)
        Amplitude and duration scales.
    rtol, atol : float
        Tolerances of :func:`rocklab.simulation.reference.simulate_ground`.
    pool : multiprocessing.pool.Pool, optional
        Spreads the histories over its workers.

    Returns
    -------
    ndarray of bool
    """
    ag = np.asarray(ag, float)
    jobs = [(model, ag, dt, float(a), float(d), rtol, atol, overturn, tail) for a, d in cells]
    results = pool.map(_reference_one, jobs, chunksize=4) if pool is not None else map(_reference_one, jobs)
    return np.fromiter(results, bool, count=len(jobs))


def check_against_reference(
    ag: npt.ArrayLike,
    dt: float,
    model: RockingModel,
    amplitude_scales: npt.ArrayLike,
    duration_scales: npt.ArrayLike,
    fast: npt.ArrayLike,
    step: float,
    *,
    pool: Pool | None = None,
    **kw: Any,
) -> dict[str, Any]:
    """Compare a map with the reference and explain each difference by the boundary.

    Criterion: a cell where the map and the reference disagree lies on the
    boundary of the map when the reference itself reaches the map's decision
    at one of the cell's four neighbours of the full grid (A_S/A or D_S/D
    moved by one grid step ``step``); both engines then place the boundary
    within one grid step of each other.

    Parameters
    ----------
    ag, dt, model
        As :func:`reference_decisions`.
    amplitude_scales, duration_scales : array_like
        Scales of the checked cells (a subgrid).
    fast : array_like of bool
        The map's decisions on that subgrid, amplitude along axis 0.
    step : float
        Grid step of the full map (0.005 for 201 values over 0.5-1.5).
    **kw
        rtol, atol, overturn, tail of :func:`reference_decisions`.

    Returns
    -------
    dict
        cells, agree, agreement_pct, mismatches (list of {amplitude_scale,
        duration_scale, map, reference, boundary}), unexplained (count),
        reference (the reference decisions, nested lists).
    """
    amp = np.asarray(amplitude_scales, float)
    dur = np.asarray(duration_scales, float)
    fast = np.asarray(fast, bool)
    cells = [(a, d) for a in amp for d in dur]
    ref = reference_decisions(ag, dt, model, cells, pool=pool, **kw).reshape(fast.shape)
    bad = np.argwhere(ref != fast)
    # the neighbours of every difference in one call, spread over the pool
    around = [
        (a, d)
        for i, j in bad
        for a, d in ((amp[i] - step, dur[j]), (amp[i] + step, dur[j]), (amp[i], dur[j] - step), (amp[i], dur[j] + step))
    ]
    neighbours = reference_decisions(ag, dt, model, around, pool=pool, **kw).reshape(-1, 4)
    mismatches = [
        {
            "amplitude_scale": float(amp[i]),
            "duration_scale": float(dur[j]),
            "map": bool(fast[i, j]),
            "reference": bool(ref[i, j]),
            "boundary": bool((nb == fast[i, j]).any()),
        }
        for (i, j), nb in zip(bad, neighbours)
    ]
    agree = int((ref == fast).sum())
    return {
        "cells": int(fast.size),
        "agree": agree,
        "agreement_pct": 100.0 * agree / fast.size,
        "mismatches": mismatches,
        "unexplained": sum(not m["boundary"] for m in mismatches),
        "reference": ref.tolist(),
    }
