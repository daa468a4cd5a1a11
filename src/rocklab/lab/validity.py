"""The lab's validity rules for a free-rocking test, applied from the data.

``docs/raw-format.md`` ("What makes a test valid"):

* residual out-of-plumb: the wall top, once the motion has died out, must be
  within 1.5 mm of where it was at rest before the test (the vertical wall,
  where the transducers were zeroed);
* undisturbed initial conditions: a release angular velocity above 10 % of
  the overturning velocity of Eq. 16 is disturbed;
* working instruments: with two of the out-of-plane kinematic channels lost
  the test is rejected; one is replaced by the backup; a lost in-plane
  channel leaves v unsolved (v = 0, flagged).

Channel roles are read from the transducer geometry, never assumed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from rocklab.lab import kinematics

#: Reject reasons, in the order they are reported when several apply.
REASONS = ("unreadable", "instrument_malfunction", "disturbed_initial_conditions", "residual_out_of_plumb")


def channel_roles(setup: pd.DataFrame, thickness_mm: float) -> pd.DataFrame:
    """Role of each transducer from its geometry.

    ``out_of_plane``: horizontal along y on a lateral face (fixes theta, phi,
    w); ``in_plane``: along x (fixes v); ``monitor``: along y on the outer or
    inner face (|y| = b/2), which sees the face's own deformation (channel 5,
    Fig. 20) and is kept out of the rigid-body fit.

    Parameters
    ----------
    setup : DataFrame
        Rows of ``setups.csv`` for one setup.
    thickness_mm : float
        Wall thickness b [mm].
    """
    X = setup[["wall_x_mm", "wall_y_mm", "wall_z_mm"]].to_numpy(float)
    F = setup[["frame_x_mm", "frame_y_mm", "frame_z_mm"]].to_numpy(float)
    d = F - X
    along_y = np.abs(d[:, 1]) >= np.abs(d[:, 0])
    on_face = np.isclose(np.abs(X[:, 1]), thickness_mm / 2, atol=1.0)
    role = np.where(~along_y, "in_plane", np.where(on_face, "monitor", "out_of_plane"))
    return pd.DataFrame({"channel": setup.channel.to_numpy(int), "role": role, "height_mm": X[:, 2]})


@dataclass
class ChannelChoice:
    """Channels used for the kinematics, and what that choice cost."""

    used: list
    solve_v: bool
    lost_out_of_plane: list
    flags: list = field(default_factory=list)
    malfunction: str | None = None


def choose_channels(roles: pd.DataFrame, lost: set, backup=(2,), policy="primary", max_lost=1) -> ChannelChoice:
    """Pick the kinematic channels as the lab does.

    Parameters
    ----------
    roles : DataFrame
        From :func:`channel_roles`.
    lost : set of int
        Channels found dead, stuck, clipped or dropping out.
    backup : sequence of int
        Out-of-plane channels held in reserve.
    policy : {'primary', 'all'}
        ``primary``: the non-backup out-of-plane channels, a backup standing in
        for each lost one; ``all``: every good out-of-plane channel (least
        squares).
    max_lost : int
        Most out-of-plane channels that may be lost before the test is rejected.
    """
    oop = roles.channel[roles.role == "out_of_plane"].tolist()
    inp = roles.channel[roles.role == "in_plane"].tolist()
    lost_oop = [c for c in oop if c in lost]
    flags = []
    primary = [c for c in oop if c not in backup]
    spare = [c for c in oop if c in backup and c not in lost]
    if policy == "all":
        used = [c for c in oop if c not in lost]
    else:
        used = [c for c in primary if c not in lost]
        need = len(primary) - len(used)
        stand_in = spare[:need]
        used += stand_in
        for c in stand_in:
            flags.append(f"backup ch{c} used")
    for c in lost_oop:
        flags.append(f"ch{c} lost")
    malfunction = None
    if len(lost_oop) > max_lost or len(used) < 3:
        malfunction = f"{len(lost_oop)} out-of-plane channel(s) lost ({', '.join(f'ch{c}' for c in lost_oop)})"
    good_inp = [c for c in inp if c not in lost]
    solve_v = bool(good_inp)
    if not solve_v:
        flags.append("in-plane channel lost: v = 0")
    return ChannelChoice(sorted(used + good_inp[:1]), solve_v, lost_oop, flags, malfunction)


def top_displacement(theta, phi, v, w, length_mm, height_mm, thickness_mm):
    """Horizontal displacement along y of the two top corners [mm].

    Read by a virtual transducer, horizontal along y and very long, fixed at
    each top corner: its elongation is the corner's y displacement to better
    than 1e-6 mm for displacements of a few mm.

    Returns
    -------
    ndarray (N, 2)
        y displacement of (x = -L/2, z = h) and (x = +L/2, z = h).
    """
    reach = 1e7
    X = np.array([[-length_mm / 2, 0.0, height_mm], [length_mm / 2, 0.0, height_mm]])
    F = X - np.array([0.0, reach, 0.0])
    return kinematics.transducer_elongation(theta, phi, v, w, X, F, thickness_mm)


def residual_out_of_plumb(top_y, fs, tail_s=1.0):
    """Residual top out-of-plumb after the motion [mm].

    The largest |y displacement| of the top corners, taken as the median over
    the last ``tail_s`` seconds of the record (the wall is at rest there).
    """
    n = max(int(round(tail_s * fs)), 1)
    tail = np.asarray(top_y)[-n:]
    if not np.isfinite(tail).any():
        return float("nan")
    return float(np.nanmax(np.abs(np.nanmedian(tail, axis=0))))


def release_state(t, theta, p):
    """Release instant, rotation and angular velocity of a free-rocking record.

    The wall falls from its held rotation to the first impact under
    theta'' = p^2 (theta - alpha_ind) (Housner's piecewise-linear equation),
    so over the fall theta = alpha_ind + A e^{pt} + B e^{-pt}, linear in
    (alpha_ind, A, B) once p is known from the geometry.  That fit over the
    stretch between 97 % and 50 % of the held rotation ignores noise and the
    screw's creep, and its invariant (theta - alpha_ind)^2 - (theta'/p)^2 =
    4AB gives the velocity with which the wall left its held rotation:
    zero for a wall that fell from rest at its instability point, the kick
    for a disturbed release.

    Parameters
    ----------
    t, theta : ndarray
        Time [s] and rotation [rad].
    p : float
        Frequency parameter [rad/s].

    Returns
    -------
    dict
        ``t_release`` [s], ``theta0`` [rad] (signed, the held rotation),
        ``thetadot0`` [rad/s] (magnitude), ``alpha_fit`` [rad], ``i_release``
        (last sample at the held rotation); NaN where no fall is found.
    """
    nan = {"t_release": np.nan, "theta0": np.nan, "thetadot0": np.nan, "alpha_fit": np.nan, "i_release": -1}
    ok = np.isfinite(theta)
    if ok.sum() < 20:
        return nan
    t, theta = np.asarray(t)[ok], np.asarray(theta)[ok]
    k0 = max(int(0.05 * len(theta)), 1)
    sign = np.sign(np.median(theta[:k0]))
    if sign == 0:
        return nan
    y = sign * theta
    below = np.flatnonzero(y < 0.5 * np.median(y[:k0]))
    if below.size == 0:
        return nan
    i50 = int(below[0])
    fs = 1.0 / np.median(np.diff(t))
    look = max(int(fs), 1)
    y_top = float(np.max(y[max(i50 - look, 0) : i50 + 1]))
    i_top = max(i50 - look, 0) + int(np.argmax(y[max(i50 - look, 0) : i50 + 1]))
    seg = np.arange(i_top, i50 + 1)
    seg = seg[(y[seg] <= 0.97 * y_top) & (y[seg] >= 0.5 * y_top)]
    if seg.size < 5:
        return nan
    tau = t[seg] - t[seg[0]]
    M = np.column_stack([np.ones_like(tau), np.exp(p * tau), np.exp(-p * tau)])
    (a_ind, A, B), *_ = np.linalg.lstsq(M, y[seg], rcond=None)
    held = np.flatnonzero(y[: seg[0] + 1] >= 0.997 * y_top)
    i_rel = int(held[-1]) if held.size else int(seg[0])
    # The held level is the plateau's median, not its noisy maximum, which
    # would read as a release velocity of a few per cent of Eq. 16.
    y_hold = float(np.median(y[max(i_rel - look // 4, 0) : i_rel + 1]))
    v2 = p**2 * ((y_hold - a_ind) ** 2 - 4.0 * A * B)
    # Released from rest the fitted trajectory turns at theta' = 0; released
    # with a kick it crosses the held level going down: u = e^{p tau} solves
    # A u^2 + (alpha_ind - theta_hold) u + B = 0 there.
    if v2 <= 0 and A * B > 0:
        tau_rel = 0.5 * np.log(B / A) / p
    else:
        roots = np.roots([A, a_ind - y_hold, B])
        roots = roots[np.isreal(roots) & (roots.real > 0)].real
        down = roots[p * (A * roots - B / roots) < 0] if roots.size else roots
        tau_rel = np.log(down.max()) / p if down.size else t[i_rel] - t[seg[0]]
    t_rel = float(np.clip(t[seg[0]] + tau_rel, t[0], t[seg[0]]))
    return {
        "t_release": t_rel,
        "theta0": float(sign * y_hold),
        "thetadot0": float(np.sqrt(max(v2, 0.0))),
        "alpha_fit": float(a_ind),
        "i_release": i_rel,
    }


def verdict(choice: ChannelChoice, release_ratio, residual_top_mm, rules) -> tuple[bool, str, str]:
    """Valid flag, reject reason and its explanation by the lab's rules.

    Parameters
    ----------
    choice : ChannelChoice
    release_ratio : float
        Release angular velocity over Eq. 16.
    residual_top_mm : float
        From :func:`residual_out_of_plumb`.
    rules : dict
        ``residual_top_mm``, ``release_velocity_ratio`` (config ``validity``).
    """
    if choice.malfunction:
        return False, "instrument_malfunction", choice.malfunction
    if not np.isfinite(release_ratio):
        return False, "disturbed_initial_conditions", "no undisturbed fall from the held rotation found"
    if release_ratio > rules["release_velocity_ratio"]:
        return (
            False,
            "disturbed_initial_conditions",
            f"release velocity {release_ratio:.1%} of the overturning velocity"
            f" (limit {rules['release_velocity_ratio']:.0%})",
        )
    if not np.isfinite(residual_top_mm) or residual_top_mm > rules["residual_top_mm"]:
        return (
            False,
            "residual_out_of_plumb",
            f"top residual {residual_top_mm:.2f} mm (limit {rules['residual_top_mm']} mm)",
        )
    return True, "", ""
