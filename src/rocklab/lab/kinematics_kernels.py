"""The compiled loops of the rigid-body fit: the model, its Gauss-Newton solve and the channels' leverage.

:func:`rocklab.lab.kinematics.solve_wall_motion` and
:func:`rocklab.lab.channel_gain.channel_gains` solve the four degrees of
freedom of a wall at each of some thousands of time steps, each a system of a
few unknowns over a few channels: written as array operations over the time
steps (NumPy), every operation of the small systems is a pass over arrays of
all the steps, and the reduction of a test spent most of its time there
(issue 44).  These loops do the same arithmetic step by step.

The results are those of the array forms they replace to the last bit: each
loop does, step by step and channel by channel, the floating-point operations
of the array form in the same order (a sum over the channels as
``numpy.einsum`` takes it: the even and the odd terms apart, then the two
sums; a sum of a few terms from its first on; no fused multiply-add, which
numba emits only under ``fastmath``); ``tests/test_kinematics_kernels.py`` checks
them against the array forms.  The leverage of :func:`cholesky_leverage`
replaces a pseudo-inverse and is not the same arithmetic: it is the more
accurate (module :mod:`rocklab.lab.channel_gain`).

Speed.  No array is sliced inside a loop (a view costs more than the few
operations on it).  The Gauss-Newton iteration runs :data:`LANES` time steps
side by side, each its own iteration (its own steps, halvings and end), so
that the long chains of divisions and square roots of one step's small
Cholesky factorisation overlap with those of the others: twice as fast as
one step after the other.

The loops are in one file: numba's on-disk cache is per file and does not see
a change in a function of another file that a cached loop calls.
"""

from __future__ import annotations

import math

import numba
import numpy as np

#: Time steps the Gauss-Newton iteration runs side by side.
LANES = 32
#: The largest float64, what ``numpy.nan_to_num`` makes of an infinity.
FLOAT_MAX = float(np.finfo(np.float64).max)
#: Least pivot of the Cholesky factorisation of :func:`cholesky_leverage`, on the unit diagonal of the
#: scaled J^T J: below it (a condition number of some 1e12) the step goes to the pseudo-inverse.
PIVOT_FLOOR = 1e-12


@numba.njit(cache=True, error_model="numpy")
def pose_step(
    th: float,
    ph: float,
    v: float,
    w: float,
    X: np.ndarray,
    F: np.ndarray,
    thickness: float,
    L: np.ndarray,
    J: np.ndarray,
    n: int,
) -> None:
    """The lengths |X' - F| of the transducers (wall points ``X``, frame points ``F``, (nch, 3)) at the motion
    (``th``, ``ph``, ``v``, ``w``) into row ``n`` of ``L`` (N, nch), and, unless ``J`` (4, N, nch) has no rows,
    their derivatives with respect to theta, phi, v, w into its row ``n``
    (:func:`rocklab.lab.kinematics.transducer_elongation`)."""
    ey = -0.5 * thickness if th < 0.0 else 0.5 * thickness
    ct, st = math.cos(th), math.sin(th)
    cp, sp = math.cos(ph), math.sin(ph)
    for c in range(X.shape[0]):
        x, z = X[c, 0], X[c, 2]
        dy = X[c, 1] - ey
        py = ct * dy + st * z  # Rx(theta) . (X - E), y component
        pz = -st * dy + ct * z  # ... z component
        qy = py + ey  # + E
        Dx = cp * x - sp * qy + (v - F[c, 0])
        Dy = sp * x + cp * qy + (w - F[c, 1])
        Dz = pz - F[c, 2]
        length = math.sqrt(Dx * Dx + Dy * Dy + Dz * Dz)
        L[n, c] = length
        if J.shape[1]:
            ux, uy, uz = Dx / length, Dy / length, Dz / length
            # d(py)/dtheta = pz and d(pz)/dtheta = -py: a rotation about the edge.
            J[0, n, c] = (cp * uy - sp * ux) * pz - uz * py
            J[1, n, c] = (cp * x - sp * qy) * uy - (sp * x + cp * qy) * ux
            J[2, n, c] = ux
            J[3, n, c] = uy


@numba.njit(cache=True, error_model="numpy")
def pose_steps(
    theta: np.ndarray,
    phi: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    X: np.ndarray,
    F: np.ndarray,
    thickness: float,
    L: np.ndarray,
    J: np.ndarray,
) -> None:
    """:func:`pose_step` of every time step into ``L`` (N, nch) and, unless it has no rows, ``J`` (4, N, nch)."""
    for n in range(theta.size):
        pose_step(theta[n], phi[n], v[n], w[n], X, F, thickness, L, J, n)


@numba.njit(cache=True, error_model="numpy")
def normal_matrix(
    J: np.ndarray, n: int, free: np.ndarray, W: np.ndarray, JW: np.ndarray, A: np.ndarray, Lc: np.ndarray, s: np.ndarray
) -> None:
    """The Jacobi-scaled normal matrix of a Gauss-Newton step and its Cholesky factor: ``J`` (4, N, nch) the
    derivatives at row ``n``, ``free`` the k unknowns solved, ``W`` (nch,) the weights; into ``JW`` (k, nch),
    ``A``, ``Lc`` (k, k) and the scales ``s`` (k,).  A singular system gives NaN."""
    k, nch = free.size, W.size
    for a in range(k):
        for c in range(nch):
            JW[a, c] = J[free[a], n, c] * W[c]
    for a in range(k):
        for b in range(a + 1):
            fb = free[b]
            even, odd = 0.0, 0.0
            for c in range(0, nch - 1, 2):
                even += JW[a, c] * J[fb, n, c]
                odd += JW[a, c + 1] * J[fb, n, c + 1]
            if nch % 2:
                even += JW[a, nch - 1] * J[fb, n, nch - 1]
            A[a, b] = even + odd
    for a in range(k):
        s[a] = 1.0 / math.sqrt(A[a, a]) if A[a, a] > 0 else math.nan
    for a in range(k):
        for b in range(a):
            A[a, b] = A[a, b] * s[a] * s[b]
        A[a, a] = 1.0 + 0.0 * s[a]
    for j in range(k):
        acc = 0.0
        for m in range(j):
            acc += Lc[j, m] * Lc[j, m]
        d = A[j, j] - acc
        Lc[j, j] = math.sqrt(d) if d > 1e-12 * A[j, j] else math.nan
        for i in range(j + 1, k):
            acc = 0.0
            for m in range(j):
                acc += Lc[i, m] * Lc[j, m]
            Lc[i, j] = (A[i, j] - acc) / Lc[j, j]


@numba.njit(cache=True, error_model="numpy")
def normal_solve(
    r: np.ndarray, JW: np.ndarray, Lc: np.ndarray, s: np.ndarray, g: np.ndarray, y: np.ndarray, dq: np.ndarray
) -> None:
    """The Gauss-Newton step minimising sum W (r + J dq)^2 into ``dq`` (k,), from the residuals ``r`` (nch,) and
    :func:`normal_matrix`'s ``JW``, ``Lc`` and ``s``; ``g``, ``y`` (k,) room for the work."""
    k, nch = s.size, r.size
    for a in range(k):
        even, odd = 0.0, 0.0
        for c in range(0, nch - 1, 2):
            even += JW[a, c] * r[c]
            odd += JW[a, c + 1] * r[c + 1]
        if nch % 2:
            even += JW[a, nch - 1] * r[nch - 1]
        g[a] = -(even + odd) * s[a]
    for i in range(k):
        acc = 0.0
        for m in range(i):
            acc += Lc[i, m] * y[m]
        y[i] = (g[i] - acc) / Lc[i, i]
    for i in range(k - 1, -1, -1):
        acc = 0.0
        for m in range(i + 1, k):
            acc += Lc[m, i] * dq[m]
        dq[i] = (y[i] - acc) / Lc[i, i]
    for i in range(k):
        dq[i] = dq[i] * s[i]


@numba.njit(cache=True, error_model="numpy")
def linear_start(J: np.ndarray, free: np.ndarray, R: np.ndarray, W: np.ndarray, q: np.ndarray) -> None:
    """One Gauss-Newton step per time step from the derivatives ``J`` (4, 1, nch) at rest, residuals ``R`` and
    weights ``W`` (N, nch): the unknowns ``free`` of ``q`` (N, 4).  The normal matrix depends on the
    weights only: a step with the weights of the one before takes its factor."""
    k, nch = free.size, J.shape[2]
    JW, A, Lc = np.empty((k, nch)), np.empty((k, k)), np.empty((k, k))
    s, g, y, dq = np.empty(k), np.empty(k), np.empty(k), np.empty(k)
    r, Wn = np.empty(nch), np.empty(nch)
    for n in range(R.shape[0]):
        same = n > 0
        for c in range(nch):
            r[c] = R[n, c]
            same = same and W[n, c] == Wn[c]
            Wn[c] = W[n, c]
        if not same:
            normal_matrix(J, 0, free, Wn, JW, A, Lc, s)
        normal_solve(r, JW, Lc, s, g, y, dq)
        for a in range(k):
            q[n, free[a]] = dq[a]


@numba.njit(cache=True, error_model="numpy")
def _lanes_residual(
    qa: np.ndarray,
    X: np.ndarray,
    F: np.ndarray,
    thickness: float,
    T: np.ndarray,
    W: np.ndarray,
    J: np.ndarray,
    r: np.ndarray,
    cost: np.ndarray,
    trig: np.ndarray,
) -> None:
    """:func:`pose_step` of each lane's point ``qa`` (4, lanes): derivatives into ``J`` (4, nch, lanes), weighted
    residuals against the target lengths ``T`` (weights ``W``, (nch, lanes)) into ``r`` (nch, lanes), their sum
    of squares into ``cost`` (lanes,); ``trig`` (5, lanes) room for the work."""
    lanes, nch = qa.shape[1], X.shape[0]
    for i in range(lanes):
        th = qa[0, i]
        trig[0, i] = -0.5 * thickness if th < 0.0 else 0.5 * thickness
        trig[1, i], trig[2, i] = math.cos(th), math.sin(th)
        trig[3, i], trig[4, i] = math.cos(qa[1, i]), math.sin(qa[1, i])
    for c in range(nch):
        x, yc, z = X[c, 0], X[c, 1], X[c, 2]
        fx, fy, fz = F[c, 0], F[c, 1], F[c, 2]
        for i in range(lanes):
            ey, ct, st, cp, sp = trig[0, i], trig[1, i], trig[2, i], trig[3, i], trig[4, i]
            dy = yc - ey
            py = ct * dy + st * z
            pz = -st * dy + ct * z
            qy = py + ey
            Dx = cp * x - sp * qy + (qa[2, i] - fx)
            Dy = sp * x + cp * qy + (qa[3, i] - fy)
            Dz = pz - fz
            length = math.sqrt(Dx * Dx + Dy * Dy + Dz * Dz)
            ux, uy, uz = Dx / length, Dy / length, Dz / length
            J[0, c, i] = (cp * uy - sp * ux) * pz - uz * py
            J[1, c, i] = (cp * x - sp * qy) * uy - (sp * x + cp * qy) * ux
            J[2, c, i] = ux
            J[3, c, i] = uy
            r[c, i] = (length - T[c, i]) * W[c, i]
    for i in range(lanes):
        even, odd = 0.0, 0.0
        for c in range(0, nch - 1, 2):
            even += r[c, i] * r[c, i]
            odd += r[c + 1, i] * r[c + 1, i]
        if nch % 2:
            even += r[nch - 1, i] * r[nch - 1, i]
        cost[i] = even + odd


@numba.njit(cache=True, error_model="numpy")
def _lanes_step(
    J: np.ndarray,
    r: np.ndarray,
    W: np.ndarray,
    free: np.ndarray,
    dq: np.ndarray,
    JW: np.ndarray,
    A: np.ndarray,
    Lc: np.ndarray,
    s: np.ndarray,
    g: np.ndarray,
    y: np.ndarray,
) -> None:
    """:func:`normal_matrix` and :func:`normal_solve` of each lane, (.., lanes) arrays: the step into ``dq``
    (k, lanes) from the derivatives ``J`` (4, nch, lanes), residuals ``r`` and weights ``W`` (nch, lanes)."""
    k, nch, lanes = free.size, r.shape[0], r.shape[1]
    for a in range(k):
        fa = free[a]
        for c in range(nch):
            for i in range(lanes):
                JW[a, c, i] = J[fa, c, i] * W[c, i]
    for a in range(k):
        for b in range(a + 1):
            fb = free[b]
            for i in range(lanes):
                even, odd = 0.0, 0.0
                for c in range(0, nch - 1, 2):
                    even += JW[a, c, i] * J[fb, c, i]
                    odd += JW[a, c + 1, i] * J[fb, c + 1, i]
                if nch % 2:
                    even += JW[a, nch - 1, i] * J[fb, nch - 1, i]
                A[a, b, i] = even + odd
    for a in range(k):
        for i in range(lanes):
            s[a, i] = 1.0 / math.sqrt(A[a, a, i]) if A[a, a, i] > 0 else math.nan
    for a in range(k):
        for b in range(a):
            for i in range(lanes):
                A[a, b, i] = A[a, b, i] * s[a, i] * s[b, i]
        for i in range(lanes):
            A[a, a, i] = 1.0 + 0.0 * s[a, i]
    for j in range(k):
        for i in range(lanes):
            acc = 0.0
            for m in range(j):
                acc += Lc[j, m, i] * Lc[j, m, i]
            d = A[j, j, i] - acc
            Lc[j, j, i] = math.sqrt(d) if d > 1e-12 * A[j, j, i] else math.nan
        for jj in range(j + 1, k):
            for i in range(lanes):
                acc = 0.0
                for m in range(j):
                    acc += Lc[jj, m, i] * Lc[j, m, i]
                Lc[jj, j, i] = (A[jj, j, i] - acc) / Lc[j, j, i]
    for a in range(k):
        for i in range(lanes):
            even, odd = 0.0, 0.0
            for c in range(0, nch - 1, 2):
                even += JW[a, c, i] * r[c, i]
                odd += JW[a, c + 1, i] * r[c + 1, i]
            if nch % 2:
                even += JW[a, nch - 1, i] * r[nch - 1, i]
            g[a, i] = -(even + odd) * s[a, i]
    for a in range(k):
        for i in range(lanes):
            acc = 0.0
            for m in range(a):
                acc += Lc[a, m, i] * y[m, i]
            y[a, i] = (g[a, i] - acc) / Lc[a, a, i]
    for a in range(k - 1, -1, -1):
        for i in range(lanes):
            acc = 0.0
            for m in range(a + 1, k):
                acc += Lc[m, a, i] * dq[m, i]
            dq[a, i] = (y[a, i] - acc) / Lc[a, a, i]
    for a in range(k):
        for i in range(lanes):
            dq[a, i] = dq[a, i] * s[a, i]


@numba.njit(cache=True, error_model="numpy")
def gauss_newton(
    q: np.ndarray,
    ok: np.ndarray,
    W: np.ndarray,
    T: np.ndarray,
    X: np.ndarray,
    F: np.ndarray,
    thickness: float,
    free: np.ndarray,
    scale: np.ndarray,
    tol: float,
    max_iter: int,
    converged: np.ndarray,
) -> None:
    """The iteration of :func:`rocklab.lab.kinematics.solve_wall_motion` at every time step ``ok`` from its start
    ``q`` (N, 4), in place: weights ``W`` and target lengths ``T`` (N, nch), the unknowns ``free`` with their
    ``scale`` for the tolerance ``tol``; ``converged`` (N,) set where it converged.

    Gauss-Newton with lazy backtracking: a step is checked when its end point is evaluated (with the
    Jacobian, needed anyway for the next step); if the residual grew, the step is halved and retried.
    :data:`LANES` time steps side by side, each its own iteration; a lane whose step has finished goes
    on computing, unread, until the last of its fellows has.
    """
    k, nch, lanes = free.size, X.shape[0], LANES
    steps = np.flatnonzero(ok)
    row = np.zeros(lanes, np.int64)
    live = np.zeros(lanes, np.bool_)
    q_prev, qa = np.empty((4, lanes)), np.empty((4, lanes))  # last accepted point, point to evaluate
    dq, dq_prev = np.empty((k, lanes)), np.empty((k, lanes))
    t, cost, cost_prev = np.empty(lanes), np.empty(lanes), np.empty(lanes)
    Tl, Wl, r = np.empty((nch, lanes)), np.empty((nch, lanes)), np.empty((nch, lanes))
    J, JW = np.empty((4, nch, lanes)), np.empty((k, nch, lanes))
    A, Lc = np.empty((k, k, lanes)), np.empty((k, k, lanes))
    s, g, y = np.empty((k, lanes)), np.empty((k, lanes)), np.empty((k, lanes))
    trig = np.empty((5, lanes))
    for first in range(0, steps.size, lanes):
        for i in range(lanes):
            live[i] = first + i < steps.size
            n = steps[first + i] if live[i] else steps[first]
            row[i] = n
            for a in range(4):
                q_prev[a, i] = q[n, a]
                qa[a, i] = q[n, a]
            for a in range(k):
                dq_prev[a, i] = 0.0
            t[i], cost_prev[i] = 1.0, np.inf
            for c in range(nch):
                Tl[c, i] = T[n, c]
                Wl[c, i] = W[n, c]
        for _ in range(max_iter):
            any_live = False
            for i in range(lanes):
                any_live = any_live or live[i]
            if not any_live:
                break
            _lanes_residual(qa, X, F, thickness, Tl, Wl, J, r, cost, trig)
            _lanes_step(J, r, Wl, free, dq, JW, A, Lc, s, g, y)
            for i in range(lanes):
                worse = cost[i] > cost_prev[i] * (1 + 1e-12) + 1e-24
                # halved down to a negligible step without lowering the residual: the last accepted
                # point is the minimum to rounding
                stalled, finite, small = worse, True, True
                for a in range(k):
                    stalled = stalled and abs(t[i] * dq_prev[a, i]) / scale[a] < tol
                    finite = finite and np.isfinite(dq[a, i])
                    small = small and abs(dq[a, i]) / scale[a] < tol
                bad = not worse and not finite
                done = not worse and finite and small
                if worse:
                    t[i] *= 0.5
                elif not bad:
                    for a in range(4):
                        q_prev[a, i] = qa[a, i]
                    for a in range(k):
                        dq_prev[a, i] = dq[a, i]
                    cost_prev[i] = cost[i]
                    t[i] = 1.0
                for a in range(4):
                    qa[a, i] = math.nan if bad else q_prev[a, i]
                if not (stalled or bad):
                    for a in range(k):
                        qa[free[a], i] += t[i] * dq_prev[a, i]
                if live[i] and (done or stalled or bad):
                    for a in range(4):
                        q[row[i], a] = qa[a, i]
                    converged[row[i]] = done or stalled
                    live[i] = False
        for i in range(lanes):
            if live[i]:  # out of iterations: best point found
                for a in range(4):
                    q[row[i], a] = q_prev[a, i]


@numba.njit(cache=True, error_model="numpy")
def residual_rms(
    q: np.ndarray, W: np.ndarray, T: np.ndarray, X: np.ndarray, F: np.ndarray, thickness: float, nused: np.ndarray
) -> np.ndarray:
    """Root mean square residual at the solution ``q`` (N, 4) (NaN read as 0, as ``numpy.nan_to_num`` does)
    over the ``nused`` channels of weight ``W`` (N, nch) against the target lengths ``T`` (N, nch); NaN where
    theta is."""
    N, nch = W.shape
    L, J = np.empty((1, nch)), np.empty((4, 0, nch))
    qn = np.empty(4)
    rms = np.empty(N)
    for n in range(N):
        for a in range(4):
            x = q[n, a]
            qn[a] = 0.0 if np.isnan(x) else min(max(x, -FLOAT_MAX), FLOAT_MAX)
        pose_step(qn[0], qn[1], qn[2], qn[3], X, F, thickness, L, J, 0)
        even, odd = 0.0, 0.0
        for c in range(0, nch - 1, 2):
            r0 = (L[0, c] - T[n, c]) * W[n, c]
            r1 = (L[0, c + 1] - T[n, c + 1]) * W[n, c + 1]
            even += r0 * r0
            odd += r1 * r1
        if nch % 2:
            r0 = (L[0, nch - 1] - T[n, nch - 1]) * W[n, nch - 1]
            even += r0 * r0
        rms[n] = math.sqrt((even + odd) / nused[n]) if np.isfinite(q[n, 0]) else math.nan
    return rms


@numba.njit(cache=True, error_model="numpy")
def cholesky_leverage(J: np.ndarray, H: np.ndarray) -> np.ndarray:
    """The leverage of each channel, diag J (J^T J)^-1 J^T, at every time step whose J (N, nch, k) has full
    column rank, into ``H`` (N, nch): by a Cholesky factorisation of J^T J scaled to a unit diagonal,
    H_c = |L^-1 S J_c|^2.  Returns whether each step's had (:data:`PIVOT_FLOOR`); the others are left."""
    N, nch, k = J.shape
    A, Lc = np.empty((k, k)), np.empty((k, k))
    s, z = np.empty(k), np.empty(k)
    full_rank = np.ones(N, np.bool_)
    for n in range(N):
        ok = True
        for a in range(k):
            for b in range(a + 1):
                acc = 0.0
                for c in range(nch):
                    acc += J[n, c, a] * J[n, c, b]
                A[a, b] = acc
            ok = ok and A[a, a] > 0.0
        if ok:
            for a in range(k):
                s[a] = 1.0 / math.sqrt(A[a, a])
            for j in range(k):
                d = 1.0
                for m in range(j):
                    d -= Lc[j, m] * Lc[j, m]
                if not d > PIVOT_FLOOR:
                    ok = False
                    break
                Lc[j, j] = math.sqrt(d)
                for i in range(j + 1, k):
                    acc = A[i, j] * s[i] * s[j]
                    for m in range(j):
                        acc -= Lc[i, m] * Lc[j, m]
                    Lc[i, j] = acc / Lc[j, j]
        if not ok:
            full_rank[n] = False
            continue
        for c in range(nch):
            h = 0.0
            for i in range(k):
                acc = J[n, c, i] * s[i]
                for m in range(i):
                    acc -= Lc[i, m] * z[m]
                z[i] = acc / Lc[i, i]
                h += z[i] * z[i]
            H[n, c] = h
    return full_rank
