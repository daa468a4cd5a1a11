"""Batch engine: many rocking walls, or many scalings of one record, at once.

Every history runs the numba event-driven integrator
:func:`rocklab.simulation.engine.run_history` (same conventions as the reference of
:mod:`rocklab.simulation.rocking_model`: onset, impacts, rest, overturning); the histories are
spread over the cores with ``numba.prange``.  For the linear (Housner) form a
step is one sample interval of the (time-scaled) record, integrated in closed
form; impacts, onset and overturning are located inside it by bisection.  The
exact form takes ``substeps`` RK4 steps per sample interval.

Scaling (Sect. 5): an amplitude scale multiplies ``ag``; a duration scale
``s`` stretches time, i.e. the record is read with interval ``dt * s``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Literal, overload

import numba
import numpy as np
import numpy.typing as npt
import xarray as xr
from numba.core.ccallback import CFunc

from rocklab.physics.flight import FloatArray
from rocklab.simulation.engine import batch_kernel as _kernel
from rocklab.simulation.engine import free_record as _record
from rocklab.simulation.engine import slot
from rocklab.simulation.flight_terms import flight_function
from rocklab.simulation.rocking_model import OVERTURN, REST_TOL, RockingModel, record_times


def _model_arrays(
    models: Sequence[RockingModel], overturn: float, rest_tol: float, substeps: int
) -> tuple[FloatArray, FloatArray, CFunc]:
    """The engine's parameter vectors and impact laws of ``models``, one row each, and the function of
    their terms in flight (those of every model, in the slots each vector holds them in)."""
    terms = tuple(dict.fromkeys(t for m in models for t, _ in m.engine_terms()))
    prm = np.array([m.numba_params(overturn, rest_tol, substeps, terms) for m in models])
    laws = [m.numba_law() for m in models]
    # a wall without a law of the impact speed has no columns for one: zeros, none
    width = max(w.shape[1] for w in laws)
    law = np.array([np.pad(w, ((0, 0), (0, width - w.shape[1]))) for w in laws])
    return prm, law, flight_function(terms)


@overload
def overturning_batch(
    ag: npt.ArrayLike,
    dt: float,
    model: RockingModel,
    amplitude_scales: npt.ArrayLike,
    duration_scales: npt.ArrayLike,
    *,
    overturn: float = ...,
    rest_tol: float = ...,
    substeps: int = ...,
    tail: float = ...,
    return_max: Literal[False] = ...,
) -> npt.NDArray[np.bool_]: ...


@overload
def overturning_batch(
    ag: npt.ArrayLike,
    dt: float,
    model: RockingModel,
    amplitude_scales: npt.ArrayLike,
    duration_scales: npt.ArrayLike,
    *,
    overturn: float = ...,
    rest_tol: float = ...,
    substeps: int = ...,
    tail: float = ...,
    return_max: Literal[True],
) -> tuple[npt.NDArray[np.bool_], FloatArray]: ...


def overturning_batch(
    ag: npt.ArrayLike,
    dt: float,
    model: RockingModel,
    amplitude_scales: npt.ArrayLike,
    duration_scales: npt.ArrayLike,
    *,
    overturn: float = OVERTURN,
    rest_tol: float = REST_TOL,
    substeps: int = 1,
    tail: float = 120.0,
    return_max: bool = False,
) -> npt.NDArray[np.bool_] | tuple[npt.NDArray[np.bool_], FloatArray]:
    """Overturning map of one wall under scaled copies of one record (Sect. 5).

    Parameters
    ----------
    ag : array_like
        Ground acceleration [m/s^2], positive towards +theta.
    dt : float
        Sample interval [s].
    model : RockingModel
        Any law with a flat form (not :class:`~rocklab.physics.impact.Custom`);
        terms in flight beyond the viscous loss in the exact form only
        (:meth:`~rocklab.simulation.rocking_model.RockingModel.numba_params`).
    amplitude_scales, duration_scales : array_like
        A_S/A multiplies ``ag``; D_S/D multiplies ``dt``.
    overturn : float
        Overturning rotation [rad] (default pi/2, see :mod:`rocklab.simulation.rocking_model`).
    substeps : int
        RK4 steps per sample interval for the exact form (ignored by the
        linear form, which is exact per interval).
    tail : float
        Longest free motion [s] followed after the record (the wall is
        followed only while it leans beyond alpha or its energy can still
        reach alpha).
    return_max : bool
        Also return max |theta| / alpha_s of each history.

    Returns
    -------
    overturned : ndarray of bool, shape (len(amplitude_scales), len(duration_scales))
    max_ratio : ndarray, same shape (only with ``return_max``)
    """
    amp = np.atleast_1d(np.asarray(amplitude_scales, float))
    dur = np.atleast_1d(np.asarray(duration_scales, float))
    A, D = np.meshgrid(amp, dur, indexing="ij")
    n = A.size
    prm, law, terms = _model_arrays([model], overturn, rest_tol, substeps)
    # prange hands each thread one contiguous block of histories, and the
    # cost of an amplitude row varies several times from row to row:
    # interleaved, every thread gets a share of each row (2-17 % of a map's
    # time lost to the idle thread otherwise, measured on three records)
    order = np.argsort(np.arange(n) % numba.get_num_threads(), kind="stable")
    h = (dt * D).ravel()[order]
    n_tail = np.ceil(tail / h).astype(np.int64)
    out = _kernel(
        np.ascontiguousarray(ag, float),
        h,
        A.ravel()[order],
        n_tail,
        False,
        np.repeat(prm, n, axis=0),
        np.repeat(law, n, axis=0),
        terms,
        np.zeros(n),
        np.zeros(n),
        0,
    )
    over, max_ratio = np.empty(n, bool), np.empty(n)
    over[order], max_ratio[order] = out[0], out[2]
    return (over.reshape(A.shape), max_ratio.reshape(A.shape)) if return_max else over.reshape(A.shape)


def ground_batch(
    ag: npt.ArrayLike,
    dt: float,
    models: Sequence[RockingModel],
    *,
    amplitude_scale: npt.ArrayLike = 1.0,
    duration_scale: npt.ArrayLike = 1.0,
    overturn: float = OVERTURN,
    rest_tol: float = REST_TOL,
    substeps: int = 1,
    tail: float = 120.0,
    max_impacts: int = 0,
) -> xr.Dataset:
    """Many walls under one record (each optionally with its own scaling).

    Parameters
    ----------
    ag, dt : see :func:`overturning_batch`.
    models : sequence of RockingModel
    amplitude_scale, duration_scale : float or array_like, broadcast to len(models)
    tail : float
        Longest free motion [s] followed after the record: every wall is
        followed until it overturns or rests, so that the impacts and
        ``max_ratio`` cover the whole response.
    max_impacts : int
        Impacts logged per history.

    Returns
    -------
    xarray.Dataset
        ``overturned``, ``t_overturn`` [s], ``max_ratio`` (max |theta|/alpha_s),
        ``n_impacts`` on dim ``history``, and the impact log (see
        :func:`free_batch`) on (history, impact).
    """
    prm, law, terms = _model_arrays(models, overturn, rest_tol, substeps)
    n = len(models)
    h = dt * np.broadcast_to(np.asarray(duration_scale, float), (n,)).copy()
    scale = np.broadcast_to(np.asarray(amplitude_scale, float), (n,)).copy()
    n_tail = np.ceil(tail / h).astype(np.int64)
    out = _kernel(
        np.ascontiguousarray(ag, float), h, scale, n_tail, True, prm, law, terms, np.zeros(n), np.zeros(n), max_impacts
    )
    return _dataset(out)


def free_batch(
    model: RockingModel,
    theta0: npt.ArrayLike,
    thetadot0: npt.ArrayLike = 0.0,
    *,
    alpha_rock: npt.ArrayLike | None = None,
    alpha_neg: npt.ArrayLike | None = None,
    zeta: npt.ArrayLike | None = None,
    e_scale: npt.ArrayLike | None = None,
    amplitude_a: npt.ArrayLike | None = None,
    amplitude_b: npt.ArrayLike | None = None,
    law: npt.ArrayLike | None = None,
    t_end: float = 30.0,
    dt: float = 1.0 / 400.0,
    substeps: int = 4,
    max_impacts: int = 100,
    overturn: float = OVERTURN,
    rest_tol: float = REST_TOL,
) -> xr.Dataset:
    """Free rocking of many parameter sets at once (used by model fitting).

    Every keyword given as an array overrides the model's value history by
    history; all arrays broadcast together with ``theta0``.

    Parameters
    ----------
    model : RockingModel
        Template: boundary, form, gap, nominal alpha, p and impact law.
    theta0, thetadot0 : array_like
        Initial rotation [rad] and angular velocity [rad/s].
    alpha_rock, alpha_neg : array_like, optional
        Rocking angles of the positive and negative hinge [rad].
    zeta : array_like, optional
        Viscous-like loss between impacts, -2 zeta p thetadot [-].
    e_scale : array_like, optional
        Multiplies the base-impact coefficients (e.g. e_exp/e_an).
    amplitude_a, amplitude_b : array_like, optional
        Replace a, b of the base-impact laws (Eq. 17 form).
    law : ndarray (n, 3, 3) or (n, 3, 4), optional
        Full flat laws (rows base +, base -, transverse; columns e0, a, b
        and optionally v_stick), see
        :meth:`rocklab.simulation.rocking_model.RockingModel.numba_law`; applied before e_scale.
    t_end, dt : float
        Duration [s] and step [s] (the closed form of the linear model is
        exact for any step; the exact form takes ``substeps`` RK4 steps).
    max_impacts : int
        Impacts logged per history.

    Returns
    -------
    xarray.Dataset
        On (history, impact): ``t_impact`` [s], ``thetadot_before``,
        ``thetadot_after`` [rad/s], ``theta_peak`` [rad] (largest |theta|
        before each impact: ``theta_peak[:, n]`` is |theta_n| of Eq. 10 and
        ``theta_peak[:, 0]`` the release); on history: ``n_impacts``,
        ``overturned``, ``t_overturn``, ``max_ratio``.  NaN-padded.
    """
    arrays = {
        "theta0": theta0,
        "thetadot0": thetadot0,
        "alpha_rock": alpha_rock,
        "alpha_neg": alpha_neg,
        "zeta": zeta,
        "e_scale": e_scale,
        "amplitude_a": amplitude_a,
        "amplitude_b": amplitude_b,
    }
    given = {k: np.asarray(v, float) for k, v in arrays.items() if v is not None}
    shapes = [v.shape for v in given.values()] + ([np.shape(law)[:-2]] if law is not None else [])
    n = int(np.prod(np.broadcast_shapes(*shapes))) if shapes else 1
    b = {k: np.broadcast_to(v, np.broadcast_shapes(*shapes)).ravel() for k, v in given.items()}
    prm, law0, terms = _model_arrays([model], overturn, rest_tol, substeps)
    prm = np.repeat(prm, n, axis=0)
    laws = np.repeat(law0, n, axis=0)
    if law is not None:
        # a law without the sticking column never sticks
        law = np.asarray(law, float)
        laws[..., : law.shape[-1]] = law
        laws[..., law.shape[-1] :] = 0.0
    if "alpha_rock" in b:
        prm[:, slot("alpha_pos")] = b["alpha_rock"]
        if "alpha_neg" not in b and model.alpha_neg is None:
            prm[:, slot("alpha_neg")] = b["alpha_rock"]
    if "alpha_neg" in b:
        prm[:, slot("alpha_neg")] = b["alpha_neg"]
    if "zeta" in b:
        prm[:, slot("zeta")] = b["zeta"]
    if "e_scale" in b:
        laws[:, :2, 0] *= b["e_scale"][:, None]
    if "amplitude_a" in b:
        laws[:, :2, 1] = b["amplitude_a"][:, None]
    if "amplitude_b" in b:
        laws[:, :2, 2] = b["amplitude_b"][:, None]
    n_steps = int(np.ceil(t_end / dt))
    out = _kernel(
        np.zeros(n_steps),
        np.full(n, dt),
        np.ones(n),
        np.zeros(n, np.int64),
        False,
        prm,
        laws,
        terms,
        b.get("theta0", np.zeros(n)).copy(),
        b.get("thetadot0", np.zeros(n)).copy(),
        max_impacts,
    )
    return _dataset(out)


def free_record(
    model: RockingModel,
    theta0: float,
    thetadot0: float = 0.0,
    *,
    t_end: float = 30.0,
    fs: float = 400.0,
    substeps: int = 8,
    overturn: float = OVERTURN,
    rest_tol: float = REST_TOL,
) -> tuple[FloatArray, FloatArray] | None:
    """Free rocking of one wall, its record: the engine's :func:`rocklab.simulation.engine.run_history`
    in place of :func:`rocklab.simulation.reference.simulate_free` where the engine holds the wall.

    On the reference's grid (0, 1/fs, ... up to ``t_end``), ``substeps`` RK4 steps per sample interval
    of the exact form; at the default 8 the impacts are the reference's within 1e-9 s and 1e-9 rad/s
    (tests/test_every_law.py).

    Returns
    -------
    (t, theta) : tuple of ndarray, or None
        Time [s] and rotation [rad], NaN past ``t_end`` as the reference's; None for a wall that
        overturns (the reference's record then ends in NaN, which this one does not reproduce).

    Raises
    ------
    NotImplementedError
        For a wall the engine does not hold (:meth:`RockingModel.numba_params`, :meth:`RockingModel.numba_law`).
    """
    t = record_times(t_end, fs)
    prm, law, terms = _model_arrays([model], overturn, rest_tol, substeps)
    over, theta = _record(1.0 / fs, t.size - 1, prm[0], law[0], terms, float(theta0), float(thetadot0))
    # the grid's last sample may lie past t_end by up to half an interval: the reference leaves it NaN
    theta[t > t_end] = np.nan
    return None if over else (t, theta)


def _dataset(out: tuple[npt.NDArray[Any], ...]) -> xr.Dataset:
    over, t_over, max_ratio, n_imp, log_t, log_vb, log_va, log_pk = out
    hist, imp = ("history",), ("history", "impact")
    return xr.Dataset(
        {
            "overturned": (hist, over),
            "t_overturn": (hist, t_over, {"units": "s"}),
            "max_ratio": (hist, max_ratio, {"long_name": "max |theta| / alpha_s"}),
            "n_impacts": (hist, n_imp),
            "t_impact": (imp, log_t, {"units": "s"}),
            "thetadot_before": (imp, log_vb, {"units": "rad/s"}),
            "thetadot_after": (imp, log_va, {"units": "rad/s"}),
            "theta_peak": (imp, log_pk, {"units": "rad", "long_name": "largest |theta| before the impact"}),
        }
    )


def compile_kernels() -> None:
    """Compile the engine's numba kernels into numba's on-disk cache.

    Runs :func:`overturning_batch`, :func:`ground_batch`, :func:`free_batch`
    and :func:`free_record` once on tiny inputs, so that the kernels are compiled
    with the argument types of the library's own calls.  A process that then
    runs a map loads them from the cache (a fraction of a second) instead of
    compiling them (about 12 s of CPU, once per process while the cache is
    cold).  ``make venv`` calls it through
    :func:`rocklab.kernels.compile_kernels` after the install.
    """
    model = RockingModel(alpha=0.1, p=2.0, form="linear")
    ag = np.array([0.0, -5.0, 0.0, 0.0])
    overturning_batch(ag, 0.01, model, [1.0], [1.0], tail=0.1)
    ground_batch(ag, 0.01, [model], tail=0.1, max_impacts=1)
    free_batch(model, 0.05, t_end=0.1, max_impacts=1)
    free_record(model, 0.05, t_end=0.1)
