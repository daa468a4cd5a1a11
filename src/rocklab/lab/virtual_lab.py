"""A virtual rocking-wall laboratory: simulated walls written as a campaign, with the truth beside it.

A campaign is a plan of :class:`VirtualTest` (the specimen, the boundary,
the wall's physics as any model of the simulator, the release, disturbed
or not, the instrument effects and faults of :mod:`rocklab.lab.virtual_record`);
:func:`simulate_virtual_test` runs one with
:func:`rocklab.simulation.reference.simulate_free` and records it
(:func:`record_virtual_test`, the seam where any simulated motion becomes a
record: :mod:`rocklab.lab.contact_lab` plugs in there),
:func:`write_campaign` writes the folder in the lab's format
(``docs/raw-format.md``) plus ``truth.csv``, so that each stage of the
reduction can be tested on data in which effects were hidden on purpose;
:func:`expected_verdict` is the verdict the lab's rules must give a test;
:func:`default_plan` is a campaign that looks like the real one;
:func:`series_records` gives the records of one series reduced to theta,
as the diagnosis reads them, without writing a campaign.  Every
effect is a knob that can be switched off, and everything is driven by one
seed.

Lengths of the record in mm, dynamics in SI (m, s, rad).

Size: the plan, the simulation, the recording seam and the campaign folder are
one pipeline whose truth columns each part adds to; the instruments, effects and
native files already live in their own modules.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd

from rocklab.lab.validity import (
    MAX_LOST_OUT_OF_PLANE,
    RELEASE_VELOCITY_RATIO,
    RESIDUAL_TOP_MM,
    Verdict,
    channel_roles,
)
from rocklab.lab.virtual_instruments import (
    InertialEffects,
    RotationEffects,
    inertial_readings,
    instrument_fault,
    rotation_readings,
    sensor_point,
    write_instrument_record,
)
from rocklab.lab.virtual_native import MarkerEffects, VideoEffects, write_c3d, write_tdms, write_video
from rocklab.lab.virtual_record import (
    LOSING_FAULTS,
    Effects,
    Fault,
    record_from_motion,
    transducer_geometry,
    usual_layout,
    write_record,
)
from rocklab.physics import restitution, wall
from rocklab.physics.boundary import Boundary

#: The instruments whose file holds the transducers of a setup: the text record and LabVIEW's TDMS.
TRANSDUCER_FILES = ("transducers", "tdms")
#: The file extension of each instrument's record (a filmed test: :attr:`VideoEffects.extension`).
EXTENSIONS = {"tdms": ".tdms", "c3d": ".c3d"}

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
        ``zeta``, ``mu``, ``kappa``, ``gap``,
        ``form``, ``hinge_rounding``, ...), every physical effect of the
        simulator; ``alpha_rock`` defaults to alpha_ratio * alpha.  With dry
        friction mu, release below (1 - mu / alpha) of the rocking angle: a
        wall the friction holds at its release never rocks, and is refused
        (ValueError).
    faults : list of Fault
    effects : Effects
    note : str
        Operator's note written in tests.csv.
    log : dict
        Further columns of the test's row of tests.csv (column -> value: a
        date, a temperature the operator wrote, ...).
    instrument : {'transducers', 'rotation', 'inertial', 'tdms', 'c3d', 'video'}
        What records the test (:mod:`rocklab.lab.virtual_instruments`, and
        the native files of :mod:`rocklab.lab.virtual_native`): the same
        true motion whatever it is.  A test without transducers has no
        setup; its ``faults`` are of
        :data:`rocklab.lab.virtual_instruments.INSTRUMENT_FAULTS` (C3D and
        video: ``unreadable`` only); a TDMS test has the transducers' faults.
    rotation, inertial : RotationEffects, InertialEffects
        What the motion-capture system and the inertial sensor do to the motion.
    markers, video : MarkerEffects, VideoEffects
        What a C3D file's motion capture and a filmed test's camera do.
    """

    test_id: str
    specimen: str = "1a"
    boundary: str = Boundary.TWO_SIDED
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
    instrument: str = "transducers"
    rotation: RotationEffects = field(default_factory=RotationEffects)
    inertial: InertialEffects = field(default_factory=InertialEffects)
    markers: MarkerEffects = field(default_factory=MarkerEffects)
    video: VideoEffects = field(default_factory=VideoEffects)

    @property
    def file(self) -> str:
        """The test's record, relative to the campaign folder."""
        ext = self.video.extension if self.instrument == "video" else EXTENSIONS.get(self.instrument, ".csv.gz")
        return f"tests/{self.test_id}{ext}"

    @property
    def setup(self) -> str:
        """The transducer setup of the test (none for the other instruments)."""
        if self.instrument not in TRANSDUCER_FILES:
            return ""
        bc = "2s" if self.boundary == Boundary.TWO_SIDED else f"1s-cd{self.contact_depth_mm:g}"
        return f"S-{self.specimen}-{bc}"


def expected_verdict(faults, layout, thickness_mm, release_ratio, residual_top_mm, instrument="transducers"):
    """Verdict the lab's rules give a test, from what was injected.

    A rotation or inertial test is lost by a dead or clipped instrument, whatever its ``layout``.

    Returns
    -------
    (Verdict, str)
        The verdict (valid, or the first of :meth:`Verdict.rejections` that applies)
        and its explanation.
    """
    if any(f.kind == "unreadable" for f in faults):
        return Verdict.UNREADABLE, "file truncated"
    if instrument not in TRANSDUCER_FILES:
        lost = [f.kind for f in faults if f.kind in LOSING_FAULTS]
        if lost:
            return Verdict.INSTRUMENT_MALFUNCTION, f"{instrument} instrument {lost[0]}"
    else:
        roles = channel_roles(layout, thickness_mm)
        oop = set(roles.channel[roles.role == "out_of_plane"])
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


def record_virtual_test(
    test: VirtualTest,
    specimen,
    layout,
    t_free,
    theta_free,
    rng: np.random.Generator,
    *,
    impacts: pd.DataFrame | None = None,
    t_rest: float | None = None,
    w_free: np.ndarray | None = None,
):
    """Record a free motion as ``test`` says: the seam between a wall's physics and the lab.

    Whatever simulated the wall (the reference simulator of
    :func:`simulate_virtual_test`, the contact mechanics of
    :mod:`rocklab.lab.contact_lab`), its free rocking goes through the same
    protocol, instruments, effects and faults here.

    Parameters
    ----------
    test : VirtualTest
    specimen : Mapping
        Row of specimens.csv (mm).
    layout : DataFrame
        setups.csv rows of the test's setup.
    t_free, theta_free : ndarray
        Free rocking from the release on the grid 1/test.fs [s, rad].
    rng : numpy.random.Generator
    impacts : DataFrame, optional
        ``t`` [s from release] and ``thetadot_before`` [rad/s] of each impact (ringing).
    t_rest : float, optional
        Time from release at which the wall is at rest [s].
    w_free : ndarray, optional
        Sliding of the base along y [mm]; default the ``effects``' random slips.

    Returns
    -------
    t, readings, truth
        As :func:`record_from_motion`, truth with the expected verdict
        (``expected_reason``, ``expected_detail``, ``expected_valid``).
    """
    E: np.ndarray | dict[str, np.ndarray]  # the transducers' readings, or an instrument's by quantity
    t, E, truth = record_from_motion(
        t_free,
        theta_free,
        test.fs,
        layout,
        specimen,
        w_free=w_free,
        impacts=impacts,
        t_rest=t_rest,
        effects=test.effects,
        faults=test.faults if test.instrument in TRANSDUCER_FILES else (),
        residual_top_mm=test.residual_top_mm,
        residual_kind=test.residual_kind,
        rng=rng,
    )
    reason, why = expected_verdict(
        test.faults, layout, specimen["thickness_mm"], test.release_ratio, truth["residual_top_mm"], test.instrument
    )
    if test.instrument == "rotation":
        E = rotation_readings(t, truth["theta"], truth["phi"], truth["v"], truth["w"], test.rotation, rng)
    elif test.instrument == "inertial":
        truth["sensor_mm"] = sensor_point(specimen, test.inertial)
        E, truth["gyro_bias_rad_s"] = inertial_readings(
            t, truth["theta"], truth["sensor_mm"], specimen["thickness_mm"], test.inertial, rng
        )
    for f in test.faults if test.instrument in ("rotation", "inertial") else ():
        assert isinstance(E, dict)  # an instrument's readings
        instrument_fault(E, f.kind, rng, f.level)
    truth.update({"expected_reason": reason, "expected_detail": why, "expected_valid": reason == "valid"})
    return t, E, truth


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
    from rocklab.simulation.reference import simulate_free
    from rocklab.simulation.rocking_model import RockingModel

    rng = np.random.default_rng(rng)
    h, b = specimen["height_mm"] / 1e3, specimen["thickness_mm"] / 1e3
    one = test.boundary == Boundary.ONE_SIDED
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
    if hist.t_rest == 0.0 and theta0 != 0.0:
        # the simulator holds it (rocklab.simulation.reference): a test of a wall that never rocks
        # has no truth the lab's rules could be checked against
        raise ValueError(
            f"test {test.test_id}: released at {test.theta0_ratio:g} of its rocking angle, the wall is held there "
            f"by the dry friction of its model (mu = {model.mu:g}, sin(alpha - |theta0|) <= mu): release it "
            f"below {1.0 - model.mu / a_side:.4g} of it"
        )
    t_rest = hist.t_rest if hist.t_rest is not None else float(hist.t[-1])
    t, E, truth = record_virtual_test(
        test,
        specimen,
        layout,
        hist.t,
        np.nan_to_num(hist.theta, nan=np.nanmax(np.abs(hist.theta)) * sgn),
        rng,
        impacts=hist.impacts,
        t_rest=t_rest,
    )
    imp = hist.impacts
    base = imp[imp["kind"] == "base"] if len(imp) else imp
    ratios = (base["thetadot_after"] / base["thetadot_before"]).to_numpy() if len(base) else np.array([])
    # a one-sided wall with a gap rocks on the base impacts of Eq. 2
    e_an = restitution.analytic(Boundary.ONE_SIDED if one and model.gap == 0 else Boundary.TWO_SIDED, alpha)
    truth.update(
        {
            "alpha": alpha,
            "alpha_rock": model.alpha_pos,
            "alpha_neg": model.alpha_minus,
            "p": model.p,
            "overturning_velocity": w_r,
            "thetadot0": thetadot0,
            "impact_law": _law_name(model.impact) or "default",
            "zeta": model.zeta,
            "hinge_rounding": model.hinge_rounding,
            "mu": model.mu,
            "kappa": model.kappa,
            "gap": model.gap,
            "form": model.form,
            "e_first": float(ratios[0]) if ratios.size else np.nan,
            "e_true": float(np.median(ratios)) if ratios.size else np.nan,
            "impacts": pd.DataFrame(
                {
                    "t": base["t"].to_numpy(float) + truth["t_release"],
                    "e": ratios,
                    "thetadot_before": base["thetadot_before"].to_numpy(float),
                }
                if len(base)
                else {"t": [], "e": [], "thetadot_before": []}
            ),
            "e_analytic": float(e_an),
            "n_impacts": int(len(imp)),
            "overturned": bool(hist.overturned),
        }
    )
    return t, E, truth


def series_records(
    name,
    specimen,
    boundary,
    model,
    *,
    n=6,
    fs=400.0,
    alpha_ratio=1.0,
    noise_mm=0.002,
    pull=False,
    theta0_range=(0.97, 0.998),
    contact_depth_mm=120.0,
    seed=0,
    log=None,
    t_end=60.0,
    simulate=None,
):
    """Records of ``n`` virtual tests of one series, reduced to theta by the kinematics.

    The records :func:`rocklab.diagnosis.diagnose_records` reads, made
    without a campaign on disk: each test simulated
    (:func:`simulate_virtual_test`, noise and hum of ``noise_mm`` on every
    channel) in the usual layout of ``specimen`` (a row of specimens.csv
    with its name), and theta solved from the five rigid-body channels.

    Parameters
    ----------
    model : dict or callable
        ``VirtualTest.model``, or test index -> model (a law that changes
        between tests).
    fs : float
        Sampling rate [Hz].
    alpha_ratio : float or callable
        ``VirtualTest.alpha_ratio`` (the rocking angle over the nominal alpha), or test index -> it: a
        rocking edge that changes within the series (a corner crushed after some test).
    pull : bool
        Every other test released towards the other hinge (two-sided).
    theta0_range : tuple
        Release rotation over the rocking angle, drawn uniformly per test.
    contact_depth_mm : float
        One-sided walls only.
    log : dict, optional
        The numbers of the test log of each test (column -> n values), as
        :func:`rocklab.lab.reduction.log_values` reads tests.csv.
    simulate : callable, optional
        The wall's physics, as :func:`write_campaign`'s; default :func:`simulate_virtual_test`.
    """
    from rocklab.lab import kinematics

    simulate = simulate_virtual_test if simulate is None else simulate

    one = boundary == Boundary.ONE_SIDED
    layout = usual_layout("S", specimen["length_mm"], specimen["height_mm"], specimen["thickness_mm"], one)
    X, F = transducer_geometry(layout)
    used = np.r_[np.ones(5), np.zeros(len(layout) - 5)]  # channel 5 monitors, it is no rigid-body input
    rng = np.random.default_rng(seed)
    recs = []
    for i in range(n):
        direction = "pull" if pull and i % 2 else "push"
        vt = VirtualTest(
            f"{name}-{i}",
            str(specimen.name),
            boundary,
            direction=direction,
            contact_depth_mm=contact_depth_mm if one else None,
            fs=fs,
            alpha_ratio=alpha_ratio(i) if callable(alpha_ratio) else alpha_ratio,
            theta0_ratio=float(rng.uniform(*theta0_range)),
            model=model(i) if callable(model) else dict(model),
            effects=Effects(noise_mm=noise_mm, hum_mm=noise_mm),
        )
        t, E, truth = simulate(vt, specimen, layout, rng, t_end)
        theta = kinematics.solve_wall_motion(E, X, F, specimen["thickness_mm"], weights=used)["theta"]
        recs.append(
            dict(
                test_id=vt.test_id,
                t=t,
                theta=theta,
                fs=vt.fs,
                alpha=truth["alpha"],
                p=truth["p"],
                boundary=boundary,
                direction=direction,
                log={k: v[i] for k, v in (log or {}).items()},
            )
        )
    return recs


def _effects_on(e: Effects):
    names = [
        k for k in ("noise_mm", "hum_mm", "ringing_mm", "creep_rad_s", "twist_ratio", "slide_mm") if getattr(e, k) > 0
    ]
    if e.decimals is not None:
        names.append("rounding")
    return names


def write_campaign(out_dir, tests, specimens=None, layouts=None, seed=0, t_end=40.0, simulate=None):
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
    simulate : callable, optional
        ``(test, specimen, layout, rng, t_end) -> (t, readings, truth)``, the
        wall's physics; default :func:`simulate_virtual_test`.  Another
        generator (:func:`rocklab.lab.contact_lab.simulate_contact_test`)
        gives the truth's keys too, and its own columns as ``truth["columns"]``.

    Returns
    -------
    DataFrame
        truth.csv: one row per test with every parameter used, the true
        theta0 and e, the effects on, the faults and the expected verdict.
    """
    simulate = simulate_virtual_test if simulate is None else simulate
    out = Path(out_dir)
    (out / "tests").mkdir(parents=True, exist_ok=True)
    specimens = DEFAULT_SPECIMENS if specimens is None else specimens
    spec = specimens.set_index("specimen")
    unknown = sorted({t.specimen for t in tests} - set(spec.index))
    if unknown:
        raise ValueError(
            f"virtual tests of specimens {', '.join(map(repr, unknown))} not in the specimens table "
            f"(known: {', '.join(map(str, spec.index))})"
        )
    layouts = dict(layouts or {})
    rows, truths = [], []
    streams = np.random.SeedSequence(seed).spawn(len(tests))
    for test, ss in zip(tests, streams):
        sp = spec.loc[test.specimen]
        # the transducers' layout of a test that other instruments record: the same true motion, not written
        key = test.setup or replace(test, instrument="transducers").setup
        if key not in layouts:
            layouts[key] = usual_layout(
                key, sp.length_mm, sp.height_mm, sp.thickness_mm, test.boundary == Boundary.ONE_SIDED
            )
        layout = layouts[key]
        rng = np.random.default_rng(ss)
        t, E, truth = simulate(test, sp, layout, rng, t_end)
        rel = test.file
        unreadable = any(f.kind == "unreadable" for f in test.faults)
        if test.instrument == "transducers":
            write_record(out / rel, test.test_id, test.fs, t, E, layout.channel.tolist(), unreadable=unreadable)
        elif test.instrument == "tdms":
            write_tdms(out / rel, t, E, layout.channel.tolist(), unreadable)
        elif test.instrument == "c3d":
            dof = (truth[k] for k in ("theta", "phi", "v", "w"))
            write_c3d(out / rel, test.fs, *dof, sp, test.markers, rng, unreadable)
        elif test.instrument == "video":
            write_video(out / rel, test.fs, truth["theta"], truth["w"], sp, test.video, rng, unreadable)
        else:
            write_instrument_record(
                out / rel, test.test_id, test.instrument, test.fs, t, E, truth.get("sensor_mm"), unreadable
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
                "instrument": test.instrument,
                "gyro_bias_rad_s": truth.get("gyro_bias_rad_s", np.nan),
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
                "zeta": truth["zeta"],
                "hinge_rounding": truth["hinge_rounding"],
                "mu": truth["mu"],
                "kappa": truth["kappa"],
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
                **truth.get("columns", {}),
            }
        )
    specimens.to_csv(out / "specimens.csv", index=False)
    used = sorted({t.setup for t in tests if t.setup})
    columns = usual_layout("", 1, 1, 1, False).columns
    pd.concat([layouts[s] for s in used] or [pd.DataFrame(columns=columns)], ignore_index=True).to_csv(
        out / "setups.csv", index=False
    )
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
        bc = dict(boundary=Boundary.ONE_SIDED, contact_depth_mm=float(rng.choice([120, 260]))) if one else {}
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
