"""Overturning maps of rocking walls under scaled records (Sect. 5, Figs. 21-23).

A map is the overturning decision of one wall under one record whose
amplitude A and duration D are scaled to A_S and D_S, on a grid of ``n x n``
values of A_S/A and D_S/D between ``lo`` and ``hi`` (the paper: 201 values,
50-150 %, i.e. 40401 histories per map).  The amplitude scale multiplies the
ground acceleration; the duration scale stretches time (the record is read
with interval ``dt D_S/D``).

Form of the equation of motion
------------------------------
The maps use Housner's piecewise-linear form (``form="linear"``, see
:mod:`rocklab.simulation.rocking_model`).  Sect. 5 reads the maps through the scaling
equivalences of that model, and for the paper's wall (alpha = 0.1 rad) the
linearisation changes the restoring moment by less than 0.2 %; the batch
engine integrates the linear form in closed form per record interval, so the
map carries no time-step error, and it is about twice as fast as the exact
form.  ``form="exact"`` is available for comparison.

Scaling equivalences (Sect. 5)
------------------------------
Duration <-> size
    Scaling the duration by ``s = D_S/D`` is the same as multiplying ``p`` by
    ``s``, i.e. R by ``(D/D_S)^2``.  Only ``p`` sets the time scale of the
    equation of motion and of Eq. 16, so this holds for both forms and every
    impact law of the maps (:mod:`rocklab.seismic.walls`) (up to the free-motion tail followed after the
    record, which is not rescaled).
Amplitude <-> slenderness
    Scaling the amplitude by ``lambda = A_S/A`` is the same as dividing alpha
    by ``lambda`` (the rotation scales by ``lambda``), but only for the linear
    form, and only if the coefficient of restitution and the overturning
    rotation are scaled with it: e stays that of the unscaled alpha (Eqs. 2,
    14 depend on alpha) and the wall overturns at ``pi/2 / lambda``.  For the
    exact form (sin, cos of alpha - theta) it does not hold.
The maps are computed by simulating the scaled records themselves, so they
use neither equivalence; the tests check both where they hold.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, cast

import numpy as np
import xarray as xr

from rocklab import __version__
from rocklab.io import cf_attrs
from rocklab.physics.flight import FloatArray
from rocklab.seismic import calibrated
from rocklab.seismic.walls import ALPHA, MODELS, R, named_model
from rocklab.simulation.rocking_model import OVERTURN

if TYPE_CHECKING:
    from rocklab.seismic.calibrated import DiagnosisLike

log = logging.getLogger(__name__)

#: How a map decides that the wall overturned, written in its attributes.
OVERTURNING_CRITERION = (
    "|theta| >= {overturn:.6g} rad (wall lying on the ground); after the record a wall still rocking is "
    "followed in free motion up to {tail:g} s while it leans beyond alpha or its energy can reach alpha "
    "(rocklab.simulation.rocking_model)"
)


def scales(n: int = 201, lo: float = 0.5, hi: float = 1.5) -> FloatArray:
    """Grid of A_S/A (or D_S/D) values: ``n`` values from ``lo`` to ``hi``."""
    return np.linspace(float(lo), float(hi), int(n))


def subgrid_step(n: int, n_sub: int) -> int:
    """Stride k such that every k-th of :func:`scales` ``(n)`` is :func:`scales` ``(n_sub)`` (same range).

    Raises
    ------
    ValueError
        When ``n_sub - 1`` does not divide ``n - 1`` (no such stride).
    """
    n, n_sub = int(n), int(n_sub)
    if n_sub < 2 or n_sub > n or (n - 1) % (n_sub - 1):
        raise ValueError(
            f"a grid of {n_sub} values is not a subgrid of one of {n} ({n - 1} is not a multiple of {n_sub - 1})"
        )
    return (n - 1) // (n_sub - 1)


def subgrid(ds: xr.Dataset, n: int) -> xr.Dataset:
    """Map ``ds`` (:func:`overturning_map`) read on the cells of an ``n`` x ``n`` grid of the same range.

    The scatter index of :func:`rocklab.seismic.indices.map_indices` depends on the grid (changes
    grow as n, overturnings as n^2): maps are compared on the same cells.
    """
    k = subgrid_step(ds.sizes["amplitude_scale"], n)
    return ds.isel(amplitude_scale=slice(None, None, k), duration_scale=slice(None, None, k))


def overturning_map(
    # an obspy Trace or an array_like (obspy is untyped, and the two are told apart by their attributes)
    record: Any,
    dt: float | None = None,
    model: str = "2s-housner",
    n: int = 201,
    lo: float = 0.5,
    hi: float = 1.5,
    *,
    alpha: float = ALPHA,
    R: float = R,
    form: str = "linear",
    eq17: tuple[float, float] | None = None,
    diagnosis: DiagnosisLike | None = None,
    polarity: int = 1,
    chunks: int = 10,
    overturn: float = OVERTURN,
    tail: float = 120.0,
    name: str | None = None,
    progress: Callable[[int, int], object] | None = None,
) -> xr.Dataset:
    """Overturning map of a named wall under one record (Sect. 5, Figs. 21, 23).

    Parameters
    ----------
    record : obspy.Trace or array_like
        Ground acceleration [m/s^2], positive towards +theta (a positive
        value pushes the wall towards negative rotations, i.e. a one-sided
        wall against the transverse walls); a Trace gives ``dt`` and the
        record's name.
    dt : float, optional
        Sample interval [s]; required for an array.
    model : str
        A key of :data:`rocklab.seismic.walls.MODELS`, or a calibrated model (with ``diagnosis``).
    n, lo, hi : int, float, float
        Grid of A_S/A and D_S/D (:func:`scales`); the paper: 201, 0.5, 1.5.
    alpha, R, form, eq17, diagnosis
        Wall and law, see :func:`rocklab.seismic.walls.named_model`.
    polarity : {1, -1}
        Multiplies the record: the maps of one-sided walls depend on it.
    chunks : int
        The map is computed in this many blocks of amplitude rows, each
        logged (logger ``rocklab.seismic.maps``) as it completes.
    overturn, tail
        Overturning rotation [rad] and longest free motion after the record
        [s], see :func:`rocklab.simulation.batch.overturning_batch`.
    name : str, optional
        Record name for the attributes; default the Trace's ``stats.record``.
    progress : callable, optional
        Called as ``progress(rows_done, rows_total)`` after each block of
        amplitude rows, e.g. to draw a progress bar (``rocklab map``).

    Returns
    -------
    xarray.Dataset
        Boolean ``overturned`` on (``amplitude_scale``, ``duration_scale``),
        with the wall (alpha, R, p, form, boundary), the impact law, the
        overturning criterion and the record in the attributes.
    """
    if dt is None:
        if not hasattr(record, "stats"):
            raise TypeError("an array record needs its sample interval dt")
        ag, dt = np.asarray(record.data, float), float(record.stats.delta)
        name = name or record.stats.get("record") or record.id
    else:
        ag = np.asarray(record, float)
    if polarity not in (1, -1):
        raise ValueError(f"polarity must be 1 or -1, not {polarity!r}")
    # imported here: numba (0.4 s) is for the map jobs, not for the configuration
    # check and the calibrated walls' job that import this module for its grids
    from rocklab.simulation.batch import overturning_batch

    wall_model = named_model(model, alpha, R, form, eq17, diagnosis)
    amp, dur = scales(n, lo, hi), scales(n, lo, hi)
    over = np.zeros((amp.size, dur.size), bool)
    signed = polarity * ag
    t0 = time.perf_counter()
    for rows in np.array_split(np.arange(amp.size), max(1, min(int(chunks), amp.size))):
        over[rows] = overturning_batch(signed, dt, wall_model, amp[rows], dur, overturn=overturn, tail=tail)
        log.info(
            "%s %s: amplitude rows %d-%d of %d done, %.1f s",
            name,
            model,
            rows[0] + 1,
            rows[-1] + 1,
            amp.size,
            time.perf_counter() - t0,
        )
        if progress is not None:
            progress(int(rows[-1]) + 1, amp.size)
    e0, a, b, v_stick = wall_model.numba_law()[0, :4]
    return xr.Dataset(
        {
            "overturned": (
                ("amplitude_scale", "duration_scale"),
                over,
                {
                    "long_name": "wall overturned",
                    # a boolean is stored as a byte, and CF flags have the type of the variable
                    "flag_values": np.array([0, 1], np.int8),
                    "flag_meanings": "standing overturned",
                },
            )
        },
        coords={
            "amplitude_scale": (
                "amplitude_scale",
                amp,
                {"long_name": "A_S/A, amplitude scale of the record", "units": "1"},
            ),
            "duration_scale": (
                "duration_scale",
                dur,
                {"long_name": "D_S/D, duration scale of the record", "units": "1"},
            ),
        },
        attrs={
            **cf_attrs(
                f"overturning map, record {name}, model {model} (Sect. 5)",
                f"rocking simulation of a wall under a scaled accelerogram, model {model}",
            ),
            "record": str(name),
            "dt": dt,
            "npts": int(ag.size),
            "polarity": int(polarity),
            "model": model,
            "model_description": (
                # a calibrated model has its diagnosis: named_model refused it without one
                calibrated.describe(cast("DiagnosisLike", diagnosis), model)
                if calibrated.is_calibrated(model)
                else MODELS[model][1]
            ),
            "alpha": wall_model.alpha,
            "R": float(R),
            "p": wall_model.p,
            "form": form,
            "boundary": wall_model.boundary,
            "impact_law": type(wall_model.base_law).__name__,
            # the engines' law e = e0 clip(a - b (thetadot^-/thetadot_r)^2) (rocklab.physics.impact),
            # 0 below a landing of v_stick thetadot_r; positive hinge (the calibrated walls'
            # other hinge and transverse impacts are in model_description)
            "impact_e0": float(e0),
            "impact_a": float(a),
            "impact_b": float(b),
            "impact_v_stick": float(v_stick),
            "alpha_rock": wall_model.alpha_pos,
            "alpha_neg": wall_model.alpha_minus,
            "gap": wall_model.gap,
            "overturning_criterion": OVERTURNING_CRITERION.format(overturn=overturn, tail=tail),
            "compute_s": time.perf_counter() - t0,
            "rocklab_version": __version__,
        },
    )
