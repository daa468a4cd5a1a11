"""The compiled loops of the rigid-body fit (rocklab.lab.kinematics_kernels) against the array forms they
replace: the same motion to rounding (on the machine they were written on, to the last bit; NumPy's
vectorised sin, cos and sums take other paths on other processors, so the check is the rounding's), and the
leverage of rocklab.lab.channel_gain against the
pseudo-inverse it replaces."""

from collections.abc import Sequence
from typing import Any

import numpy as np
import pytest
from test_kinematics import FRAME, WALL, B, rocking_motion

from rocklab.kernels import compile_kernels
from rocklab.lab import channel_gain, kinematics
from rocklab.lab import kinematics_kernels as kernels
from rocklab.lab.kinematics import _pose, _weights, rest_length, solve_wall_motion, transducer_elongation

# The array forms, as rocklab.lab.kinematics had them before the compiled loops (issue 44).


def array_pose(
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


def array_cholesky_solve(A: Sequence[Sequence[Any]], g: Sequence[np.ndarray]) -> np.ndarray:
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


def array_normal_step(J: Sequence[np.ndarray], r: np.ndarray, W: np.ndarray) -> np.ndarray:
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
    return array_cholesky_solve(As, g) * np.column_stack(s)


def array_solve(
    elongation, wall_xyz, frame_xyz, thickness, weights=None, solve_v=True, x0=None, tol=1e-10, max_iter=30
):
    """solve_wall_motion's array form."""
    X, F = np.atleast_2d(np.asarray(wall_xyz, float)), np.atleast_2d(np.asarray(frame_xyz, float))
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
        _, J_rest = array_pose(z1, z1, z1, z1, X, F, 0.0, True)
        assert J_rest is not None  # asked for
        J0 = [np.broadcast_to(J_rest[a], (N, nch)) for a in free]
        q[:, free] = array_normal_step(J0, -Ez, W)
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
        L, J = array_pose(qa[:, 0], qa[:, 1], qa[:, 2], qa[:, 3], X, F, b, True)
        assert J is not None  # asked for
        r = (L - Ta) * Wa
        cost = np.einsum("nc,nc->n", r, r)
        worse = cost > cost_prev * (1 + 1e-12) + 1e-24
        # Halved down to a negligible step without lowering the residual:
        # the last accepted point is the minimum to rounding.
        stalled = worse & (np.max(np.abs(t[:, None] * dq_prev) / scale, axis=1) < tol)
        dq = array_normal_step([J[a] for a in free], r, Wa)
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

    L, _ = array_pose(
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


def noisy_readings(channels, seed=0, n=4000, lost=0.0):
    """Readings of :func:`test_kinematics.rocking_motion` on ``channels`` with 0.002 mm of noise, a share
    ``lost`` of the samples NaN."""
    rng = np.random.default_rng(seed)
    e = transducer_elongation(*rocking_motion(n), WALL[channels], FRAME[channels], B)
    e = e + rng.normal(0.0, 0.002, e.shape)
    e[rng.random(e.shape) < lost] = np.nan
    return e


#: Relative difference of the compiled loops from the array forms: rounding, where a processor's vector
#: paths for sin, cos and sums differ from the loops' (none on the machine they were written on).
ROUNDING = 1e-12


def assert_same_values(got, want):
    for key in want:
        assert got[key].dtype == want[key].dtype, key
        np.testing.assert_allclose(got[key], want[key], rtol=ROUNDING, atol=0.0, equal_nan=True, err_msg=key)


@pytest.mark.parametrize(
    "channels, kwargs",
    [
        ([0, 1, 3, 4], {}),
        ([0, 1, 2, 3, 4], {}),
        ([0, 1, 2, 3, 4, 5], {}),
        ([0, 1, 2, 3, 4, 5], {"weights": [1, 1, 0, 1, 1, 0]}),
        ([0, 1, 2, 3], {"solve_v": False}),
        ([0, 1, 3, 4], {"x0": [0.01, 0.0, 0.0, 0.0]}),
        ([0, 1, 3, 4], {"max_iter": 3}),
        ([0, 1, 3, 4], {"tol": 1e-14}),
    ],
)
@pytest.mark.parametrize("lost", [0.0, 0.2])
def test_the_compiled_solve_is_the_array_form_to_rounding(channels, kwargs, lost):
    """Every output of every time step: the start, the halvings at the kink, the steps that end short of
    their channels (lost samples) or out of iterations, the residual."""
    e = noisy_readings(channels, seed=len(channels), lost=lost)
    want = array_solve(e, WALL[channels], FRAME[channels], B, **kwargs)
    got = solve_wall_motion(e, WALL[channels], FRAME[channels], B, **kwargs)
    assert_same_values(got, want)
    if lost:
        assert np.isnan(got["theta"]).any() and np.isfinite(got["theta"]).any()


def test_the_compiled_model_is_the_array_form_to_rounding():
    theta, phi, v, w = rocking_motion(999)
    L, J = _pose(theta, phi, v, w, WALL, FRAME, B, True)
    L0, J0 = array_pose(theta, phi, v, w, WALL, FRAME, B, True)
    np.testing.assert_allclose(L, L0, rtol=ROUNDING, atol=0.0)
    for a in range(4):
        np.testing.assert_allclose(J[a], J0[a], rtol=ROUNDING, atol=1e-15 * np.abs(J0[a]).max())
    np.testing.assert_allclose(_pose(theta, phi, v, w, WALL, FRAME, B, False)[0], L0, rtol=ROUNDING, atol=0.0)


def test_a_step_too_few_channels_or_singular_is_nan_as_in_the_array_form():
    e = noisy_readings([0, 1, 3, 4], n=200)
    e[:50, :2] = np.nan  # two channels left: fewer than the unknowns
    X = WALL[[0, 1, 3, 4]].copy()
    got = solve_wall_motion(e, X, FRAME[[0, 1, 3, 4]], B)
    assert_same_values(got, array_solve(e, X, FRAME[[0, 1, 3, 4]], B))
    assert np.isnan(got["theta"][:50]).all() and not got["converged"][:50].any()
    # all the channels at one point: a singular geometry
    Xs, Fs = np.repeat(X[:1], 4, axis=0), np.repeat(FRAME[:1], 4, axis=0)
    got = solve_wall_motion(e[50:], Xs, Fs, B)
    assert_same_values(got, array_solve(e[50:], Xs, Fs, B))


def test_the_leverage_is_the_pseudo_inverses_and_the_more_accurate():
    """Against a QR factorisation of J (exact leverage to rounding): the Cholesky of the scaled J^T J within
    1e-13, the pseudo-inverse of J^T J it replaces within its own rounding (1e-9 at this conditioning)."""
    theta, phi, v, w = rocking_motion(500)
    J = kinematics.elongation_jacobian(theta, phi, v, w, WALL, FRAME, B)
    for free in ([0, 1, 2, 3], [0, 1, 3]):
        Jf = J[:, :, free]
        Q = np.linalg.qr(Jf)[0]
        exact = np.einsum("nck,nck->nc", Q, Q)
        pinv = np.einsum("nck,nkl,ncl->nc", Jf, np.linalg.pinv(np.einsum("nck,ncl->nkl", Jf, Jf)), Jf)
        H = channel_gain.leverage(Jf)
        assert np.max(np.abs(H - exact)) < 1e-13
        assert np.max(np.abs(pinv - exact)) < 1e-9
        assert np.allclose(H.sum(axis=1), len(free), atol=1e-12)


def test_a_degenerate_step_takes_its_leverage_from_the_pseudo_inverse():
    rng = np.random.default_rng(5)
    J = rng.normal(size=(6, 5, 4))
    J[2, :, 3] = 2.0 * J[2, :, 2]  # rank 3
    J[4] = 0.0  # rank 0
    H = channel_gain.leverage(J)
    pinv = np.einsum("nck,nkl,ncl->nc", J, np.linalg.pinv(np.einsum("nck,ncl->nkl", J, J)), J)
    assert np.allclose(H, pinv, atol=1e-12)
    assert H[2].sum() == pytest.approx(3.0) and (H[4] == 0).all()
    full = kernels.cholesky_leverage(J, np.empty((6, 5)))
    assert full.tolist() == [True, True, False, True, False, True]


def test_compile_kernels_covers_the_reductions_calls():
    """What make venv compiles is what a reduction calls: no kernel compiles again in a job."""
    compile_kernels()
    entries = [kernels.pose_steps, kernels.linear_start, kernels.gauss_newton, kernels.residual_rms]
    entries.append(kernels.cholesky_leverage)
    before = [set(f.signatures) for f in entries]
    assert all(before)
    e = noisy_readings([0, 1, 2, 3, 4, 5], n=300, lost=0.05)
    # read-only inputs, as a dataset read back gives them, and lists
    e.flags.writeable = False
    X, F = WALL.copy(), FRAME.copy()
    X.flags.writeable = False
    solve_wall_motion(e, X, F, B, weights=[1, 1, 0, 1, 1, 0])
    solve_wall_motion(e[:, :4], X[:4], F[:4], B, solve_v=False, x0=[0.0, 0.0, 0.0, 0.0])
    channel_gain.channel_gains(e, X, F, B, list(range(6)))
    kinematics.transducer_elongation([0.01, 0.02], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], X.tolist(), F.tolist(), B)
    assert [set(f.signatures) for f in entries] == before
