"""The lab's validity rules for a free-rocking test, applied from the data.

``docs/raw-format.md`` ("What makes a test valid"):

* residual out-of-plumb: the wall top, once the motion has died out, must be
  within 1.5 mm of where it was at rest before the test (the vertical wall,
  where the transducers were zeroed);
* undisturbed initial conditions: a release angular velocity above 10 % of
  the overturning velocity of Eq. 16 is disturbed (the release speed of
  :func:`rocklab.lab.release.release_state`);
* working instruments: with two of the out-of-plane kinematic channels lost
  the test is rejected; one is replaced by the backup; a lost in-plane
  channel leaves v unsolved (v = 0, flagged).

Channel roles are read from the transducer geometry, never assumed.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from rocklab.lab import kinematics, release
from rocklab.lab.channels import BACKUP_CHANNELS, CHANNEL_POLICY, LOST_STATUSES, ChannelReport

#: Largest residual out-of-plumb of the wall top after the motion [mm].
RESIDUAL_TOP_MM = 1.5
#: Largest release speed of an undisturbed release, over Eq. 16 [-].
RELEASE_VELOCITY_RATIO = 0.10
#: Most out-of-plane kinematic channels lost (the backup stands in) before a reject.
MAX_LOST_OUT_OF_PLANE = 1
#: The rules above: the defaults of the workflow config's ``validity`` section.
RULES = {
    "residual_top_mm": RESIDUAL_TOP_MM,
    "release_velocity_ratio": RELEASE_VELOCITY_RATIO,
    "max_lost_out_of_plane": MAX_LOST_OUT_OF_PLANE,
}


class Verdict(StrEnum):
    """The verdict of a test: valid, or the rule it breaks (``reject_reason`` of ``qc.csv``).

    The one vocabulary of verdicts: ``qc.csv``'s schema
    (``workflow/schemas/qc.schema.yaml``), the QC summary and the virtual
    lab's expected verdicts use it. The rejections are listed in the order
    they are reported when several apply (:meth:`rejections`).
    """

    VALID = "valid"
    UNREADABLE = "unreadable"
    INSTRUMENT_MALFUNCTION = "instrument_malfunction"
    DISTURBED_INITIAL_CONDITIONS = "disturbed_initial_conditions"
    RESIDUAL_OUT_OF_PLUMB = "residual_out_of_plumb"

    @classmethod
    def rejections(cls) -> tuple[Verdict, ...]:
        """The reject reasons, first the one reported when several apply."""
        return tuple(v for v in cls if v is not cls.VALID)


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


@dataclass(frozen=True)
class SetupLayout:
    """A setup's transducers on a wall of one thickness, as a reduction reads them
    (:func:`setup_layout`; the same for every test of that setup and wall).

    Attributes
    ----------
    channels : list of int
        The setup's channel numbers, in the order of its rows of ``setups.csv`` (by channel).
    wall_xyz, frame_xyz : ndarray (nch, 3)
        Transducer end points on the wall (body frame) and on the frame
        (lab frame) [mm], in the order of ``channels`` (read-only).
    roles : DataFrame
        :func:`channel_roles` of the setup.
    """

    channels: list[int]
    wall_xyz: np.ndarray
    frame_xyz: np.ndarray
    roles: pd.DataFrame


def setup_layout(setup: pd.DataFrame, thickness_mm: float) -> SetupLayout:
    """The :class:`SetupLayout` of the rows ``setup`` of ``setups.csv`` on a wall ``thickness_mm`` thick [mm]."""
    wall_xyz = setup[["wall_x_mm", "wall_y_mm", "wall_z_mm"]].to_numpy(float)
    frame_xyz = setup[["frame_x_mm", "frame_y_mm", "frame_z_mm"]].to_numpy(float)
    # shared by the tests of the setup: a test takes its rows, never changes these
    wall_xyz.flags.writeable = frame_xyz.flags.writeable = False
    return SetupLayout(setup.channel.tolist(), wall_xyz, frame_xyz, channel_roles(setup, thickness_mm))


@dataclass
class ChannelChoice:
    """Channels used for the kinematics, and what that choice cost."""

    used: list[int]
    solve_v: bool
    lost_out_of_plane: list[int]
    flags: list[str] = field(default_factory=list)
    malfunction: str | None = None
    backups_used: list[int] = field(default_factory=list)


def choose_channels(
    roles: pd.DataFrame,
    lost: set[int],
    backup: Sequence[int] = BACKUP_CHANNELS,
    policy: str = CHANNEL_POLICY,
    max_lost: int = MAX_LOST_OUT_OF_PLANE,
    absent: Sequence[int] = (),
) -> ChannelChoice:
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
    absent : sequence of int
        The lost channels that are lost because the record has no column for
        them (a channel of the setup the acquisition did not write); named so.
    """
    # as arrays: the pandas lookups cost more than the choice
    channel, role = roles.channel.to_numpy(), roles.role.to_numpy()
    oop, inp = channel[role == "out_of_plane"].tolist(), channel[role == "in_plane"].tolist()
    lost_oop = [c for c in oop if c in lost]
    flags: list[str] = []
    primary = [c for c in oop if c not in backup]
    spare = [c for c in oop if c in backup and c not in lost]
    if policy == "all":
        used: list[int] = [c for c in oop if c not in lost]
        stand_in: list[int] = []
    else:
        used = [c for c in primary if c not in lost]
        need = len(primary) - len(used)
        stand_in = spare[:need]
        used += stand_in
        for c in stand_in:
            flags.append(f"backup ch{c} used")
    names = {c: f"ch{c} not in the record" if c in absent else f"ch{c}" for c in channel.tolist()}
    for c in lost_oop:
        flags.append(names[c] if c in absent else f"ch{c} lost")
    malfunction = None
    if len(lost_oop) > max_lost or len(used) < 3:
        malfunction = f"{len(lost_oop)} out-of-plane channel(s) lost ({', '.join(names[c] for c in lost_oop)})"
        if len(used) < 3 and len(lost_oop) <= max_lost:
            malfunction += f": {len(used)} left of the 3 the kinematics needs"
    good_inp = [c for c in inp if c not in lost]
    solve_v = bool(good_inp)
    if not solve_v:
        flags.append("in-plane channel lost: v = 0")
    flags += [names[c] for c in inp if c in absent]
    return ChannelChoice(sorted(used + good_inp[:1]), solve_v, lost_oop, flags, malfunction, stand_in)


#: The channel faults of ``qc.csv``, one column each (:func:`channel_faults`).
FAULT_COLUMNS = (
    "channels_dead",
    "channels_stuck",
    "channels_clipped",
    "channels_dropout",
    "channels_spikes_repaired",
    "channels_backup_used",
    "in_plane_lost",
)


def channel_faults(reports: Sequence[ChannelReport], choice: ChannelChoice) -> dict[str, str | int]:
    """The channel faults of a test, as the columns :data:`FAULT_COLUMNS` of ``qc.csv``.

    Parameters
    ----------
    reports : list of rocklab.lab.channels.ChannelReport
        What :func:`rocklab.lab.channels.assess_channels` found on each channel.
    choice : ChannelChoice
        The channels chosen for the kinematics.

    Returns
    -------
    dict
        ``channels_<status>`` for each status that loses a channel, the channels
        found so (``ch<n>`` separated by spaces, empty for none); the same for
        the channels whose spikes were repaired and the backups that stood in;
        ``in_plane_lost``: 1 when no in-plane channel was left (v = 0), else 0
        (a netCDF attribute holds no boolean).
    """

    def named(channels: Iterable[int]) -> str:
        return " ".join(f"ch{c}" for c in channels)

    return {
        **{f"channels_{s}": named(r.channel for r in reports if r.status == s) for s in LOST_STATUSES},
        "channels_spikes_repaired": named(r.channel for r in reports if r.spikes),
        "channels_backup_used": named(choice.backups_used),
        "in_plane_lost": int(not choice.solve_v),
    }


#: The columns of :data:`FAULT_COLUMNS` of a test whose record could not be read.
NO_FAULTS = {**{c: "" for c in FAULT_COLUMNS[:-1]}, "in_plane_lost": 0}


def top_displacement(
    theta: ArrayLike,
    phi: ArrayLike,
    v: ArrayLike,
    w: ArrayLike,
    length_mm: float,
    height_mm: float,
    thickness_mm: float,
) -> np.ndarray:
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


def residual_out_of_plumb(top_y: ArrayLike, fs: float, tail_s: float = 1.0) -> float:
    """Residual top out-of-plumb after the motion [mm].

    The largest |y displacement| of the top corners, taken as the median over
    the last ``tail_s`` seconds of the record (the wall is at rest there).
    """
    n = max(int(round(tail_s * fs)), 1)
    tail = np.asarray(top_y)[-n:]
    if not np.isfinite(tail).any():
        return float("nan")
    return float(np.nanmax(np.abs(np.nanmedian(tail, axis=0))))


def verdict(
    malfunction: str | None,
    release_ratio: float,
    residual_top_mm: float,
    rules: Mapping[str, float] = RULES,
) -> tuple[bool, str, str]:
    """Valid flag, reject reason and its explanation by the lab's rules.

    Parameters
    ----------
    malfunction : str or None
        Why the instruments are lost (:attr:`ChannelChoice.malfunction`, or
        :attr:`rocklab.lab.instrument.InstrumentMotion.malfunction`), None when they work.
    release_ratio : float
        Release angular velocity over Eq. 16.
    residual_top_mm : float
        From :func:`residual_out_of_plumb`.
    rules : dict
        ``residual_top_mm``, ``release_velocity_ratio`` (config ``validity``).
    """
    if malfunction:
        return False, Verdict.INSTRUMENT_MALFUNCTION, malfunction
    if not np.isfinite(release_ratio):
        return False, Verdict.DISTURBED_INITIAL_CONDITIONS, "no undisturbed fall from the held rotation found"
    if release_ratio > rules["release_velocity_ratio"]:
        return (
            False,
            Verdict.DISTURBED_INITIAL_CONDITIONS,
            f"release velocity {release_ratio:.1%} of the overturning velocity"
            f" (limit {rules['release_velocity_ratio']:.0%})",
        )
    if not np.isfinite(residual_top_mm) or residual_top_mm > rules["residual_top_mm"]:
        return (
            False,
            Verdict.RESIDUAL_OUT_OF_PLUMB,
            f"top residual {residual_top_mm:.2f} mm (limit {rules['residual_top_mm']} mm)",
        )
    return True, "", ""


def judge_motion(
    meta: Mapping[str, Any],
    time: np.ndarray,
    fs: float,
    theta: np.ndarray,
    phi: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    malfunction: str | None,
    rules: Mapping[str, float],
) -> tuple[dict[str, Any], np.ndarray]:
    """The lab's rules on a test's motion, whatever the instrument: the verdict and the numbers
    it rests on, as attributes of the reduced test, and the y displacement of the top corners
    [mm] (N, 2) that the out-of-plumb is read from.

    ``meta`` is the test's metadata (:func:`rocklab.lab.reduction.test_metadata`): the wall's
    dimensions [mm], its ``p`` [rad/s] and ``overturning_velocity`` (Eq. 16) [rad/s]; the
    release speed is :func:`rocklab.lab.release.release_state`'s.
    """
    top = top_displacement(theta, phi, v, w, meta["length_mm"], meta["height_mm"], meta["thickness_mm"])
    residual = residual_out_of_plumb(top, fs)
    state = release.release_state(time, theta, meta["p"])
    ratio = state["thetadot0"] / meta["overturning_velocity"]
    valid, reason, detail = verdict(malfunction, ratio, residual, rules)
    return {
        "valid": int(valid),
        "reject_reason": reason,
        "reject_detail": detail or "",
        "residual_top_mm": residual,
        "release_velocity_ratio": ratio,
        "t_release": state["t_release"],
        "theta0_release": state["theta0"],
        "alpha_fit_release": state["alpha_fit"],
    }, top
