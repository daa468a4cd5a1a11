"""A virtual rocking-wall laboratory: simulated motions written as a campaign.

Turns wall motions (theta, and optionally phi, v, w, on a time grid) into the
transducer records of the lab's raw format (``docs/raw-format.md``),
with the instrument effects of the real campaign (noise, 50 Hz mains hum,
ringing after impacts, 3-decimal readings), the test protocol (a hold phase
with the screw's slow creep, the release, free rocking, rest), and the
faults and anomalies that the lab's validity rules must catch (dead, stuck
and clipped channels, spikes, short gaps, a disturbed release, a residual
out-of-plumb, an unreadable file).  Every effect is a knob that can be
switched off, everything is driven by one seed, and the truth is written
beside the campaign (``truth.csv``) so that each stage of the reduction can
be tested on data in which effects were hidden on purpose.

Layers, from the bottom:

* :func:`instrument_readings` / :func:`apply_faults`: readings from a motion;
* :func:`record_from_motion`: a whole record (hold, release, rocking, rest)
  from a free-rocking history theta(t) given as arrays;
* :func:`simulate_virtual_test`: the same from :func:`rocklab.simulation.reference.simulate_free`;
* :func:`write_campaign`: a folder in the lab's format plus ``truth.csv``;
  :func:`default_plan` a campaign that looks like the real one.

Lengths of the record in mm, dynamics in SI (m, s, rad).
"""

from __future__ import annotations

import gzip
import io
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd

from rocklab.lab import kinematics
from rocklab.lab.validity import MAX_LOST_OUT_OF_PLANE, RELEASE_VELOCITY_RATIO, RESIDUAL_TOP_MM, Verdict
from rocklab.physics import restitution, wall

#: Faults that lose a channel, and those that are repaired.
LOSING_FAULTS = ("dead", "stuck", "clipped")
REPAIRABLE_FAULTS = ("spikes", "gaps")

#: Specimens like those of the real campaign (Table 2 of the paper).
DEFAULT_SPECIMENS = pd.DataFrame(
    [
        ("1a", "1", "clay brick", 1420, 1090, 113, 18.1),
        ("2a", "2", "clay brick", 1440, 1630, 113, 18.1),
        ("3b", "3", "tuff", 1500, 1280, 123, 12.8),
        ("5c", "5", "tuff", 1130, 800, 123, 12.8),
    ],
    columns=["specimen", "wall", "unit", "length_mm", "height_mm", "thickness_mm", "unit_weight_kN_m3"],
)


@dataclass(frozen=True)
class Effects:
    """Instrument and protocol effects; a zero amplitude switches one off.

    Defaults match the real campaign: 0.002 mm noise and 50 Hz hum of
    ~0.002 mm on every channel, a 0.05-0.1 mm transient dying out in
    ~50 ms after impacts, a hold of 1.5-3 s with the screw pushing the wall
    back at ~3e-4 rad/s, 2-4 s of rest at the end, twist of ~5e-4 rad.

    Attributes
    ----------
    noise_mm : float
        Standard deviation of the white gaussian noise of each channel [mm].
    hum_mm, hum_hz : float
        Amplitude [mm] and frequency [Hz] of the mains hum (random phase per
        channel; aliased at 100 Hz sampling).
    ringing_mm, ringing_hz, ringing_tau_s : float
        Ringing after each impact: amplitude [mm] at the top of the wall for
        the first impact (scaled by the impact velocity and the transducer
        height), frequency [Hz], decay time [s].
    creep_rad_s : float
        Rate at which the screw pushes the held wall back [rad/s].
    hold_s, rest_s : (float, float)
        Ranges of the hold before the release and of the rest after the
        motion has died out [s].
    twist_ratio : float
        Twist phi as a fraction of theta (asymmetric wall) [-].
    slide_mm : float
        Standard deviation of the sliding w added at each impact [mm].
    decimals : int or None
        Decimals of the written readings (the lab writes 3); None keeps all.
    """

    noise_mm: float = 0.002
    hum_mm: float = 0.002
    hum_hz: float = 50.0
    ringing_mm: float = 0.08
    ringing_hz: float = 35.0
    ringing_tau_s: float = 0.012
    creep_rad_s: float = 3e-4
    hold_s: tuple = (1.5, 3.0)
    rest_s: tuple = (2.0, 4.0)
    twist_ratio: float = 0.005
    slide_mm: float = 0.005
    decimals: int | None = 3

    @classmethod
    def off(cls, **kw):
        """Every effect switched off (exact readings), except those in kw."""
        base = cls(
            noise_mm=0.0, hum_mm=0.0, ringing_mm=0.0, creep_rad_s=0.0, twist_ratio=0.0, slide_mm=0.0, decimals=None
        )
        return replace(base, **kw)


@dataclass(frozen=True)
class Fault:
    """An instrument fault injected in one record.

    Attributes
    ----------
    kind : {'dead', 'stuck', 'clipped', 'spikes', 'gaps', 'unreadable'}
        ``dead``: the channel reads ~0 (noise only) throughout; ``stuck``:
        frozen at its value from ``start_s`` on; ``clipped``: saturates at
        ``level`` times its largest |reading| (default 0.6); ``spikes``:
        ``count`` isolated samples off by 2-30 mm; ``gaps``: ``count`` runs of
        1 to ``max_len`` lost samples (empty fields); ``unreadable``: the file
        is truncated in the middle of the gzip stream (``channel`` ignored).
    channel : int
        Channel number (as in ``setups.csv``).
    """

    kind: str
    channel: int = 0
    start_s: float | None = None
    level: float | None = None
    count: int = 3
    max_len: int = 8

    def describe(self) -> str:
        if self.kind == "unreadable":
            return "unreadable file"
        extra = f" from {self.start_s:.2f} s" if self.start_s is not None and self.kind == "stuck" else ""
        n = f" x{self.count}" if self.kind in REPAIRABLE_FAULTS else ""
        return f"ch{self.channel} {self.kind}{extra}{n}"


def usual_layout(setup, length_mm, height_mm, thickness_mm, one_sided):
    """Transducers in the usual layout of the spec, as ``setups.csv`` rows.

    Channels 0, 1 on x = -L/2 and 2, 3 on x = +L/2 at 0.35 h and 0.85 h,
    horizontal along y with the frame 180-210 mm on the -y side; channel 4 on
    x = +L/2 at 0.6 h along x (frame 150 mm beyond); channel 5 (one-sided
    only) at the centre of the outer face at 0.5 h, frame 160 mm outside.
    Heights and distances are those of the real campaign's setups.
    """
    L, h, b = float(length_mm), float(height_mm), float(thickness_mm)
    lo, hi, mid = round(0.35 * h), round(0.85 * h), round(0.6 * h)
    rows = [
        (0, -L / 2, 0, lo, -L / 2, -180, lo),
        (1, -L / 2, 0, hi, -L / 2, -210, hi),
        (2, L / 2, 0, lo, L / 2, -185, lo),
        (3, L / 2, 0, hi, L / 2, -205, hi),
        (4, L / 2, 0, mid, L / 2 + 150, 0, mid),
    ]
    if one_sided:
        z5 = round(0.5 * h)
        rows.append((5, 0, b / 2, z5, 0, b / 2 + 160, z5))
    df = pd.DataFrame(
        rows, columns=["channel", "wall_x_mm", "wall_y_mm", "wall_z_mm", "frame_x_mm", "frame_y_mm", "frame_z_mm"]
    )
    df.insert(0, "setup", setup)
    return df


def _geometry(layout):
    X = layout[["wall_x_mm", "wall_y_mm", "wall_z_mm"]].to_numpy(float)
    F = layout[["frame_x_mm", "frame_y_mm", "frame_z_mm"]].to_numpy(float)
    return X, F


def top_offset_mm(theta, phi, v, w, length_mm, height_mm, thickness_mm):
    """Largest |y displacement| of the two top corners of the wall [mm].

    The quantity of the out-of-plumb rule, exact from the rigid-body map of
    the spec (the y component of X' - X at (+-L/2, 0, h)).
    """
    th, ph = np.asarray(theta, float), np.asarray(phi, float)
    b, h = float(thickness_mm), float(height_mm)
    ey = np.where(th < 0, -b / 2, b / 2)
    qy = np.cos(th) * (0 - ey) + np.sin(th) * h + ey
    out = [np.sin(ph) * x + np.cos(ph) * qy + np.asarray(w, float) for x in (-length_mm / 2, length_mm / 2)]
    return np.max(np.abs(out), axis=0)


def instrument_readings(
    t, theta, phi, v, w, layout, thickness_mm, height_mm, effects=Effects(), impacts=None, rng=None
):
    """Transducer readings of a motion with noise, hum and ringing [mm].

    Parameters
    ----------
    t : ndarray (N,)
        Time [s].
    theta, phi : ndarray (N,)
        Rotations [rad].
    v, w : ndarray (N,)
        Sliding [mm].
    layout : DataFrame
        ``setups.csv`` rows of the setup.
    thickness_mm, height_mm : float
        Wall thickness and height [mm].
    effects : Effects
    impacts : sequence of (t_impact [s], strength [-]), optional
        Impacts that make the readings ring; strength 1 for the reference
        (first) impact.
    rng : numpy.random.Generator

    Returns
    -------
    ndarray (N, nch)
        Elongations [mm] before faults and rounding.
    """
    rng = np.random.default_rng(rng)
    X, F = _geometry(layout)
    E = kinematics.transducer_elongation(theta, phi, v, w, X, F, thickness_mm)
    n, nch = E.shape
    if effects.noise_mm > 0:
        E += rng.normal(0.0, effects.noise_mm, E.shape)
    if effects.hum_mm > 0:
        ph = rng.uniform(0, 2 * np.pi, nch)
        amp = effects.hum_mm * rng.uniform(0.5, 1.5, nch)
        E += amp * np.sin(2 * np.pi * effects.hum_hz * t[:, None] + ph)
    if effects.ringing_mm > 0 and impacts is not None and len(impacts):
        reach = np.clip(X[:, 2] / float(height_mm), 0.0, 1.0) * rng.uniform(0.6, 1.4, nch)
        ring = np.zeros(n)
        dt = t[1] - t[0]
        span = int(np.ceil(6 * effects.ringing_tau_s / dt)) + 1
        for ti, strength in impacts:
            i0 = int(np.searchsorted(t, ti))
            seg = slice(i0, min(i0 + span, n))
            tau = t[seg] - ti
            ring[seg] += strength * np.exp(-tau / effects.ringing_tau_s) * np.sin(2 * np.pi * effects.ringing_hz * tau)
        E += effects.ringing_mm * ring[:, None] * reach
    return E


def apply_faults(readings, t, faults, channels, rng=None, noise_mm=0.002):
    """Inject instrument faults in readings (in place) [mm].

    Parameters
    ----------
    readings : ndarray (N, nch)
    t : ndarray (N,)
    faults : sequence of Fault
    channels : sequence of int
        Channel number of each column.
    rng : numpy.random.Generator
    noise_mm : float
        Noise left on a dead channel.

    Returns
    -------
    ndarray
        The readings, with NaN for lost samples.
    """
    rng = np.random.default_rng(rng)
    col = {c: i for i, c in enumerate(channels)}
    n = len(t)
    for f in faults:
        if f.kind == "unreadable":
            continue
        x = readings[:, col[f.channel]]
        if f.kind == "dead":
            x[:] = (0.0 if f.level is None else f.level) + rng.normal(0, noise_mm, n)
        elif f.kind == "stuck":
            i0 = int(np.searchsorted(t, f.start_s if f.start_s is not None else t[n // 3]))
            x[i0:] = x[i0]
        elif f.kind == "clipped":
            k = int(np.nanargmax(np.abs(x)))
            lim = (0.6 if f.level is None else f.level) * abs(x[k])
            x[:] = np.minimum(x, lim) if x[k] > 0 else np.maximum(x, -lim)
        elif f.kind == "spikes":
            idx = rng.choice(np.arange(5, n - 5), size=f.count, replace=False)
            x[idx] += rng.choice([-1.0, 1.0], f.count) * rng.uniform(2.0, 30.0, f.count)
        elif f.kind == "gaps":
            for i0 in rng.choice(np.arange(5, n - f.max_len - 5), size=f.count, replace=False):
                x[i0 : i0 + rng.integers(1, f.max_len + 1)] = np.nan
        else:
            raise ValueError(f"unknown fault kind {f.kind!r}")
    return readings


def _smoothstep(u):
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3 - 2 * u)


def record_from_motion(
    t_free,
    theta_free,
    fs,
    layout,
    specimen,
    *,
    phi_free=None,
    v_free=None,
    w_free=None,
    impacts=None,
    t_rest=None,
    effects=Effects(),
    faults=(),
    residual_top_mm=0.0,
    residual_kind="rotation",
    rng=None,
):
    """A whole record (hold, release, free rocking, rest) from a free motion.

    Parameters
    ----------
    t_free, theta_free : ndarray
        Free rocking from the release (t_free[0] = 0) on the grid 1/fs [s, rad];
        theta_free[0] is the release rotation theta0.
    fs : float
        Sampling rate [Hz] (400 or 100).
    layout : DataFrame
        ``setups.csv`` rows of the setup.
    specimen : Mapping
        ``length_mm``, ``height_mm``, ``thickness_mm``.
    phi_free, v_free, w_free : ndarray, optional
        Extra degrees of freedom of the free motion [rad, mm, mm]; default
        the twist and sliding of ``effects``.
    impacts : DataFrame, optional
        Impacts of the free motion (``t`` [s] from release, ``thetadot_before``):
        they make the readings ring and the wall slide.
    t_rest : float, optional
        Time from release at which the wall comes to rest [s]; default the
        end of ``t_free``.
    effects : Effects
    faults : sequence of Fault
    residual_top_mm : float
        Final offset of the wall top (signed, y) [mm], grown over the motion.
    residual_kind : {'rotation', 'sliding'}
        As a final rotation theta_res = offset / h or a sliding w.
    rng : numpy.random.Generator

    Returns
    -------
    t : ndarray (N,)
        Record time [s] from 0.
    readings : ndarray (N, nch)
        Readings [mm], NaN where lost, rounded to ``effects.decimals``.
    truth : dict
        ``t_release``, ``theta0``, ``theta`` / ``phi`` / ``v`` / ``w`` arrays
        (the motion written), ``residual_top_mm`` (true, from the final pose).
    """
    rng = np.random.default_rng(rng)
    L, h, b = (float(specimen[k]) for k in ("length_mm", "height_mm", "thickness_mm"))
    dt = 1.0 / fs
    theta_free = np.asarray(theta_free, float)
    n_free = len(theta_free)
    if t_rest is None:
        t_rest = float(t_free[-1])
    # Drop the part of the free history far beyond the rest.
    hold = rng.uniform(*effects.hold_s)
    rest = rng.uniform(*effects.rest_s)
    n_keep = min(n_free, int(np.ceil((t_rest + rest) / dt)) + 1)
    theta_free = theta_free[:n_keep]
    n_hold = int(round(hold * fs))
    n_tail = max(int(np.ceil((t_rest + rest) / dt)) + 1 - n_keep, 0)
    theta0 = theta_free[0]
    sgn = np.sign(theta0) or 1.0
    # The screw holds the wall past the release rotation and pushes it back
    # slowly: a linear creep ending at theta0 at the release.
    th_hold = theta0 + sgn * effects.creep_rad_s * (n_hold - np.arange(n_hold)) * dt
    theta = np.concatenate([th_hold, theta_free, np.full(n_tail, theta_free[-1])])
    n = len(theta)
    t = np.arange(n) * dt
    t_release = n_hold * dt
    tf = t - t_release  # time from release
    rel = tf >= 0

    imp_t = np.asarray([] if impacts is None or len(impacts) == 0 else impacts["t"], float)
    imp_v = np.asarray([] if impacts is None or len(impacts) == 0 else np.abs(impacts["thetadot_before"]), float)
    imp_t, imp_v = imp_t[imp_t <= t_rest + rest], imp_v[imp_t <= t_rest + rest]

    phi = (
        effects.twist_ratio * theta
        if phi_free is None
        else np.concatenate([np.full(n_hold, phi_free[0]), phi_free[:n_keep], np.full(n_tail, phi_free[n_keep - 1])])
    )
    v = (
        np.zeros(n)
        if v_free is None
        else np.concatenate([np.full(n_hold, v_free[0]), v_free[:n_keep], np.full(n_tail, v_free[n_keep - 1])])
    )
    w = (
        np.zeros(n)
        if w_free is None
        else np.concatenate([np.full(n_hold, w_free[0]), w_free[:n_keep], np.full(n_tail, w_free[n_keep - 1])])
    )
    if w_free is None and effects.slide_mm > 0 and imp_t.size:
        steps = rng.normal(0, effects.slide_mm, imp_t.size)
        for ti, s in zip(imp_t, steps):
            w += s * _smoothstep((tf - ti) / 0.01)

    if residual_top_mm:
        # Grows from the first impact to the rest (the wall settles askew or
        # walks on its base), then stays.
        t_a = imp_t[0] if imp_t.size else 0.0
        ramp = _smoothstep((tf - t_a) / max(t_rest - t_a, dt)) * rel
        if residual_kind == "rotation":
            theta = theta + np.arcsin(residual_top_mm / h) * ramp
        elif residual_kind == "sliding":
            w = w + residual_top_mm * ramp
        else:
            raise ValueError("residual_kind must be 'rotation' or 'sliding'")

    ring = None
    if imp_t.size:
        ring = list(zip(imp_t + t_release, imp_v / imp_v[0]))
    E = instrument_readings(t, theta, phi, v, w, layout, b, h, effects, ring, rng)
    apply_faults(E, t, faults, layout.channel.tolist(), rng, effects.noise_mm)
    if effects.decimals is not None:
        E = np.round(E, effects.decimals)
    top = top_offset_mm(theta[-1], phi[-1], v[-1], w[-1], L, h, b)
    truth = {
        "t_release": t_release,
        "theta0": float(theta0),
        "theta": theta,
        "phi": phi,
        "v": v,
        "w": w,
        "residual_top_mm": float(top),
        "t_rest": t_release + t_rest,
    }
    return t, E, truth


def write_record(path, test_id, fs, t, readings, channels, unreadable=False):
    """Write one ``tests/<id>.csv.gz`` exactly in the lab's format.

    Time with 4 decimals, readings with 3, empty fields for NaN.  With
    ``unreadable`` the gzip stream is cut in the middle (a broken transfer).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    head = f"# test_id: {test_id}\n# sampling_rate_hz: {fs:g}\n# units: s, mm\n"
    head += "time_s," + ",".join(f"ch{c}" for c in channels) + "\n"
    buf = io.StringIO()
    np.savetxt(buf, np.column_stack([t, readings]), fmt=["%.4f"] + ["%.3f"] * readings.shape[1], delimiter=",")
    body = buf.getvalue().replace("nan", "")
    data = gzip.compress((head + body).encode(), compresslevel=6, mtime=0)
    if unreadable:
        data = data[: len(data) // 2]
    path.write_bytes(data)


@dataclass
class VirtualTest:
    """One test of a virtual campaign.

    Attributes
    ----------
    test_id, specimen : str
    boundary : {'two-sided', 'one-sided'}
    direction : {'push', 'pull'}
    contact_depth_mm : float or None
        One-sided only.
    fs : float
        Sampling rate [Hz].
    alpha_ratio : float
        Rocking angle of the hinge over the nominal alpha (alpha_ind / alpha):
        0.91 two-sided and 0.73 one-sided on average in the paper.
    theta0_ratio : float
        Release rotation over the rocking angle (just below 1: the wall is
        pushed back just past its instability point).
    release_ratio : float
        Initial angular velocity over the overturning velocity of Eq. 16
        (a disturbed release above 0.10), towards the rest position.
    residual_top_mm : float
        Final offset of the wall top [mm] (out-of-plumb above 1.5).
    residual_kind : {'rotation', 'sliding'}
    model : dict
        Further ``RockingModel`` keywords (``impact``, ``alpha_neg``,
        ``flight_damping``, ``hinge_friction``, ``flight_drag``, ``gap``,
        ``form``, ``hinge_rounding``, ...), every physical effect of the
        simulator; ``alpha_rock`` defaults to alpha_ratio * alpha.  With dry
        friction mu, release below (1 - mu / alpha) of the rocking angle (a
        wall held by friction at its apex is not simulated).
    faults : list of Fault
    effects : Effects
    note : str
        Operator's note written in tests.csv.
    log : dict
        Further columns of the test's row of tests.csv (column -> value: a
        date, a temperature the operator wrote, ...).
    """

    test_id: str
    specimen: str = "1a"
    boundary: str = "two-sided"
    direction: str = "push"
    contact_depth_mm: float | None = None
    fs: float = 400.0
    alpha_ratio: float | None = None
    theta0_ratio: float = 0.995
    release_ratio: float = 0.0
    residual_top_mm: float = 0.0
    residual_kind: str = "rotation"
    model: dict = field(default_factory=dict)
    faults: list = field(default_factory=list)
    effects: Effects = field(default_factory=Effects)
    note: str = ""
    log: dict = field(default_factory=dict)

    @property
    def setup(self) -> str:
        bc = "2s" if self.boundary == "two-sided" else f"1s-cd{self.contact_depth_mm:g}"
        return f"S-{self.specimen}-{bc}"


def expected_verdict(faults, layout, thickness_mm, release_ratio, residual_top_mm):
    """Verdict the lab's rules give a test, from what was injected.

    Returns
    -------
    (Verdict, str)
        The verdict (valid, or the first of :meth:`Verdict.rejections` that applies)
        and its explanation.
    """
    if any(f.kind == "unreadable" for f in faults):
        return Verdict.UNREADABLE, "file truncated"
    X, F = _geometry(layout)
    d = F - X
    oop = set(
        layout.channel[(np.abs(d[:, 1]) >= np.abs(d[:, 0])) & ~np.isclose(np.abs(X[:, 1]), thickness_mm / 2, atol=1.0)]
    )
    lost = sorted({f.channel for f in faults if f.kind in LOSING_FAULTS} & oop)
    if len(lost) > MAX_LOST_OUT_OF_PLANE:
        return Verdict.INSTRUMENT_MALFUNCTION, f"{len(lost)} out-of-plane channels lost ({lost})"
    if release_ratio > RELEASE_VELOCITY_RATIO:
        return Verdict.DISTURBED_INITIAL_CONDITIONS, f"release velocity {release_ratio:.0%} of Eq. 16"
    if abs(residual_top_mm) > RESIDUAL_TOP_MM:
        return Verdict.RESIDUAL_OUT_OF_PLUMB, f"top residual {abs(residual_top_mm):.2f} mm"
    return Verdict.VALID, ""


def _law_name(law):
    if law is None:
        return ""
    inner = ", ".join(
        f"{k}={_law_name(v) if hasattr(v, '__dict__') else v}" for k, v in vars(law).items() if not k.startswith("_")
    )
    return f"{type(law).__name__}({inner})"


def simulate_virtual_test(test: VirtualTest, specimen, layout, rng=None, t_end=40.0):
    """Simulate one test with :func:`rocklab.simulation.reference.simulate_free` and record it.

    Parameters
    ----------
    test : VirtualTest
    specimen : Mapping
        Row of specimens.csv (mm).
    layout : DataFrame
        setups.csv rows of the test's setup.
    rng : numpy.random.Generator
    t_end : float
        Longest free rocking simulated [s].

    Returns
    -------
    t, readings, truth
        As :func:`record_from_motion`; truth also holds every parameter used.
    """
    from rocklab.physics.impact import HousnerTwoSided, calibrated
    from rocklab.simulation.model import RockingModel
    from rocklab.simulation.reference import simulate_free

    rng = np.random.default_rng(rng)
    h, b = specimen["height_mm"] / 1e3, specimen["thickness_mm"] / 1e3
    one = test.boundary == "one-sided"
    if one and test.direction == "pull":
        raise ValueError("a one-sided wall can only be released from theta > 0 (push)")
    alpha = float(wall.slenderness_angle(h, b))
    ratio = test.alpha_ratio if test.alpha_ratio is not None else (0.73 if one else 0.91)
    kw = {"alpha_rock": ratio * alpha, **test.model}
    if not one and "impact" not in kw:
        # The campaign's mean e_exp / e_an,2s (Sect. 4): records of ~10 s.
        c = restitution.CALIBRATED_RATIO_TWO_SIDED
        kw["impact"] = calibrated(HousnerTwoSided(), c, c)
    model = RockingModel.from_wall(h, b, boundary=test.boundary, **kw)
    sgn = 1.0 if test.direction == "push" else -1.0
    a_side = model.alpha_pos if sgn > 0 else model.alpha_minus
    theta0 = sgn * test.theta0_ratio * a_side
    w_r = float(wall.overturning_velocity(alpha, model.p))
    thetadot0 = -sgn * test.release_ratio * w_r
    hist = simulate_free(model, theta0, thetadot0, t_end=t_end, fs=test.fs)
    t_rest = hist.t_rest if hist.t_rest is not None else float(hist.t[-1])
    t, E, truth = record_from_motion(
        hist.t,
        np.nan_to_num(hist.theta, nan=np.nanmax(np.abs(hist.theta)) * sgn),
        test.fs,
        layout,
        specimen,
        impacts=hist.impacts,
        t_rest=t_rest,
        effects=test.effects,
        faults=test.faults,
        residual_top_mm=test.residual_top_mm,
        residual_kind=test.residual_kind,
        rng=rng,
    )
    imp = hist.impacts
    base = imp[imp["kind"] == "base"] if len(imp) else imp
    ratios = (base["thetadot_after"] / base["thetadot_before"]).to_numpy() if len(base) else np.array([])
    # a one-sided wall with a gap rocks on the base impacts of Eq. 2
    e_an = restitution.analytic("one-sided" if one and model.gap == 0 else "two-sided", alpha)
    reason, why = expected_verdict(
        test.faults, layout, specimen["thickness_mm"], test.release_ratio, truth["residual_top_mm"]
    )
    truth.update(
        {
            "alpha": alpha,
            "alpha_rock": model.alpha_pos,
            "alpha_neg": model.alpha_minus,
            "p": model.p,
            "overturning_velocity": w_r,
            "thetadot0": thetadot0,
            "impact_law": _law_name(model.impact) or "default",
            "flight_damping": model.flight_damping,
            "hinge_rounding": model.hinge_rounding,
            "hinge_friction": model.hinge_friction,
            "flight_drag": model.flight_drag,
            "gap": model.gap,
            "form": model.form,
            "e_first": float(ratios[0]) if ratios.size else np.nan,
            "e_true": float(np.median(ratios)) if ratios.size else np.nan,
            "e_analytic": float(e_an),
            "n_impacts": int(len(imp)),
            "overturned": bool(hist.overturned),
            "expected_reason": reason,
            "expected_detail": why,
            "expected_valid": reason == "valid",
        }
    )
    return t, E, truth


def _effects_on(e: Effects):
    names = [
        k for k in ("noise_mm", "hum_mm", "ringing_mm", "creep_rad_s", "twist_ratio", "slide_mm") if getattr(e, k) > 0
    ]
    if e.decimals is not None:
        names.append("rounding")
    return names


def write_campaign(out_dir, tests, specimens=None, layouts=None, seed=0, t_end=40.0):
    """Simulate and write a virtual campaign in the lab's format, with its truth.

    Parameters
    ----------
    out_dir : path
        Campaign folder to create (specimens.csv, setups.csv, tests.csv,
        tests/<id>.csv.gz, truth.csv).
    tests : sequence of VirtualTest
    specimens : DataFrame, optional
        specimens.csv rows; default :data:`DEFAULT_SPECIMENS`.
    layouts : Mapping setup id -> DataFrame, optional
        Transducer layouts; setups not given get :func:`usual_layout`.
    seed : int
        Seed of everything random (one independent stream per test).
    t_end : float
        Longest free rocking simulated [s].

    Returns
    -------
    DataFrame
        truth.csv: one row per test with every parameter used, the true
        theta0 and e, the effects on, the faults and the expected verdict.
    """
    out = Path(out_dir)
    (out / "tests").mkdir(parents=True, exist_ok=True)
    specimens = DEFAULT_SPECIMENS if specimens is None else specimens
    spec = specimens.set_index("specimen")
    layouts = dict(layouts or {})
    rows, truths = [], []
    streams = np.random.SeedSequence(seed).spawn(len(tests))
    for test, ss in zip(tests, streams):
        sp = spec.loc[test.specimen]
        if test.setup not in layouts:
            layouts[test.setup] = usual_layout(
                test.setup, sp.length_mm, sp.height_mm, sp.thickness_mm, test.boundary == "one-sided"
            )
        layout = layouts[test.setup]
        t, E, truth = simulate_virtual_test(test, sp, layout, np.random.default_rng(ss), t_end)
        rel = f"tests/{test.test_id}.csv.gz"
        write_record(
            out / rel,
            test.test_id,
            test.fs,
            t,
            E,
            layout.channel.tolist(),
            unreadable=any(f.kind == "unreadable" for f in test.faults),
        )
        rows.append(
            {
                "test_id": test.test_id,
                "specimen": test.specimen,
                "boundary": test.boundary,
                "contact_depth_mm": "" if test.contact_depth_mm is None else f"{test.contact_depth_mm:g}",
                "direction": test.direction,
                "setup": test.setup,
                "file": rel,
                "note": test.note,
                **test.log,
            }
        )
        truths.append(
            {
                "test_id": test.test_id,
                "specimen": test.specimen,
                "boundary": test.boundary,
                "direction": test.direction,
                "fs": test.fs,
                "theta0": truth["theta0"],
                "thetadot0": truth["thetadot0"],
                "release_ratio": test.release_ratio,
                "t_release": truth["t_release"],
                "t_rest": truth["t_rest"],
                "alpha": truth["alpha"],
                "alpha_rock": truth["alpha_rock"],
                "alpha_neg": truth["alpha_neg"],
                "p": truth["p"],
                "overturning_velocity": truth["overturning_velocity"],
                "impact_law": truth["impact_law"],
                "flight_damping": truth["flight_damping"],
                "hinge_rounding": truth["hinge_rounding"],
                "hinge_friction": truth["hinge_friction"],
                "flight_drag": truth["flight_drag"],
                "gap": truth["gap"],
                "form": truth["form"],
                "e_true": truth["e_true"],
                "e_first": truth["e_first"],
                "e_analytic": truth["e_analytic"],
                "n_impacts": truth["n_impacts"],
                "overturned": truth["overturned"],
                "residual_top_mm": truth["residual_top_mm"],
                "residual_kind": test.residual_kind,
                "effects": ";".join(_effects_on(test.effects)),
                **{f"effect_{k}": v for k, v in asdict(test.effects).items() if not isinstance(v, tuple)},
                "faults": ";".join(f.describe() for f in test.faults),
                "expected_valid": truth["expected_valid"],
                "expected_reason": truth["expected_reason"],
                "expected_detail": truth["expected_detail"],
            }
        )
    specimens.to_csv(out / "specimens.csv", index=False)
    used = {t.setup for t in tests}
    pd.concat([layouts[s] for s in sorted(used)], ignore_index=True).to_csv(out / "setups.csv", index=False)
    pd.DataFrame(rows).to_csv(out / "tests.csv", index=False)
    truth = pd.DataFrame(truths)
    truth.to_csv(out / "truth.csv", index=False)
    return truth


def default_plan(n_tests=20, seed=0, fs_early=100.0):
    """A campaign plan like the real one, with every anomaly represented.

    About two thirds are clean valid tests over the default specimens and
    both boundary conditions; the rest carry one hidden effect each: a lost
    backup-able channel, a lost channel 4, two lost out-of-plane channels,
    spikes and gaps, a disturbed release, a residual out-of-plumb (rotation
    and sliding), an unreadable file, a 100 Hz early test, a pull test.

    Returns
    -------
    list of VirtualTest
    """
    rng = np.random.default_rng(seed)
    special = [
        dict(faults=[Fault("dead", 1)]),
        dict(faults=[Fault("stuck", 4, start_s=3.0)]),
        dict(faults=[Fault("dead", 0), Fault("clipped", 3, level=0.5)]),
        dict(faults=[Fault("spikes", 1, count=4), Fault("gaps", 3, count=3, max_len=6)]),
        dict(release_ratio=0.2),
        dict(residual_top_mm=3.0, residual_kind="rotation"),
        dict(residual_top_mm=-2.5, residual_kind="sliding"),
        dict(faults=[Fault("unreadable")]),
        dict(fs=fs_early),
        dict(direction="pull"),
    ]
    specs = DEFAULT_SPECIMENS.specimen.tolist()
    plan = []
    for k in range(n_tests):
        kw = special[k] if k < len(special) else {}
        one = kw.get("direction") != "pull" and k % 3 == 2
        bc = dict(boundary="one-sided", contact_depth_mm=float(rng.choice([120, 260]))) if one else {}
        residual = kw.pop("residual_top_mm", float(rng.normal(0, 0.3)))
        plan.append(
            VirtualTest(
                test_id=f"V{k + 1:04d}",
                specimen=specs[k % len(specs)],
                residual_top_mm=residual,
                theta0_ratio=float(rng.uniform(0.99, 0.998)),
                **bc,
                **kw,
            )
        )
    return plan
