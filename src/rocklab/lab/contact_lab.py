"""A second virtual lab whose physics is not the rocking model: a rigid block on compliant contacts.

The virtual lab of :mod:`rocklab.lab.virtual_lab` simulates walls with the
project's own rocking model, the family the diagnosis fits, so a bench built
on it alone is circular: it can only show that the diagnosis recovers the
causes it was written to find.  This module simulates the same tests with
different physics: the wall is a planar rigid rectangle (the specimen's
height and thickness, its mass and its inertia about the centre of mass)
free to slide and to rotate in the plane of rocking, standing on two
compliant contacts at its base edges with Coulomb friction.  Nothing says
where it pivots, when it impacts nor what it loses there: rocking,
restitution, bounce, sliding and the loss at each impact follow from the
contacts (:class:`ContactModel`).

Why MuJoCo (and not PyBullet): it is maintained (Google DeepMind, monthly
releases), deterministic (the same model and state give the same bits on a
machine), its soft contact is a documented spring-damper in constraint
space (``solref``: time constant and damping ratio; ``solimp``: impedance;
mujoco.readthedocs.io, "Computation" and "Modeling > Solver parameters"),
with the elliptic Coulomb cone, it has a pip wheel with no system library,
and it is fast: 40 s of rocking of wall 1a (5 kHz steps, a Python loop
that reads the contact forces at each) take about 4 s on one core.  PyBullet's contact is a
velocity-level LCP whose restitution is an input (``restitution`` of
``changeDynamics``): the quantity under test would be set, not measured.
MuJoCo is imported when a wall is first simulated
(:func:`rocklab._imports.lazy_module`): ``import rocklab`` does not load it.

The record goes through the virtual lab's own machinery: the motion
(theta and the base's sliding w, sampled at the test's rate) is handed to
:func:`rocklab.lab.virtual_lab.record_virtual_test` (the hold, the release,
the rest, the transducers, the rotation and inertial instruments, their
effects and faults), and :func:`simulate_contact_test` is the ``simulate``
of :func:`rocklab.lab.virtual_lab.write_campaign`: a campaign folder in the
lab's raw format (``docs/raw-format.md``) with ``truth.csv`` beside it.

The truth is measured from the block's own state (:func:`contact_episodes`):
the angular velocity just before the landing edge first carries load over
the angular velocity just after the edge left stops carrying it, one
contact episode per impact.  Two-sided (free-standing) walls only: a
return wall (one-sided rocking, :class:`rocklab.physics.boundary.Boundary`)
is not built.

Lengths of the record in mm, dynamics in SI (m, s, rad, N).

Size: one construction read top to bottom (the MJCF model, the hold and release,
the contact episodes that give the truth, the campaign's ``simulate``); split, each
part would need the others' conventions of axes, edges and signs.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass
from types import ModuleType
from typing import Any

import numpy as np
import pandas as pd

from rocklab._imports import lazy_module
from rocklab.physics import restitution, wall
from rocklab.physics.boundary import Boundary
from rocklab.physics.constants import G


def _mujoco() -> ModuleType:
    return lazy_module("mujoco")


@dataclass(frozen=True)
class ContactModel:
    """The wall's contacts with its base: every knob of the contact lab.

    Attributes
    ----------
    contact_time_s : float
        Time constant of each contact's spring-damper [s] (MuJoCo's
        ``solref[0]``): the stiffness k = 1 / (t_c^2 z^2) per unit of
        effective mass (z the damping ratio), so about the duration of a
        contact episode.  Small is stiff.
    damping_ratio : float
        Damping ratio of the contact's spring-damper [-] (``solref[1]``):
        1 is critical (the landing edge does not bounce), below 1 it
        bounces, above 1 it sinks in slowly.
    impedance : (float, float, float)
        MuJoCo's ``solimp`` (d0, d_width, width [m]): the share of the
        constraint force that is enforced at zero and at ``width`` of
        penetration.  Close to 1: a hard contact.
    mu : float
        Coulomb friction coefficient of the base [-] (elliptic cone): below
        the horizontal impulse an impact needs, the base slides.
    edge_radius_mm : float
        Radius of the rounded base edges [mm] (the contact is a sphere of
        this radius at each edge).
    edge_inset_mm : float
        How far the edges are set in from the faces [mm]: a crushed or
        indented hinge.  The block rocks on alpha_r = atan((b/2 - inset - r)
        / (h/2 - r)) while its mass and inertia stay the whole block's.
    zeta : float
        Viscous damping in flight [-]: a moment -2 zeta p I_O thetadot on the
        rotation (a damper on the hinge joint), the deceleration
        -2 zeta p thetadot of :mod:`rocklab.diagnosis.causes.flight_damping`
        with p of the block on its edges.
    timestep_s : float
        Longest integration step [s]; the step used divides 1/fs and is at
        most a tenth of ``contact_time_s``.
    """

    contact_time_s: float = 0.002
    damping_ratio: float = 1.0
    impedance: tuple[float, float, float] = (0.99, 0.999, 0.001)
    mu: float = 0.8
    edge_radius_mm: float = 0.5
    edge_inset_mm: float = 0.0
    zeta: float = 0.0
    timestep_s: float = 2e-4


@dataclass(frozen=True)
class ContactHistory:
    """Free rocking of a block on compliant contacts, on the integration grid.

    Attributes
    ----------
    t : ndarray
        Time from the release [s].
    theta, thetadot : ndarray
        Rotation of the block and its rate [rad, rad/s]; theta > 0 leans on
        the +y edge, as in the lab's kinematics.
    y, z, vy, vz : ndarray
        Position [m] and velocity [m/s] of the centre of mass.
    force : ndarray (n, 2)
        Normal force on the -y and the +y edge [N].
    energy : ndarray
        Kinetic plus potential energy of the block [J] (potential from the
        base), the springs' stored energy left out.
    mass, inertia : float
        Mass [kg] and moment of inertia about the centre of mass [kg m^2].
    edges : ndarray (2, 2)
        Centres (y, z) of the -y and +y edges' spheres in the block [m].
    edge_radius : float
        Their radius [m].
    rocking_angle, p : float
        alpha_r [rad] and p = sqrt(m g R / I_O) [rad/s] of the block on its edges.
    step : int
        Integration steps per sample of the record.
    rest_index : int or None
        First step from which the wall stays at rest.
    """

    t: np.ndarray
    theta: np.ndarray
    thetadot: np.ndarray
    y: np.ndarray
    z: np.ndarray
    vy: np.ndarray
    vz: np.ndarray
    force: np.ndarray
    energy: np.ndarray
    mass: float
    inertia: float
    edges: np.ndarray
    edge_radius: float
    rocking_angle: float
    p: float
    step: int
    rest_index: int | None


def rocking_angle(height_m: float, thickness_m: float, model: ContactModel = ContactModel()) -> float:
    """The angle alpha_r the block rocks on [rad]: its centre of mass above a rounded edge's centre."""
    r, inset = model.edge_radius_mm / 1e3, model.edge_inset_mm / 1e3
    return float(np.arctan2(thickness_m / 2 - inset - r, height_m / 2 - r))


def housner_of_block(height_m: float, thickness_m: float, model: ContactModel = ContactModel()) -> float:
    """Housner's e of the block as built, Eq. 1 on its edges [-].

    Angular momentum about the landing edge is conserved
    (:func:`rocklab.physics.restitution.two_sided_asymmetric`, Eq. 1
    generalised), with the edges at b/2 - inset - r from the centre and the
    inertia of the whole block, I_G = m (h^2 + b^2) / 12; with no inset and
    sharp edges this is Eq. 2, 1 - 3/2 sin^2 alpha.
    """
    half = thickness_m / 2 - (model.edge_inset_mm + model.edge_radius_mm) / 1e3
    k_g = np.sqrt((height_m**2 + thickness_m**2) / 12.0)
    return float(restitution.two_sided_asymmetric(half, half, height_m / 2, k_g))


def _xml(h: float, b: float, mass: float, inertia: float, model: ContactModel, dt: float, damping: float) -> str:
    r, inset = model.edge_radius_mm / 1e3, model.edge_inset_mm / 1e3
    ey, ez = b / 2 - inset - r, -h / 2 + r
    d0, dw, width = model.impedance
    contact = (
        f'friction="{model.mu!r} 0 0" solref="{model.contact_time_s!r} {model.damping_ratio!r}" '
        f'solimp="{d0!r} {dw!r} {width!r}" condim="3"'
    )
    # the hinge's axis is -x so that theta > 0 tips the top towards +y, onto the +y edge (the lab's sign)
    return f"""<mujoco model="rocking block">
  <option timestep="{dt!r}" gravity="0 0 {-G!r}" integrator="Euler" cone="elliptic"/>
  <worldbody>
    <geom name="base" type="plane" size="10 10 0.1" {contact}/>
    <body name="wall" pos="0 0 {h / 2!r}">
      <joint name="y" type="slide" axis="0 1 0"/>
      <joint name="z" type="slide" axis="0 0 1"/>
      <joint name="theta" type="hinge" axis="-1 0 0" damping="{damping!r}"/>
      <inertial pos="0 0 0" mass="{mass!r}" diaginertia="{inertia!r} {inertia!r} {inertia!r}"/>
      <geom name="minus" type="sphere" size="{r!r}" pos="0 {-ey!r} {ez!r}" {contact}/>
      <geom name="plus" type="sphere" size="{r!r}" pos="0 {ey!r} {ez!r}" {contact}/>
    </body>
  </worldbody>
</mujoco>"""


def simulate_contact(
    height_m: float,
    thickness_m: float,
    theta0: float,
    thetadot0: float = 0.0,
    model: ContactModel = ContactModel(),
    *,
    fs: float = 400.0,
    t_end: float = 40.0,
    mass_kg: float = 100.0,
    hold_s: float = 0.3,
    rest_fraction: float = 1e-5,
) -> ContactHistory:
    """Free rocking of a rigid block on two compliant edges, released from ``theta0``.

    The block is first held at ``theta0`` on its edge while the contact
    settles (``hold_s``: the screw of the lab), then released with angular
    velocity ``thetadot0`` about that edge.

    Parameters
    ----------
    height_m, thickness_m : float
        The block [m].
    theta0, thetadot0 : float
        Release rotation [rad] and rate [rad/s].
    model : ContactModel
    fs : float
        Sampling rate of the record the motion is for [Hz].
    t_end : float
        Longest free rocking simulated [s].
    mass_kg : float
        Mass of the block [kg]: the contact's parameters are per unit of
        effective mass, so it changes only the forces.
    hold_s : float
        Settling before the release [s].
    rest_fraction : float
        The wall is at rest once its rocking energy above the upright,
        (1/2) I_O thetadot^2 + m g R (cos(alpha_r - |theta|) - cos alpha_r),
        stays below this fraction of its initial value [-].

    Returns
    -------
    ContactHistory
    """
    mj = _mujoco()
    h, b = float(height_m), float(thickness_m)
    inertia = mass_kg * (h**2 + b**2) / 12.0
    k = max(int(np.ceil(1.0 / (fs * min(model.timestep_s, model.contact_time_s / 10.0)))), 1)
    dt = 1.0 / (fs * k)
    alpha_r = rocking_angle(h, b, model)
    r = model.edge_radius_mm / 1e3
    big_r = float(np.hypot(b / 2 - model.edge_inset_mm / 1e3 - r, h / 2 - r))
    i_o = inertia + mass_kg * big_r**2
    p = float(np.sqrt(mass_kg * G * big_r / i_o))
    m_def = mj.MjModel.from_xml_string(_xml(h, b, mass_kg, inertia, model, dt, 2 * model.zeta * p * i_o))
    d = mj.MjData(m_def)
    edges = (m_def.geom("minus").id, m_def.geom("plus").id)
    sgn = 1.0 if theta0 >= 0 else -1.0
    pivot = edges[1] if sgn > 0 else edges[0]

    # lean the block on its edge: the sphere's lowest point on the base
    d.qpos[2] = theta0
    mj.mj_kinematics(m_def, d)
    c = d.geom_xpos[pivot]
    d.qpos[1] += r - c[2]
    d.qpos[0] -= c[1] - sgn * (b / 2 - model.edge_inset_mm / 1e3 - r)
    mj.mj_forward(m_def, d)
    for _ in range(int(round(hold_s / dt))):
        d.qpos[2], d.qvel[2] = theta0, 0.0
        mj.mj_step(m_def, d)
    d.qpos[2] = theta0
    mj.mj_forward(m_def, d)
    # released about the contact point: v = omega x (centre - pivot), omega along -x
    c = d.geom_xpos[pivot] - np.array([0.0, 0.0, r])
    d.qvel[:] = [thetadot0 * (d.qpos[1] - c[2]), -thetadot0 * (d.qpos[0] - c[1]), thetadot0]
    mj.mj_forward(m_def, d)

    n_max = int(np.ceil(t_end * fs)) * k + 1
    out = np.empty((n_max, 9))
    f6 = np.zeros(6)

    def rocking_energy(i: int) -> float:
        th, thd = abs(out[i, 1]), out[i, 2]
        return 0.5 * i_o * thd**2 + mass_kg * G * big_r * (np.cos(alpha_r - min(th, alpha_r)) - np.cos(alpha_r))

    e0, below, rest, n = 0.0, 0, None, n_max
    need = int(round(0.5 * fs)) * k  # half a second at rest
    for i in range(n_max):
        if i:
            mj.mj_step(m_def, d)
        fn = [0.0, 0.0]
        for j in range(d.ncon):
            con = d.contact[j]
            mj.mj_contactForce(m_def, d, j, f6)
            g = con.geom2 if con.geom1 == 0 else con.geom1
            fn[edges.index(g)] += f6[0]
        out[i] = (i * dt, d.qpos[2], d.qvel[2], d.qpos[0], d.qpos[1], d.qvel[0], d.qvel[1], *fn)
        e = rocking_energy(i)
        e0 = e0 or max(e, 1e-300)
        below = below + 1 if e < rest_fraction * e0 else 0
        if below == 1:
            rest = i
        if below >= need and i % k == 0:
            n = i + 1
            break
    out = out[:n]
    vy, vz = out[:, 5], out[:, 6]
    energy = 0.5 * mass_kg * (vy**2 + vz**2) + 0.5 * inertia * out[:, 2] ** 2 + mass_kg * G * out[:, 4]
    ey = b / 2 - model.edge_inset_mm / 1e3 - r
    return ContactHistory(
        t=out[:, 0],
        theta=out[:, 1],
        thetadot=out[:, 2],
        y=out[:, 3],
        z=out[:, 4],
        vy=vy,
        vz=vz,
        force=out[:, 7:9],
        energy=energy,
        mass=mass_kg,
        inertia=inertia,
        edges=np.array([[-ey, -h / 2 + r], [ey, -h / 2 + r]]),
        edge_radius=r,
        rocking_angle=alpha_r,
        p=p,
        step=k,
        rest_index=rest if below else None,
    )


def edge_velocity(hist: ContactHistory, edge: int) -> np.ndarray:
    """Velocity (vy, vz) of the lowest point of an edge's sphere [m/s], shape (n, 2).

    Zero when the block turns freely about that edge (no slip, no
    compression of the contact).
    """
    py, pz = hist.edges[edge]
    c, s_ = np.cos(hist.theta), np.sin(hist.theta)
    # body -> world for a rotation theta about -x: y' = y cos + z sin, z' = -y sin + z cos
    ry, rz = py * c + pz * s_, -py * s_ + pz * c - hist.edge_radius
    return np.column_stack([hist.vy + hist.thetadot * rz, hist.vz - hist.thetadot * ry])


def _edge_y(hist: ContactHistory, edge: int) -> np.ndarray:
    py, pz = hist.edges[edge]
    return np.asarray(hist.y + py * np.cos(hist.theta) + pz * np.sin(hist.theta))


def speed_at_upright(hist: ContactHistory, index: int) -> float:
    """thetadot at theta = 0 of the rigid flight through a step [rad/s], Eq. (energy about the edge).

    (1/2) thetadot^2 + p^2 cos(alpha_r - |theta|) is constant in a flight
    about an edge (the block on a rigid pivot, no loss), so thetadot(0)^2 =
    thetadot^2 + 2 p^2 (cos(alpha_r - |theta|) - cos alpha_r); the sign is
    thetadot's.  It takes out what gravity did between theta = 0 and the
    step, so that e does not depend on where an episode is said to end.
    """
    th, thd = abs(hist.theta[index]), hist.thetadot[index]
    a, p = hist.rocking_angle, hist.p
    return float(np.sign(thd) * np.sqrt(thd**2 + 2 * p**2 * (np.cos(a - th) - np.cos(a))))


def contact_episodes(hist: ContactHistory, min_apex_rad: float = 0.0, tolerance: float = 1e-3) -> pd.DataFrame:
    """The impacts of a history, each measured across its contact episode.

    An impact is a change of sign of theta.  Its episode starts at the
    first step after the last apex at which the edge it lands on carries
    load, and ends once the block turns freely about that edge: the edge
    left carries no load again before the next apex, and the landing edge's
    lowest point moves at less than ``tolerance`` |thetadot| R for a
    contact time (:func:`edge_velocity`).  Within it the load passes from
    one edge to the other, through bounces, a lift of both edges or a
    slip.  The speeds just before and just after, each carried to theta = 0
    along its rigid flight (:func:`speed_at_upright`), give e =
    thetadot^+ / thetadot^-, Eq. 1's ratio: what the wall lost, whatever
    lost it.

    Parameters
    ----------
    hist : ContactHistory
    min_apex_rad : float
        Impacts between apexes below this [rad] are left out (the wall
        settling on its contacts is no rocking).
    tolerance : float
        Speed of the landing edge's contact point, over |thetadot| R, below
        which the block turns freely about it [-].

    Returns
    -------
    DataFrame
        ``t`` (theta = 0, linear between steps) [s from release],
        ``thetadot_before``, ``thetadot_after`` (at theta = 0) [rad/s],
        ``e`` [-], ``t_start``, ``t_end`` [s], ``duration_s`` of the
        episode, ``lifted`` (both edges off the base at some step of it),
        ``slip_mm`` (sliding of the landing edge across it, from touch-down), ``apex_before``,
        ``apex_after`` [rad].
    """
    th, force = hist.theta, hist.force
    n = len(th)
    thr = 1e-6 * hist.mass * G
    big_r = float(np.hypot(*hist.edges[1]))
    dt = float(hist.t[1] - hist.t[0])
    window = max(int(np.ceil(hist.step)), 3)
    # each edge's motion once: per impact, on the whole history, it took 2/3 of a slender wall's test
    vel = [np.hypot(*edge_velocity(hist, e).T) for e in (0, 1)]
    edge_y = [_edge_y(hist, e) for e in (0, 1)]
    cross = np.flatnonzero(th[:-1] * th[1:] < 0)
    bounds = np.r_[0, cross + 1, n]
    apex = [int(lo) + int(np.argmax(np.abs(th[lo:hi]))) for lo, hi in zip(bounds[:-1], bounds[1:])]
    rows = []
    for k, i in enumerate(cross.tolist()):
        a0, a1 = apex[k], apex[k + 1]
        if min(abs(th[a0]), abs(th[a1])) < min_apex_rad:
            continue
        new = 1 if th[i + 1] > 0 else 0
        on = np.flatnonzero(force[a0 : i + 2, new] > thr)
        start = max(a0 + int(on[0]) - 1 if on.size else i, 0)
        off = np.flatnonzero(force[i : a1 + 1, 1 - new] > thr)
        first = i + int(off[-1]) + 1 if off.size else i + 1
        speed = vel[new][first : a1 + 1]
        still = speed <= tolerance * np.abs(hist.thetadot[first : a1 + 1]) * big_r
        # the first step from which the landing edge stays still for a window
        # none where the edge left still carries load at the next apex (a creeping soft contact)
        run = np.convolve(still, np.ones(window), "valid") >= window if still.size >= window else still[:0]
        end = min(first + int(np.argmax(run)) if run.any() else a1, n - 1)
        before, after = speed_at_upright(hist, start), speed_at_upright(hist, end)
        seg = slice(start, end + 1)
        rows.append(
            {
                "t": hist.t[i] + dt * th[i] / (th[i] - th[i + 1]),
                "thetadot_before": before,
                "thetadot_after": after,
                "e": after / before,
                "t_start": hist.t[start],
                "t_end": hist.t[end],
                "duration_s": hist.t[end] - hist.t[start],
                "lifted": bool(np.any((force[seg] <= thr).all(axis=1))),
                "slip_mm": 1e3 * float(np.diff(edge_y[new][[start, end]])[0]),
                "apex_before": abs(th[a0]),
                "apex_after": abs(th[a1]),
            }
        )
    cols = ["t", "thetadot_before", "thetadot_after", "e", "t_start", "t_end", "duration_s", "lifted", "slip_mm"]
    return pd.DataFrame(rows, columns=[*cols, "apex_before", "apex_after"])


def flight_zeta(hist: ContactHistory, ep: pd.DataFrame, min_apex_rad: float = 0.0) -> np.ndarray:
    """The viscous zeta that would lose what each flight between two contact episodes loses [-].

    A moment -2 zeta p I_O thetadot takes dE/dt = -2 zeta p I_O thetadot^2,
    so a flight that leaves one episode at thetadot_a and reaches the next at
    thetadot_b (both carried to theta = 0, :func:`speed_at_upright`) loses
    what zeta = (thetadot_a^2 - thetadot_b^2) / (4 p int thetadot^2 dt) would:
    the knob ``zeta`` and the pivot's spring-damper alike, read on the scale
    of :mod:`rocklab.diagnosis.causes.flight_damping`.  Flights of apex
    below ``min_apex_rad`` [rad] are left out.
    """
    out = []
    for a, b in zip(ep.iloc[:-1].itertuples(), ep.iloc[1:].itertuples()):
        if a.apex_after < min_apex_rad:
            continue
        lo, hi = np.searchsorted(hist.t, [a.t_end, b.t_start])
        work = np.trapezoid(hist.thetadot[lo : hi + 1] ** 2, hist.t[lo : hi + 1])
        out.append((a.thetadot_after**2 - b.thetadot_before**2) / (4 * hist.p * work))
    return np.asarray(out, float)


def base_sliding_mm(hist: ContactHistory, height_m: float, thickness_m: float) -> np.ndarray:
    """The lab's sliding w of the base [mm]: where the active edge's corner is, less where it stood.

    The lab's kinematics (:func:`rocklab.lab.kinematics.transducer_elongation`)
    turns the wall about its corner y = sign(theta) b/2 on the base and moves
    it by w along y; this w puts that corner where the block has it, so the
    transducers see the block's motion but for the corner's height (the
    contact's penetration and the lift of a rounded or set-in edge,
    micrometres).
    """
    ey = np.where(hist.theta >= 0, 1.0, -1.0) * thickness_m / 2
    corner_y = hist.y + np.cos(hist.theta) * ey - np.sin(hist.theta) * height_m / 2
    return np.asarray(1e3 * (corner_y - ey))


def contact_model_of(test: Any, height_m: float, thickness_m: float) -> ContactModel:
    """The :class:`ContactModel` of a virtual test: its ``model`` keywords, and its ``alpha_ratio`` as an inset.

    A test with an ``alpha_ratio`` (the rocking angle over the nominal
    alpha) has its edges set in until the block rocks on that angle
    (:func:`rocking_angle`); without one, the edges are where ``model`` puts them.
    """
    model = ContactModel(**test.model)
    if test.alpha_ratio is not None:
        r = model.edge_radius_mm / 1e3
        target = test.alpha_ratio * float(wall.slenderness_angle(height_m, thickness_m))
        inset = thickness_m / 2 - r - np.tan(target) * (height_m / 2 - r)
        model = ContactModel(**{**asdict(model), "edge_inset_mm": 1e3 * float(inset)})
    return model


def simulate_contact_test(
    test: Any,
    specimen: Mapping[str, Any],
    layout: pd.DataFrame,
    rng: np.random.Generator | int | None = None,
    t_end: float = 40.0,
) -> tuple[np.ndarray, Any, dict[str, Any]]:
    """Simulate one virtual test on compliant contacts and record it as the virtual lab does.

    The ``simulate`` of :func:`rocklab.lab.virtual_lab.write_campaign`: a
    :class:`rocklab.lab.virtual_lab.VirtualTest` whose ``model`` holds the
    keywords of :class:`ContactModel` (``alpha_ratio``, if given, sets the
    edges' inset: :func:`contact_model_of`); the release (``theta0_ratio``
    of the block's rocking angle, ``release_ratio`` of Eq. 16's velocity),
    the instrument, its effects and faults are the virtual lab's
    (:func:`rocklab.lab.virtual_lab.record_virtual_test`).  The base's
    sliding is the block's (:func:`base_sliding_mm`), not the effects'
    random slips.

    Returns
    -------
    t, readings, truth
        As :func:`rocklab.lab.virtual_lab.simulate_virtual_test`: ``e_true``
        the median of the e measured across the contact episodes
        (:func:`contact_episodes`), ``impacts`` those episodes (``t`` from
        the record's start), ``e_analytic`` Eq. 2 at the nominal alpha, and
        ``columns`` the contact's knobs and measures for truth.csv.
    """
    from rocklab.lab.virtual_lab import record_virtual_test

    rng = np.random.default_rng(rng)
    if test.boundary != Boundary.TWO_SIDED:
        raise ValueError("the contact lab builds free-standing (two-sided) walls only")
    h, b, length = (float(specimen[k]) / 1e3 for k in ("height_mm", "thickness_mm", "length_mm"))
    model = contact_model_of(test, h, b)
    mass = float(specimen["unit_weight_kN_m3"]) * 1e3 * length * h * b / G
    alpha = float(wall.slenderness_angle(h, b))
    alpha_r = rocking_angle(h, b, model)
    p = float(wall.frequency_parameter(wall.half_diagonal(h, b)))
    w_r = float(wall.overturning_velocity(alpha, p))
    sgn = 1.0 if test.direction == "push" else -1.0
    thetadot0 = -sgn * test.release_ratio * w_r
    hist = simulate_contact(
        h, b, sgn * test.theta0_ratio * alpha_r, thetadot0, model, fs=test.fs, mass_kg=mass, t_end=t_end
    )
    ep = contact_episodes(hist, min_apex_rad=1e-3 * alpha_r)
    k = hist.step
    t_rest = hist.t[hist.rest_index] if hist.rest_index is not None else float(hist.t[-1])
    t, E, truth = record_virtual_test(
        test,
        specimen,
        layout,
        hist.t[::k],
        hist.theta[::k],
        rng,
        impacts=ep[["t", "thetadot_before"]],
        t_rest=float(t_rest),
        w_free=base_sliding_mm(hist, h, b)[::k],
    )
    e = ep["e"].to_numpy(float)
    e_block = housner_of_block(h, b, model)
    truth.update(
        {
            "alpha": alpha,
            "alpha_rock": alpha_r,
            "alpha_neg": alpha_r,
            "p": hist.p,
            "overturning_velocity": w_r,
            "thetadot0": thetadot0,
            "impact_law": "contact (MuJoCo)",
            "zeta": model.zeta,
            # the rocking model's knobs with no counterpart here: no hinge friction moment, drag, gap or form
            "hinge_rounding": np.nan,
            "mu": 0.0,
            "kappa": 0.0,
            "gap": 0.0,
            "form": "contact",
            "e_first": float(e[0]) if e.size else np.nan,
            "e_true": float(np.median(e)) if e.size else np.nan,
            "impacts": pd.DataFrame(
                {"t": ep["t"].to_numpy(float) + truth["t_release"], "e": e, "thetadot_before": ep["thetadot_before"]}
            ),
            "episodes": ep,
            "e_analytic": float(restitution.two_sided(alpha)),
            "n_impacts": int(len(ep)),
            "overturned": bool(abs(hist.theta[-1]) > alpha_r),
            "columns": {
                "generator": "contact_lab",
                "contact_time_s": model.contact_time_s,
                "damping_ratio": model.damping_ratio,
                "impedance": " ".join(f"{x:g}" for x in model.impedance),
                "contact_mu": model.mu,
                "edge_radius_mm": model.edge_radius_mm,
                "edge_inset_mm": model.edge_inset_mm,
                "e_housner_block": e_block,
                "restitution_scale": float(np.median(e)) / e_block if e.size else np.nan,
                "n_lifted": int(ep["lifted"].sum()),
                # on the flights the diagnosis reads a flight loss on (flight_damping.LONG_FLIGHT of alpha)
                "zeta_flight": float(np.median(zf)) if (zf := flight_zeta(hist, ep, 0.3 * alpha_r)).size else np.nan,
                "max_slip_mm": float(ep["slip_mm"].abs().max()) if len(ep) else 0.0,
            },
        }
    )
    return t, E, truth


def housner_table(
    slenderness: tuple[float, ...] = (14.4, 10.4, 9.6, 6.5, 4.0),
    contact_times_s: tuple[float, ...] = (5e-4, 2e-3, 1e-2),
    height_m: float = 1.09,
    t_end: float = 3.0,
) -> pd.DataFrame:
    """e measured on the block against Housner's Eq. 2, across slenderness and contact stiffness.

    Each block (h/b of the campaign's specimens, Table 2, and a stocky
    one) is released at 0.9 of its rocking angle on near-sharp edges
    (0.05 mm) with a critically damped contact of each time constant, and
    its first impacts measured (:func:`contact_episodes`).

    Returns
    -------
    DataFrame
        ``h_over_b``, ``contact_time_s``, ``e_eq2`` (Eq. 2), ``e`` (median
        of the impacts in ``t_end``), ``loss_ratio`` ((1 - e) / (1 - e_eq2)),
        ``n_impacts``, ``lifted`` (impacts during which both edges left the base).
    """
    rows = []
    for hb in slenderness:
        b = height_m / hb
        e_an = float(restitution.two_sided(wall.slenderness_angle(height_m, b)))
        for tc in contact_times_s:
            model = ContactModel(contact_time_s=tc, edge_radius_mm=0.05)
            hist = simulate_contact(height_m, b, 0.9 * rocking_angle(height_m, b, model), model=model, t_end=t_end)
            ep = contact_episodes(hist)
            e = float(ep["e"].median())
            rows.append(
                {
                    "h_over_b": hb,
                    "contact_time_s": tc,
                    "e_eq2": e_an,
                    "e": e,
                    "loss_ratio": (1 - e) / (1 - e_an),
                    "n_impacts": len(ep),
                    "lifted": int(ep["lifted"].sum()),
                }
            )
    return pd.DataFrame(rows)


if __name__ == "__main__":  # python -m rocklab.lab.contact_lab: the table of the changelog and the docs
    print(housner_table().to_string(index=False, float_format=lambda x: f"{x:.4g}"))
