"""Four-degree-of-freedom kinematics of a rocking wall from its transducers.

Sect. 2.2 of the paper (Eqs. 3-8), written in the coordinates of the lab's
raw format (``docs/raw-format.md``).  A body point X of the wall maps
to the lab as

    X' = Rz(phi) . (Rx(theta) . (X - E) + E) + (v, w, 0),

E = (0, s b/2, 0) on the active base edge, s = sgn(theta) (the edge
y = +b/2 when theta > 0, y = -b/2 when theta < 0; both coincide at theta = 0,
so the map is continuous but has a kink there).  ``Rx(theta)`` tips the top
towards +y for theta > 0: (y, z) -> (y cos + z sin, -y sin + z cos);
``Rz(phi)`` is the right-handed twist about z: (x, y) -> (x cos - y sin,
x sin + y cos).  A transducer between the wall point X and the frame point F
reads the elongation |X' - F| - |X - F| (Eq. 3, the paper's component sums
of Eqs. 4-7 being this vector written out for horizontal instruments on the
lateral faces; here any geometry is accepted).

Lengths in mm, angles in rad.  The solver works on all time steps at once:
Gauss-Newton with the analytic Jacobian (Newton when exactly as many channels
as unknowns, least squares when more), each step's small normal system being
solved by a Cholesky factorisation, in compiled loops over the time steps
(:mod:`rocklab.lab.kinematics_kernels`).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from rocklab.lab import kinematics_kernels as kernels

if TYPE_CHECKING:
    import xarray as xr

#: Order of the unknowns in ``x0`` and in the Jacobian.
DOF = ("theta", "phi", "v", "w")


def _as_taken(a: ArrayLike) -> np.ndarray:
    """``a`` as float64, C-ordered and writeable: as the compiled loops take it (another kind of array would
    have them compile again, in the job that passed it)."""
    return np.require(a, float, ("C", "W"))


def _geometry(wall_xyz: ArrayLike, frame_xyz: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    X = _as_taken(np.atleast_2d(np.asarray(wall_xyz, float)))
    F = _as_taken(np.atleast_2d(np.asarray(frame_xyz, float)))
    if X.shape != F.shape or X.shape[1] != 3:
        raise ValueError("wall_xyz and frame_xyz must both be (nch, 3)")
    return X, F


def _pose(
    theta: np.ndarray,
    phi: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    X: np.ndarray,
    F: np.ndarray,
    thickness: float,
    jacobian: bool,
) -> tuple[np.ndarray, np.ndarray | None]:
    """Lengths |X' - F| per step and channel, shape (N, nch), and (optionally)
    their derivatives with respect to theta, phi, v, w, shape (4, N, nch).
    Inputs theta, phi, v, w have shape (N,)."""
    N, nch = theta.size, X.shape[0]
    L = np.empty((N, nch))
    J = np.empty((4, N if jacobian else 0, nch))
    kernels.pose_steps(
        _as_taken(theta), _as_taken(phi), _as_taken(v), _as_taken(w), _as_taken(X), _as_taken(F), float(thickness), L, J
    )
    return L, (J if jacobian else None)


def lab_points(
    theta: ArrayLike, phi: ArrayLike, v: ArrayLike, w: ArrayLike, X: ArrayLike, thickness: float
) -> np.ndarray:
    """Where body points of the wall are in the lab for a motion (the rigid-body map of ``docs/raw-format.md``).

    ``X' = Rz(phi) . (Rx(theta) . (X - E) + E) + (v, w, 0)``, E on the
    active base edge (y = +-b/2 as theta > 0 or < 0).

    Parameters
    ----------
    theta, phi : array_like (N,)
        Rotations [rad].
    v, w : array_like (N,)
        Sliding [mm].
    X : array_like (npt, 3)
        Body points [mm].
    thickness : float
        Wall thickness b [mm].

    Returns
    -------
    ndarray (N, npt, 3)
        Lab positions [mm].
    """
    X = np.atleast_2d(np.asarray(X, float))
    th, ph, vv, ww = (np.atleast_1d(np.asarray(a, float))[:, None] for a in (theta, phi, v, w))
    ey = np.where(th < 0.0, -0.5 * thickness, 0.5 * thickness)
    x, dy, z = X[:, 0], X[:, 1] - ey, X[:, 2]
    qy = np.cos(th) * dy + np.sin(th) * z + ey
    qz = -np.sin(th) * dy + np.cos(th) * z
    out = [np.cos(ph) * x - np.sin(ph) * qy + vv, np.sin(ph) * x + np.cos(ph) * qy + ww, qz + 0 * vv]
    return np.stack(out, axis=-1)


def rest_length(wall_xyz: ArrayLike, frame_xyz: ArrayLike) -> np.ndarray:
    """Length of each transducer with the wall vertical and at rest [mm]."""
    X, F = _geometry(wall_xyz, frame_xyz)
    return np.linalg.norm(X - F, axis=1)


def transducer_elongation(
    theta: ArrayLike,
    phi: ArrayLike,
    v: ArrayLike,
    w: ArrayLike,
    wall_xyz: ArrayLike,
    frame_xyz: ArrayLike,
    thickness: float,
) -> np.ndarray:
    """Readings of the transducers for a given motion (Eq. 3), forward model.

    Parameters
    ----------
    theta, phi : array_like, shape (N,)
        Rocking rotation about the active base edge and twist about z [rad].
    v, w : array_like, shape (N,)
        Base sliding along x and y [mm].
    wall_xyz, frame_xyz : array_like, shape (nch, 3)
        Transducer end points on the wall (body frame) and on the frame
        (lab frame) [mm], as in ``setups.csv``.
    thickness : float
        Wall thickness b [mm] (the rocking edges are at y = +-b/2).

    Returns
    -------
    ndarray, shape (N, nch)
        Elongation |X' - F| - |X - F| [mm], positive when the transducer
        lengthens; zero with the wall vertical at rest.
    """
    X, F = _geometry(wall_xyz, frame_xyz)
    th, ph, vv, ww = np.broadcast_arrays(*(np.atleast_1d(np.asarray(a, float)) for a in (theta, phi, v, w)))
    L, _ = _pose(th.ravel(), ph.ravel(), vv.ravel(), ww.ravel(), X, F, float(thickness), jacobian=False)
    return L - rest_length(X, F)


def elongation_jacobian(
    theta: ArrayLike,
    phi: ArrayLike,
    v: ArrayLike,
    w: ArrayLike,
    wall_xyz: ArrayLike,
    frame_xyz: ArrayLike,
    thickness: float,
) -> np.ndarray:
    """Derivatives of the transducer readings with respect to the four degrees of freedom.

    The analytic Jacobian of :func:`transducer_elongation` that the solver
    uses, for callers that need the fit's local geometry (the redundant
    directions of :mod:`rocklab.lab.channel_gain`).

    Parameters
    ----------
    theta, phi, v, w, wall_xyz, frame_xyz, thickness
        As in :func:`transducer_elongation` [rad, mm].

    Returns
    -------
    ndarray, shape (N, nch, 4)
        d(elongation)/d(theta, phi) [mm/rad] and d(elongation)/d(v, w) [mm/mm],
        in the order of :data:`DOF`.
    """
    return elongation_and_jacobian(theta, phi, v, w, wall_xyz, frame_xyz, thickness)[1]


def elongation_and_jacobian(
    theta: ArrayLike,
    phi: ArrayLike,
    v: ArrayLike,
    w: ArrayLike,
    wall_xyz: ArrayLike,
    frame_xyz: ArrayLike,
    thickness: float,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`transducer_elongation` and :func:`elongation_jacobian` at once (one evaluation of the model).

    Returns
    -------
    (ndarray (N, nch), ndarray (N, nch, 4))
        The readings [mm] and their derivatives [mm/rad, mm/mm].
    """
    X, F = _geometry(wall_xyz, frame_xyz)
    th, ph, vv, ww = np.broadcast_arrays(*(np.atleast_1d(np.asarray(a, float)) for a in (theta, phi, v, w)))
    L, J = _pose(th.ravel(), ph.ravel(), vv.ravel(), ww.ravel(), X, F, float(thickness), jacobian=True)
    assert J is not None  # asked for
    return L - rest_length(X, F), np.ascontiguousarray(J.transpose(1, 2, 0))


def _weights(elongation: np.ndarray, weights: ArrayLike | None) -> np.ndarray:
    N, nch = elongation.shape
    W = np.ones((N, nch)) if weights is None else np.broadcast_to(np.asarray(weights, float), (N, nch)).copy()
    W[~np.isfinite(elongation)] = 0.0
    return (W > 0).astype(float)


def solve_wall_motion(
    elongation: ArrayLike,
    wall_xyz: ArrayLike,
    frame_xyz: ArrayLike,
    thickness: float,
    weights: ArrayLike | None = None,
    solve_v: bool = True,
    x0: ArrayLike | None = None,
    tol: float = 1e-10,
    max_iter: int = 30,
) -> dict[str, np.ndarray]:
    """Four degrees of freedom of the wall at every time step (Eqs. 3-7).

    Solves |X'(q) - F| - |X - F| = elongation for q = (theta, phi, v, w) at
    all time steps at once by Gauss-Newton with the analytic Jacobian: the
    exact Newton method when as many good channels as unknowns, the least
    squares solution when more.  A step is halved while it does not lower
    the squared residual, which keeps the iteration on track across the
    kink of the model at theta = 0 (where the active base edge switches).

    Parameters
    ----------
    elongation : array_like, shape (N, nch)
        Transducer readings [mm]; NaN marks a lost sample (that channel is
        dropped at that step).
    wall_xyz, frame_xyz : array_like, shape (nch, 3)
        Transducer end points [mm] (``setups.csv``); any subset of channels.
    thickness : float
        Wall thickness b [mm].
    weights : array_like, shape (nch,) or (N, nch), optional
        0/1 (or any value, > 0 meaning used) to exclude channels.
    solve_v : bool
        False fixes v = 0 (channel along x lost) and solves for theta, phi, w.
    x0 : array_like, shape (4,) or (N, 4), optional
        Initial guess (theta, phi, v, w).  Default: the linearised solution
        about the vertical wall, the generalisation of Eq. 8.
    tol : float
        Convergence when the step in theta and phi [rad] and in v, w divided
        by the largest transducer lever arm [mm/mm] is below ``tol``.
    max_iter : int
        Most evaluations of the model with its Jacobian (Gauss-Newton
        iterations and step halvings).

    Returns
    -------
    dict of ndarray, each shape (N,)
        ``theta``, ``phi`` [rad], ``v``, ``w`` [mm] (NaN where unsolvable:
        fewer good channels than unknowns or a singular geometry);
        ``residual_rms`` [mm], root mean square of the fit residual over the
        good channels; ``n_channels`` used; ``converged`` (bool).
    """
    X, F = _geometry(wall_xyz, frame_xyz)
    E = np.asarray(elongation, float)
    if E.ndim == 1:
        E = E[None, :]
    N, nch = E.shape
    if nch != X.shape[0]:
        raise ValueError(f"elongation has {nch} channels, geometry {X.shape[0]}")
    b = float(thickness)
    W = _weights(E, weights)
    Ez = np.where(W > 0, E, 0.0)
    nused = W.sum(axis=1).astype(int)
    free = np.array([0, 1, 2, 3]) if solve_v else np.array([0, 1, 3])
    target = np.ascontiguousarray(Ez + rest_length(X, F))
    lever = float(np.max(np.abs(X))) or 1.0
    scale = np.array([1.0, 1.0, lever, lever])[free]

    q = np.zeros((N, 4))
    if x0 is None:
        # Linearised about the vertical wall with the pivot at mid-thickness
        # (the kink at theta = 0 only affects the z component).
        z1 = np.zeros(1)
        _, J_rest = _pose(z1, z1, z1, z1, X, F, 0.0, True)
        assert J_rest is not None  # asked for
        kernels.linear_start(J_rest, free, -Ez, W, q)
        # Keep only theta: the other degrees of freedom are small, and a
        # transducer along x reads the second-order transverse motion of
        # a tilted wall, which the linearisation would take for sliding v.
        q[:, 1:] = np.where(np.isfinite(q[:, :1]), 0.0, np.nan)
    else:
        q[:] = np.broadcast_to(np.asarray(x0, float), (N, 4))
        if not solve_v:
            q[:, 2] = 0.0

    ok = (nused >= free.size) & np.all(np.isfinite(q), axis=1)
    q[~ok] = np.nan
    converged = np.zeros(N, bool)
    # Gauss-Newton with lazy backtracking, at each time step (a compiled loop): a step is checked
    # when its end point is evaluated (with the Jacobian, needed anyway for the next step); if the
    # residual grew, the step is halved and retried.
    kernels.gauss_newton(q, ok, W, target, X, F, b, free, scale, float(tol), int(max_iter), converged)

    rms = kernels.residual_rms(q, W, target, X, F, b, nused)
    return {
        "theta": q[:, 0],
        "phi": q[:, 1],
        "v": q[:, 2],
        "w": q[:, 3],
        "residual_rms": rms,
        "n_channels": nused,
        "converged": converged,
    }


def theta_simplified(elongation_ch: ArrayLike, height_ch: ArrayLike) -> np.ndarray:
    """Rocking rotation from one horizontal transducer, Eq. 8 [rad].

    theta ~= arctan(Delta l_i / h_i), h_i the height of the transducer above
    the rocking hinge.  Pass a negative ``h_i`` for a transducer that
    shortens when the wall tips towards +y (frame on the +y side).
    """
    return np.arctan(np.asarray(elongation_ch, float) / np.asarray(height_ch, float))


def simplified_channel(
    wall_xyz: ArrayLike, frame_xyz: ArrayLike, channels: Iterable[int] | None = None
) -> tuple[int, float]:
    """Channel and signed height to use in Eq. 8.

    Among the transducers (optionally restricted to ``channels``) lying
    mostly along y, the highest one; its height is signed so that
    ``theta_simplified`` is positive when the wall tips towards +y.

    Returns
    -------
    (int, float)
        Channel index and signed height h_i [mm]; (-1, nan) if none fits.
    """
    X, F = _geometry(wall_xyz, frame_xyz)
    d = X - F
    along_y = np.abs(d[:, 1]) > 2.0 * np.hypot(d[:, 0], d[:, 2])
    if channels is not None:
        keep = np.zeros(len(X), bool)
        keep[list(channels)] = True
        along_y &= keep
    if not along_y.any():
        return -1, float("nan")
    idx = np.flatnonzero(along_y)
    i = int(idx[np.argmax(X[idx, 2])])
    return i, float(X[i, 2] * np.sign(d[i, 1]))


def normalised_peaks(
    theta: ArrayLike, phi: ArrayLike, v: ArrayLike, w: ArrayLike, alpha: float, thickness: float
) -> dict[str, float]:
    """Normalised maximum absolute values of the four degrees of freedom (Fig. 9b).

    max|theta| / alpha, max|phi| / alpha, max|v| / b, max|w| / b: rotations
    against the slenderness (or alpha_ind) and sliding against the thickness.
    NaN samples are ignored.

    Returns
    -------
    dict of float
    """

    def peak(a: ArrayLike) -> float:
        a = np.abs(np.asarray(a, float))
        return float(np.nanmax(a)) if np.isfinite(a).any() else float("nan")

    return {"theta": peak(theta) / alpha, "phi": peak(phi) / alpha, "v": peak(v) / thickness, "w": peak(w) / thickness}


def wall_motion_dataset(
    time: ArrayLike,
    elongation: ArrayLike,
    wall_xyz: ArrayLike,
    frame_xyz: ArrayLike,
    thickness: float,
    alpha: float | None = None,
    channels: Iterable[int] | None = None,
    weights: ArrayLike | None = None,
    solve_v: bool = True,
) -> xr.Dataset:
    """Per-test kinematics as an ``xarray.Dataset`` on ``time``.

    Variables ``theta``, ``phi`` [rad], ``v``, ``w`` [mm], ``residual_rms``
    [mm], ``n_channels``, ``converged`` from :func:`solve_wall_motion`, and
    ``theta_eq8`` from Eq. 8 on the highest transducer along y; attributes
    ``theta_eq8_max_abs_diff`` (Fig. 9a) and, when ``alpha`` is given, the
    normalised peaks ``peak_theta``, ``peak_phi``, ``peak_v``, ``peak_w``
    (Fig. 9b).

    Parameters
    ----------
    time : array_like, shape (N,)
        Sample times [s].
    elongation : array_like, shape (N, nch)
        Readings [mm] (NaN = lost).
    wall_xyz, frame_xyz, thickness, weights, solve_v
        As in :func:`solve_wall_motion`.
    alpha : float, optional
        Angle the rotations are normalised by [rad] (alpha or alpha_ind).
    channels : sequence of int, optional
        Channels used (the others get weight 0); default all.
    """
    import xarray as xr

    data, attrs = wall_motion_variables(
        time, elongation, wall_xyz, frame_xyz, thickness, alpha, channels, weights, solve_v
    )
    return xr.Dataset(data, attrs=attrs)


def wall_motion_variables(
    time: ArrayLike,
    elongation: ArrayLike,
    wall_xyz: ArrayLike,
    frame_xyz: ArrayLike,
    thickness: float,
    alpha: float | None = None,
    channels: Iterable[int] | None = None,
    weights: ArrayLike | None = None,
    solve_v: bool = True,
) -> tuple[dict[str, tuple[str, np.ndarray, dict[str, Any]]], dict[str, float | int]]:
    """The variables and attributes of :func:`wall_motion_dataset`, not yet a dataset.

    For a caller that adds variables of its own (:mod:`rocklab.lab.reduction`): one
    ``xarray.Dataset`` of them all, not one merged into another.

    Returns
    -------
    (dict, dict)
        name -> (dimension, values, attributes), and the dataset's attributes.
    """
    E = np.asarray(elongation, float)
    W = np.ones(E.shape[1]) if weights is None else np.asarray(weights, float)
    if channels is not None:
        sel = np.zeros(E.shape[1])
        sel[list(channels)] = 1.0
        W = W * sel
    sol = solve_wall_motion(E, wall_xyz, frame_xyz, thickness, weights=W, solve_v=solve_v)
    units = {"theta": "rad", "phi": "rad", "v": "mm", "w": "mm", "residual_rms": "mm"}
    # one Dataset of all the variables: each added one by one is a merge
    data: dict[str, tuple[str, np.ndarray, dict[str, Any]]] = {
        k: ("time", np.asarray(a), {"units": units[k]} if k in units else {}) for k, a in sol.items()
    }
    data["time"] = ("time", np.asarray(time, float), {"units": "s"})
    attrs: dict[str, float | int] = {}
    used = np.flatnonzero(W > 0) if W.ndim == 1 else None
    ch, h = simplified_channel(wall_xyz, frame_xyz, used)
    if ch >= 0:
        t8 = theta_simplified(E[:, ch], h)
        data["theta_eq8"] = ("time", t8, {"units": "rad", "channel": ch, "height_mm": h})
        attrs["theta_eq8_max_abs_diff"] = (
            float(np.nanmax(np.abs(t8 - sol["theta"]))) if np.isfinite(t8 - sol["theta"]).any() else float("nan")
        )
    if alpha is not None:
        for k, val in normalised_peaks(sol["theta"], sol["phi"], sol["v"], sol["w"], alpha, thickness).items():
            attrs[f"peak_{k}"] = val
    attrs["solve_v"] = int(bool(solve_v))
    return data, attrs
