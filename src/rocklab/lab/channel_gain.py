"""A transducer whose gain disagrees with the rigid body: found from the fit's redundancy.

Instrument errors are not physics (issue 42, item 1).  The wall moves as a
rigid body with four degrees of freedom q = (theta, phi, v, w); N healthy
channels measure it, so N - 4 directions of the readings are redundant: a
reading vector y(t) of a rigid motion lies (to first order) in the range of
the fit's Jacobian J(t) (N x 4), and its component along the complement
P_perp(t) = I - J (J^T J)^-1 J^T is noise.

A gain g on channel j reads y_j = g x_j, i.e. an error e_j(t) = (1 - 1/g) y_j(t)
along the unit vector of channel j, and the least-squares fit leaves the
residual

    r(t) = P_perp(t) e(t) = beta_j y_j(t) P_perp(t) u_j,   beta_j = 1 - 1/g.

So the residual's time structure follows channel j's own reading.  Regressing
r(t) on a_j(t) = y_j(t) P_perp(t) u_j (a one-parameter least squares per
candidate channel j, all time steps at once) gives

    beta_j = sum_t y_j(t) r_j(t) / sum_t y_j(t)^2 P_perp,jj(t)

(P_perp r = r at the least-squares solution, P_perp symmetric and idempotent),
the gain g_j = 1 / (1 - beta_j) and the share of the residual's sum of squares
it explains.  This is the linearisation of refitting the rigid body with a
free gain on channel j (a five-parameter solve), exact to first order in
g - 1.

What can be told apart.  The residual alone identifies the channel only
where the candidates' regressors are not collinear over the test.  In the
lab's usual layout (``docs/raw-format.md``) channels 0-3 are horizontal along
y at two heights on the two lateral faces and channel 4 along x: the one
redundant direction is n = (1, -1, -1, 1, 0) / 2 (the four y-channels read
w + z theta + x phi to first order), and channel 4 carries none (its gain is
absorbed by the sliding v: never detectable).  Channels 0-3 all read almost
the same history z_j theta(t), so a 2 % gain on channel 0 is explained as
well (shares of 0.9998 each on a virtual test) by +2 % on channel 2 or by
-/+0.8 % (0.35 h / 0.85 h) on channels 1 and 3: the residual *detects* the
disagreement but does not say *which* channel.  What tells them apart is the
motion each correction leaves: every candidate's correction makes the
channels consistent, but a wrong one does so by moving the hinge, which the
rigid body shows as a sliding w that follows the rotation (w ~ -1.4 % of the
top displacement for the wrong low channel).  A wall rocking on its base
edge does not slide in step with theta (it slides, if at all, at impacts),
so the channel named is the one whose correction leaves the least sliding in
step with theta, step to step (:func:`sliding_slope`: a sliding that grows over
the test, a wall walking on its base, is not taken for it), *identifiable* when the runner-up
leaves :data:`IDENTIFY_RATIO` times more and at least :data:`SLOPE_FLOOR`.
Where the readings are not collinear (two redundant directions and more: the
one-sided layout's channel 5 at mid-height and mid-length) the residual
tells the channel itself, the candidate that explains it leaving
:data:`IDENTIFY_RATIO` times less unexplained than any other; the sliding
is the tie-breaker of the collinear case only.  That rests on an assumption:
a wall whose hinge is not at its base edge (rocking on a joint above it)
would make the choice unreliable, and
``identifiable`` False then keeps the readings as recorded (no correction
on a guess; the QC row says ``unidentified``).

Offsets.  The lab zeroes every transducer with the wall vertical and at rest
before it is tilted (``docs/raw-format.md``), so an offset is removed by the
protocol and is not estimated here; a residual constant would be read by
this regression as part of a gain only through the hold phase.

Intervals.  The residual is not white (mains hum, ringing after impacts,
model error), so the interval of beta_j is the ratio estimator's over
:data:`N_BLOCKS` contiguous time blocks of the test (a batch-means interval,
Student t with K - 1 degrees of freedom): the unit within one test.  A
transducer's calibration varies with the setup (it is mounted and zeroed per
setup), so :func:`pool_setup` pools the tests sharing a setup with the tests
as units (t interval over tests; fewer than :data:`MIN_TESTS_SETUP` tests
give no interval, said so).

Decision.  A channel disagrees when its gain interval excludes
[1 - :data:`MARGIN`, 1 + :data:`MARGIN`] (a practical margin of 0.5 %: below it a
gain error moves theta by less than the lab's other systematic errors).

Lengths in mm, angles in rad, gains dimensionless.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike

from rocklab._imports import lazy_module
from rocklab.lab import kinematics, kinematics_kernels

stats = lazy_module("scipy.stats")

#: Practical margin on a gain [-]: a channel is named when its interval excludes 1 -+ MARGIN.
MARGIN = 0.005
#: Contiguous time blocks of a test, the units of its gain interval.
N_BLOCKS = 10
#: Least share of a channel's readings in the redundant directions (mean of 1 - leverage) for it to be a candidate:
#: 1/4 for each of channels 0-3 of the usual layout, ~0 for channel 4 (along x).
MIN_SHARE = 0.01
#: Confidence level of the intervals.
LEVEL = 0.95
#: The named channel's correction leaves at least this many times less sliding-with-rotation than the runner-up's.
IDENTIFY_RATIO = 3.0
#: Sliding per top displacement [-] below which two candidates' corrections are not told apart.
SLOPE_FLOOR = 1e-3
#: Fewest tests of a setup for a pooled interval (tests as units).
MIN_TESTS_SETUP = 3


@dataclass(frozen=True)
class ChannelGain:
    """The gain of one channel against the rigid-body fit of one test.

    Attributes
    ----------
    channel : int
        Channel number (``setups.csv``).
    gain, low, high : float
        Estimate and interval at :data:`LEVEL` [-] (1: agrees with the rigid body).
    explained : float
        Share of the redundant residual's sum of squares this gain explains [-].
    sliding_slope : float
        The sliding w per top displacement of the rigid body once this channel is
        corrected (:func:`sliding_slope`) [-]; NaN where not computed (no channel disagrees,
        or the residual alone told the channel).
    """

    channel: int
    gain: float
    low: float
    high: float
    explained: float
    sliding_slope: float = float("nan")

    @property
    def disagrees(self) -> bool:
        """The interval excludes 1 -+ :data:`MARGIN`."""
        return outside_margin(self.low, self.high)


def outside_margin(low: float, high: float) -> bool:
    """Whether a gain's interval [low, high] excludes 1 -+ :data:`MARGIN`: the instrument disagrees."""
    return bool(low > 1.0 + MARGIN or high < 1.0 - MARGIN)


@dataclass(frozen=True)
class GainCheck:
    """The channels' gains of one test and the verdict.

    Attributes
    ----------
    gains : list of ChannelGain
        One per candidate channel (those with a share in a redundant direction).
    redundancy : int
        Redundant directions: healthy channels minus solved degrees of freedom.
    n_samples : int
        Time steps used.
    channel : int
        The channel named (-1: none disagrees).
    identifiable : bool
        The named channel explains the residual clearly better than any other
        (:data:`IDENTIFY_RATIO`); False: a disagreement was found but which
        channel is not told by the test's motion.
    """

    gains: list[ChannelGain] = field(default_factory=list)
    redundancy: int = 0
    n_samples: int = 0
    channel: int = -1
    identifiable: bool = False

    @property
    def named(self) -> ChannelGain | None:
        """The :class:`ChannelGain` of the channel named (None when none)."""
        return next((g for g in self.gains if g.channel == self.channel), None)


def block_starts(n: int, k: int) -> np.ndarray:
    """Start indices of ``k`` contiguous blocks of ``n`` samples (fewer if ``n < k``)."""
    return np.unique(np.linspace(0, n, min(k, n) + 1).astype(int)[:-1])


def ratio_interval(num: np.ndarray, den: np.ndarray, level: float = LEVEL) -> tuple[np.ndarray, np.ndarray]:
    """Ratio estimate sum(num) / sum(den) and its half-width over blocks (rows), per column.

    Parameters
    ----------
    num, den : ndarray (K, c)
        Per-block sums of the regression's cross and square terms.
    level : float
        Confidence level.

    Returns
    -------
    (ndarray (c,), ndarray (c,))
        Estimate and half-width of its Student-t interval with K - 1 degrees of freedom.
    """
    k = num.shape[0]
    with np.errstate(invalid="ignore", divide="ignore"):
        beta = num.sum(axis=0) / den.sum(axis=0)
        u = num - beta * den
        se = np.sqrt(k / max(k - 1, 1) * (u * u).sum(axis=0)) / den.sum(axis=0)
    half = t_quantile(0.5 + level / 2, max(k - 1, 1)) * se if k > 1 else np.full_like(beta, np.inf)
    return beta, half


@functools.cache
def t_quantile(q: float, dof: int) -> float:
    """Student's t quantile ``q`` with ``dof`` degrees of freedom (``scipy.stats.t.ppf``), kept:
    every test asks for the same few, and scipy's call costs as much as a test's interval."""
    return float(stats.t.ppf(q, dof))


def channel_gains(
    elongation: ArrayLike,
    wall_xyz: ArrayLike,
    frame_xyz: ArrayLike,
    thickness: float,
    channels: Sequence[int],
    weights: ArrayLike | None = None,
    solve_v: bool = True,
    n_blocks: int = N_BLOCKS,
    level: float = LEVEL,
) -> GainCheck:
    """Each healthy channel's gain against the rigid-body fit of one test.

    Parameters
    ----------
    elongation : array_like (N, nch)
        Readings [mm] (NaN: lost sample).
    wall_xyz, frame_xyz : array_like (nch, 3)
        Transducer end points [mm] (``setups.csv``).
    thickness : float
        Wall thickness b [mm].
    channels : sequence of int
        Channel number of each column.
    weights : array_like (nch,), optional
        > 0 for the channels to check (the healthy ones, backups included); default all.
    solve_v : bool
        As in :func:`rocklab.lab.kinematics.solve_wall_motion`.
    n_blocks : int
        Time blocks of the interval.
    level : float
        Confidence level.

    Returns
    -------
    GainCheck
        No candidates (``redundancy`` <= 0) when the healthy channels only just
        determine the motion.
    """
    E = np.asarray(elongation, float)
    X = np.asarray(wall_xyz, float)
    F = np.asarray(frame_xyz, float)
    use = np.ones(E.shape[1], bool) if weights is None else np.asarray(weights, float) > 0
    free = [0, 1, 2, 3] if solve_v else [0, 1, 3]
    redundancy = int(use.sum()) - len(free)
    if redundancy <= 0:
        return GainCheck(redundancy=max(redundancy, 0))
    Eu, Xu, Fu = E[:, use], X[use], F[use]
    sol = kinematics.solve_wall_motion(Eu, Xu, Fu, thickness, solve_v=solve_v)
    q = np.column_stack([sol[k] for k in kinematics.DOF])
    ok = np.all(np.isfinite(Eu), axis=1) & np.all(np.isfinite(q), axis=1)
    n = int(ok.sum())
    if n < 2 * n_blocks:
        return GainCheck(redundancy=redundancy, n_samples=n)
    q, y = q[ok], Eu[ok]
    th, ph, v, w = q.T
    rigid, jacobian = kinematics.elongation_and_jacobian(th, ph, v, w, Xu, Fu, thickness)
    r = y - rigid  # reading minus rigid body
    J = jacobian[:, :, free]
    H = leverage(J)
    perp = np.clip(1.0 - H, 0.0, 1.0)
    starts = block_starts(n, n_blocks)
    num = np.add.reduceat(y * r, starts, axis=0)
    den = np.add.reduceat(y * y * perp, starts, axis=0)
    beta, half = ratio_interval(num, den, level)
    with np.errstate(invalid="ignore", divide="ignore"):
        explained = beta**2 * den.sum(axis=0) / float(np.sum(r * r))
    # g = 1 / (1 - beta), monotone: the interval maps end to end
    # a channel with (almost) no share in a redundant direction has its gain absorbed by the fit
    candidates = np.flatnonzero(den.sum(axis=0) > MIN_SHARE * np.sum(y * y, axis=0))
    col = np.asarray(channels)[use]
    gains = [
        ChannelGain(
            int(col[j]),
            float(1.0 / (1.0 - beta[j])),
            float(1.0 / (1.0 - (beta[j] - half[j]))),
            float(1.0 / (1.0 - (beta[j] + half[j]))),
            float(explained[j]),
        )
        for j in candidates
    ]
    if not any(g.disagrees for g in gains):
        return GainCheck(gains, redundancy, n)
    # Where the candidates' readings are not collinear (two redundant directions and more, as in the
    # one-sided layout) the residual itself tells the channel: one explains it, the others leave a share.
    by_share = sorted(gains, key=lambda g: -g.explained)
    if len(by_share) > 1 and (1.0 - by_share[1].explained) >= IDENTIFY_RATIO * max(1.0 - by_share[0].explained, 0.0):
        best = by_share[0]
        return GainCheck(gains, redundancy, n, best.channel if best.disagrees else -1, best.disagrees)
    # Which channel: each disagreeing candidate's correction gives a consistent rigid body, but only the
    # right one leaves no sliding that follows the rotation (a wall on its edge does not slide in step with
    # theta; the wrong channel's correction moves the hinge and shows as w ~ theta).
    # Every candidate is tried, not only those that disagree: an error on a high channel is explained by a
    # larger one on a low channel, which may pass the margin while the high channel's own does not.
    gains = [
        replace(g, sliding_slope=sliding_slope(y, Xu, Fu, thickness, int(j), g.gain, solve_v))
        for g, j in zip(gains, candidates)
    ]
    ranked = sorted(gains, key=lambda g: abs(g.sliding_slope))
    best = ranked[0]
    if not best.disagrees:  # the channel whose correction is consistent is within the margin
        return GainCheck(gains, redundancy, n)
    runner = abs(ranked[1].sliding_slope) if len(ranked) > 1 else np.inf
    identifiable = runner >= IDENTIFY_RATIO * abs(best.sliding_slope) and runner > SLOPE_FLOOR
    return GainCheck(gains, redundancy, n, best.channel, bool(identifiable))


def leverage(J: np.ndarray) -> np.ndarray:
    """The leverage of each channel at each time step: the diagonal of J (J^T J)^+ J^T.

    Parameters
    ----------
    J : ndarray (N, nch, k)
        The fit's Jacobian at each step.

    Returns
    -------
    ndarray (N, nch)
        In [0, 1] to rounding; the leverages of a step sum to the rank of its J.

    A step whose J has full column rank (J^T J positive definite: the usual
    case) is solved by a Cholesky factorisation of J^T J scaled to a unit
    diagonal, step by step (a compiled loop); the others, a degenerate
    geometry at some step, by the pseudo-inverse, which gives their leverage
    on the range of J rather than an exception.  The scaling makes it the
    more accurate of the two: on the campaign's tests (J^T J of condition
    number 1e7) 3e-15 from a QR factorisation of J, against 7e-12 for the
    pseudo-inverse of J^T J, which a gain reads at 1e-11 of itself.
    """
    J = np.require(J, float, ("C", "W"))  # as the compiled loop takes it
    H = np.empty(J.shape[:2])
    full_rank = kinematics_kernels.cholesky_leverage(J, H)
    if not full_rank.all():
        Js = J[~full_rank]
        H[~full_rank] = np.einsum("nck,nkl,ncl->nc", Js, np.linalg.pinv(np.einsum("nck,ncl->nkl", Js, Js)), Js)
    return H


def sliding_slope(
    readings: np.ndarray,
    wall_xyz: np.ndarray,
    frame_xyz: np.ndarray,
    thickness: float,
    column: int,
    gain: float,
    solve_v: bool = True,
) -> float:
    """Sliding w per top displacement of the rigid body fitted once a column's gain is corrected [-].

    Parameters
    ----------
    readings : ndarray (N, nch)
        Readings [mm], every sample finite.
    wall_xyz, frame_xyz : ndarray (nch, 3)
        Transducer end points [mm].
    thickness : float
        Wall thickness b [mm].
    column : int
        Column whose readings are divided by ``gain``.
    gain : float
        Its gain [-].
    solve_v : bool
        As in :func:`rocklab.lab.kinematics.solve_wall_motion`.

    Returns
    -------
    float
        Least-squares slope of w's step-to-step change [mm] on that of z_max theta [mm], z_max the
        highest transducer point: 0 for a wall that does not slide in step with its rotation.
    """
    y = readings.copy()
    y[:, column] /= gain
    sol = kinematics.solve_wall_motion(y, wall_xyz, frame_xyz, thickness, solve_v=solve_v)
    # step to step: a sliding that grows over the test (the wall walking on its base, a residual
    # offset) or steps at impacts does not follow theta's oscillation; a moved hinge does, at every step
    dtop = np.diff(sol["theta"]) * float(np.max(wall_xyz[:, 2]))
    dw = np.diff(sol["w"])
    ok = np.isfinite(dtop) & np.isfinite(dw)
    return float(np.sum(dtop[ok] * dw[ok]) / np.sum(dtop[ok] ** 2))


#: Columns of ``qc.csv`` of a test's gain check (:func:`qc_values`).
QC_COLUMNS = ("gain_channel", "gain_estimate", "gain_low", "gain_high", "gain_action", "channel_gains")
#: Their values where no check was made (another instrument, too few channels).
NO_VALUES: dict[str, str | float] = {
    "gain_channel": "",
    "gain_estimate": np.nan,
    "gain_low": np.nan,
    "gain_high": np.nan,
    "gain_action": "",
    "channel_gains": "",
}
#: Columns of ``qc.csv`` pooled over the tests of a setup (:func:`pool_setups`).
SETUP_COLUMNS = ("gain_setup_channel", "gain_setup_estimate", "gain_setup_low", "gain_setup_high", "gain_setup_tests")


def qc_values(check: GainCheck) -> dict[str, str | float]:
    """The :data:`QC_COLUMNS` of a test's check.

    ``gain_action``: ``corrected`` (the named channel divided by its gain before the
    motion was solved), ``unidentified`` (a disagreement, which channel not told:
    readings kept as recorded) or empty.  ``channel_gains``: every candidate's
    estimate, ``ch<n>:<gain>`` separated by spaces (what :func:`pool_setups` pools).
    """
    out: dict[str, str | float] = dict(NO_VALUES)
    out["channel_gains"] = " ".join(f"ch{g.channel}:{g.gain:.5f}" for g in check.gains)
    g = check.named
    if g is not None:
        out.update(
            gain_channel=f"ch{g.channel}",
            gain_estimate=g.gain,
            gain_low=g.low,
            gain_high=g.high,
            gain_action="corrected" if check.identifiable else "unidentified",
        )
    return out


def parse_gains(text: str) -> dict[str, float]:
    """``{'ch<n>': gain}`` of a ``channel_gains`` entry of ``qc.csv`` (:func:`qc_values`)."""
    pairs = (item.split(":") for item in str(text).split() if ":" in item)
    return {ch: float(v) for ch, v in pairs}


def pool_tests(estimates: ArrayLike, level: float = LEVEL) -> tuple[float, float, float, int]:
    """Mean gain over tests and its interval, the tests as units [-].

    Parameters
    ----------
    estimates : array_like
        One gain per test (NaN: none).
    level : float
        Confidence level.

    Returns
    -------
    (float, float, float, int)
        Mean, low, high (Student t over tests; NaN with fewer than
        :data:`MIN_TESTS_SETUP` tests: too few units for an interval) and the tests.
    """
    g = np.asarray(estimates, float)
    g = g[np.isfinite(g)]
    n = int(g.size)
    if n == 0:
        return np.nan, np.nan, np.nan, 0
    mean = float(g.mean())
    if n < MIN_TESTS_SETUP:
        return mean, np.nan, np.nan, n
    half = float(stats.t.ppf(0.5 + level / 2, n - 1) * g.std(ddof=1) / np.sqrt(n))
    return mean, mean - half, mean + half, n


def pool_setups(
    setups: Sequence[str], named: Sequence[str], actions: Sequence[str], channel_gains: Sequence[str]
) -> dict[str, dict[str, str | float | int]]:
    """The :data:`SETUP_COLUMNS` of every setup: its tests' gains pooled.

    A transducer is calibrated and zeroed per setup, so its gain is a property of
    the setup and the tests sharing it are its units.  The setup's channel is the
    one its tests identify most often (``gain_action`` ``corrected``); its gain is
    pooled over every test of the setup that has an estimate of it (those where it
    was within the margin too, so that the pooled value is not selected on its
    own disagreement).

    Parameters
    ----------
    setups, named, actions, channel_gains : sequence of str
        Per test: its setup, ``gain_channel``, ``gain_action`` and ``channel_gains``.

    Returns
    -------
    dict
        setup -> :data:`SETUP_COLUMNS` (channel empty and NaN gains where none is identified).
    """
    out: dict[str, dict[str, str | float | int]] = {}
    for setup in dict.fromkeys(setups):
        idx = [i for i, s in enumerate(setups) if s == setup]
        votes = [named[i] for i in idx if actions[i] == "corrected" and named[i]]
        if not votes:
            n = sum(1 for i in idx if channel_gains[i])
            out[setup] = dict(zip(SETUP_COLUMNS, ("", np.nan, np.nan, np.nan, n)))
            continue
        ch = max(dict.fromkeys(votes), key=votes.count)
        mean, low, high, n = pool_tests([parse_gains(channel_gains[i]).get(ch, np.nan) for i in idx])
        out[setup] = dict(zip(SETUP_COLUMNS, (ch, mean, low, high, n)))
    return out
