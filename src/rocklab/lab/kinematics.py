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
solved by a vectorised Cholesky factorisation.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

if TYPE_CHECKING:
    import xarray as xr

#: Order of the unknowns in ``x0`` and in the Jacobian.
DOF = ("theta", "phi", "v", "w")


def _geometry(wall_xyz: ArrayLike, frame_xyz: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    X = np.atleast_2d(np.asarray(wall_xyz, float))
    F = np.atleast_2d(np.asarray(frame_xyz, float))
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
) -> tuple[np.ndarray, list[np.ndarray] | None]:
    """Lengths |X' - F| per step and channel, shape (N, nch), and (optionally)
    their derivatives with respect to theta, phi, v, w: a list of four
    (N, nch) arrays.  Inputs theta, phi, v, w have shape (N,)."""
    th = theta[:, None]
    ey = np.where(th < 0.0, -0.5 * thickness, 0.5 * thickness)
    x, y, z = X[:, 0], X[:, 1], X[:, 2]
    ct, st = np.cos(th), np.sin(th)
    cp, sp = np.cos(phi)[:, None], np.sin(phi)[:, None]
    dy = y - ey
    py = ct * dy + st * z  # Rx(theta) . (X - E), y component
    pz = -st * dy + ct * z  # ... z component
    qy = py + ey  # + E
    Dx = cp * x - sp * qy + (v[:, None] - F[:, 0])
    Dy = sp * x + cp * qy + (w[:, None] - F[:, 1])
    Dz = pz - F[:, 2]
    L = np.sqrt(Dx * Dx + Dy * Dy + Dz * Dz)
    if not jacobian:
        return L, None
    ux, uy, uz = Dx / L, Dy / L, Dz / L
    # d(py)/dtheta = pz and d(pz)/dtheta = -py: a rotation about the edge.
    J = [(cp * uy - sp * ux) * pz - uz * py, (cp * x - sp * qy) * uy - (sp * x + cp * qy) * ux, ux, uy]
    return L, J


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
    X, F = _geometry(wall_xyz, frame_xyz)
    th, ph, vv, ww = np.broadcast_arrays(*(np.atleast_1d(np.asarray(a, float)) for a in (theta, phi, v, w)))
    _, J = _pose(th.ravel(), ph.ravel(), vv.ravel(), ww.ravel(), X, F, float(thickness), jacobian=True)
    assert J is not None  # asked for
    return np.stack(J, axis=-1)


def _cholesky_solve(A: Sequence[Sequence[Any]], g: Sequence[np.ndarray]) -> np.ndarray:
    """Solve the stacked symmetric positive definite systems A x = g.

    ``A[i][j]`` (i >= j) and ``g[i]`` are (N,) arrays for a small system of
    size k: a Python loop over k, NumPy over N, much faster than per-matrix
    LAPACK calls for millions of 4 x 4 systems.  Singular systems give NaN.
    """
    k = len(g)
    Lc: list[list[Any]] = [[None] * k for _ in range(k)]
    with np.errstate(invalid="ignore", divide="ignore"):
        for j in range(k):
            d = A[j][j] - sum(Lc[j][m] ** 2 for m in range(j))
            Lc[j][j] = np.sqrt(np.where(d > 1e-12 * A[j][j], d, np.nan))
            for i in range(j + 1, k):
                Lc[i][j] = (A[i][j] - sum(Lc[i][m] * Lc[j][m] for m in range(j))) / Lc[j][j]
        y: list[Any] = [None] * k
        for i in range(k):
            y[i] = (g[i] - sum(Lc[i][m] * y[m] for m in range(i))) / Lc[i][i]
        x: list[Any] = [None] * k
        for i in reversed(range(k)):
            x[i] = (y[i] - sum(Lc[m][i] * x[m] for m in range(i + 1, k))) / Lc[i][i]
    return np.column_stack(x)


def _normal_step(J: Sequence[np.ndarray], r: np.ndarray, W: np.ndarray) -> np.ndarray:
    """Gauss-Newton step minimising sum W (r + J dq)^2, Jacobi-scaled.

    J is a list of k (N, nch) derivative arrays, r and W are (N, nch)."""
    k = len(J)
    JW = [Ja * W for Ja in J]
    A: list[list[Any]] = [[np.einsum("nc,nc->n", JW[a], J[b]) if b <= a else None for b in range(k)] for a in range(k)]
    with np.errstate(invalid="ignore", divide="ignore"):
        s = [np.where(A[a][a] > 0, 1.0 / np.sqrt(A[a][a]), np.nan) for a in range(k)]
    As: list[list[Any]] = [[A[a][b] * s[a] * s[b] if b <= a else None for b in range(k)] for a in range(k)]
    for a in range(k):
        As[a][a] = np.ones_like(s[a]) + 0.0 * s[a]
    g = [-np.einsum("nc,nc->n", JW[a], r) * s[a] for a in range(k)]
    return _cholesky_solve(As, g) * np.column_stack(s)


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
    target = Ez + rest_length(X, F)
    lever = float(np.max(np.abs(X))) or 1.0
    scale = np.array([1.0, 1.0, lever, lever])[free]

    q = np.zeros((N, 4))
    if x0 is None:
        # Linearised about the vertical wall with the pivot at mid-thickness
        # (the kink at theta = 0 only affects the z component).
        z1 = np.zeros(1)
        _, J_rest = _pose(z1, z1, z1, z1, X, F, 0.0, True)
        assert J_rest is not None  # asked for
        J0 = [np.broadcast_to(J_rest[a], (N, nch)) for a in free]
        q[:, free] = _normal_step(J0, -Ez, W)
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
    # Gauss-Newton with lazy backtracking: a step is checked when its end
    # point is evaluated (with the Jacobian, needed anyway for the next
    # step); if the residual grew, the step is halved and retried.
    active = np.flatnonzero(ok)
    q_prev = q[active]  # last accepted point
    qa = q_prev.copy()  # point to evaluate
    Wa, Ta = W[active], target[active]
    dq_prev = np.zeros((active.size, free.size))
    t = np.ones(active.size)
    cost_prev = np.full(active.size, np.inf)
    for _ in range(max_iter):
        if active.size == 0:
            break
        L, J = _pose(qa[:, 0], qa[:, 1], qa[:, 2], qa[:, 3], X, F, b, True)
        assert J is not None  # asked for
        r = (L - Ta) * Wa
        cost = np.einsum("nc,nc->n", r, r)
        worse = cost > cost_prev * (1 + 1e-12) + 1e-24
        # Halved down to a negligible step without lowering the residual:
        # the last accepted point is the minimum to rounding.
        stalled = worse & (np.max(np.abs(t[:, None] * dq_prev) / scale, axis=1) < tol)
        dq = _normal_step([J[a] for a in free], r, Wa)
        bad = ~worse & ~np.all(np.isfinite(dq), axis=1)
        acc = ~worse & ~bad
        done = acc & (np.max(np.abs(dq) / scale, axis=1) < tol)
        t[worse] *= 0.5
        q_prev[acc] = qa[acc]
        cost_prev[acc] = cost[acc]
        dq_prev[acc] = dq[acc]
        t[acc] = 1.0
        qa = q_prev.copy()
        qa[:, free] += t[:, None] * dq_prev
        qa[stalled] = q_prev[stalled]
        qa[bad] = np.nan
        fin = done | stalled | bad
        if fin.any():
            q[active[fin]] = qa[fin]
            converged[active[done | stalled]] = True
            keep = ~fin
            active, qa, q_prev, dq_prev, t, cost_prev, Wa, Ta = (
                a[keep] for a in (active, qa, q_prev, dq_prev, t, cost_prev, Wa, Ta)
            )
    q[active] = q_prev  # out of iterations: best point found

    L, _ = _pose(
        np.nan_to_num(q[:, 0]), np.nan_to_num(q[:, 1]), np.nan_to_num(q[:, 2]), np.nan_to_num(q[:, 3]), X, F, b, False
    )
    r = (L - target) * W
    with np.errstate(invalid="ignore", divide="ignore"):
        rms = np.sqrt(np.einsum("nc,nc->n", r, r) / nused)
    rms[~np.isfinite(q[:, 0])] = np.nan
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
    return xr.Dataset(data, attrs=attrs)
