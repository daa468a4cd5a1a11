"""``rocklab simulate``: one wall, free or under a record, with the event-driven reference.

The wall, its impact law and its motion from the options
(:func:`simulate_model`), its history written to netCDF (:func:`simulate`).
"""

from __future__ import annotations

import math

import numpy as np

from rocklab.cli.arguments import (
    ANGLE,
    FINITE,
    NON_NEGATIVE,
    POSITIVE,
    HelpFormatter,
    UsageError,
    add_eq17_option,
    add_record_options,
    check_eq17,
    check_wall,
    check_writable,
    number,
    read_record,
    write_dataset,
)
from rocklab.physics import impact, wall
from rocklab.physics.boundary import Boundary
from rocklab.simulation.rocking_model import OVERTURN, RockingModel

LAWS = {"housner": impact.HousnerTwoSided, Boundary.ONE_SIDED: impact.OneSided, "zero": impact.Zero}

#: Most output samples ``rocklab simulate`` writes (t_end x fs): 10^7 samples
#: are 240 MB of history in memory, beyond what an analyst means to ask for.
MAX_SAMPLES = 10_000_000


def _impact_law(args, alpha):
    """The impact law the options ask for (None: the model's default) and its checks."""
    law = base = None
    if args.impact is not None:
        law = base = LAWS[args.impact]()
    if args.e_scale != 1.0:
        base = law or impact.analytic(args.boundary, args.gap > 0)
        law = impact.calibrated(base, args.e_scale, args.e_scale)
    if args.amplitude_law is not None:
        a, b = check_eq17(args.amplitude_law, "--amplitude-law")
        law = impact.AmplitudeLaw(law or impact.OneSided(), a, b)
    elif base is not None:
        # Eq. 17's bracket is a law of the speed, clipped where it reaches
        # |e| = 1; a scale or a constant past it would be clipped everywhere
        # (rocklab.physics.impact.bounded_factor): asked for, it is a mistake
        e0 = np.abs(base.flat(alpha)[:, 0]).max() * args.e_scale
        if e0 > 1.0:
            raise UsageError(
                "--e-scale" if args.e_scale != 1.0 else "--impact",
                f"|e| = {e0:.3g} > 1 for alpha = {alpha:.4g} rad: an impact would create energy",
            )
    return law


def simulate_model(args):
    """The :class:`~rocklab.simulation.rocking_model.RockingModel` of ``rocklab simulate``'s options."""
    given = check_wall(args, "--p")
    if given == "hb":
        alpha = float(wall.slenderness_angle(args.height, args.thickness))
        p = float(wall.frequency_parameter(wall.half_diagonal(args.height, args.thickness)))
    elif args.alpha is None or args.p is None:
        missing = "--alpha" if args.alpha is None else "--p"
        raise UsageError(
            missing, "missing: give the wall as --height and --thickness [m], or as --alpha [rad] and --p [rad/s]"
        )
    else:
        alpha, p = args.alpha, args.p
    if args.gap > 0 and args.boundary != Boundary.ONE_SIDED:
        raise UsageError("--gap", "only for --boundary one-sided")
    if args.gap >= args.overturn:
        raise UsageError("--gap", f"must be < --overturn ({args.overturn:.4g} rad)")
    return RockingModel(
        alpha=alpha,
        p=p,
        boundary=args.boundary,
        impact=_impact_law(args, alpha),
        alpha_rock=args.alpha_rock,
        alpha_neg=args.alpha_neg,
        zeta=args.zeta,
        gap=args.gap,
        form=args.form,
    )


def _check_start(args, model):
    if abs(args.theta0) >= args.overturn:
        raise UsageError("--theta0", f"|theta0| must be < --overturn ({args.overturn:.4g} rad)")
    if model.one_sided and args.theta0 < -model.gap:
        raise UsageError("--theta0", f"a one-sided wall cannot start below -gap = {-model.gap:g} rad")


def _check_samples(t_end, fs):
    n = t_end * fs
    if n > MAX_SAMPLES:
        raise UsageError("--fs", f"{n:.3g} samples over {t_end:g} s; at most {MAX_SAMPLES:.0e} (lower --fs or --t-end)")


def simulate(args) -> int:
    """Run one wall, free or under a record, and write its history (netCDF).

    Returns
    -------
    int
        Exit status 0.
    """
    from rocklab.simulation.reference import simulate_free, simulate_ground

    model = simulate_model(args)
    _check_start(args, model)
    if args.record is None:
        if args.dt is not None:
            raise UsageError("--dt", "only with --record (a one-column text file)")
        if args.theta0 == 0 and args.thetadot0 == 0:
            raise UsageError("--theta0", "free rocking needs --theta0 or --thetadot0 (or give --record)")
        t_end, fs = args.t_end or 30.0, args.fs or 400.0
        _check_samples(t_end, fs)
        check_writable(args.output, "--output")
        hist = simulate_free(model, args.theta0, args.thetadot0, t_end=t_end, fs=fs, overturn=args.overturn)
    else:
        ag, dt, _ = read_record(args)
        _check_samples(args.t_end or ag.size * dt, args.fs or 1.0 / dt)
        check_writable(args.output, "--output")
        hist = simulate_ground(
            model,
            args.scale * ag,
            dt,
            t_end=args.t_end,
            fs=args.fs,
            overturn=args.overturn,
            theta0=args.theta0,
            thetadot0=args.thetadot0,
        )
    write_dataset(hist.to_xarray(), args.output, "--output", args.history)
    state = f"overturned at t = {hist.t_overturn:.3f} s" if hist.overturned else "standing"
    print(f"{args.output}: {len(hist.impacts)} impacts, {state}")
    return 0


SIMULATE_EPILOG = """\
examples:
  rocklab simulate --height 1.63 --thickness 0.113 --theta0 0.05 -o free.nc
  rocklab simulate --height 1.63 --thickness 0.113 --boundary one-sided \\
      --record 40EIC180 --scale 0.5 -o elcentro.nc
  rocklab simulate --alpha 0.1 --p 2 --record my.txt --dt 0.01 --units g -o my.nc
"""


def add_parser(sub):
    p = sub.add_parser(
        "simulate",
        help="simulate one rocking wall (free or under a record) to netCDF",
        description="Simulate one rocking wall, free or under a ground motion, with the event-driven\n"
        "reference, and write its history (rotation, angular velocity, impacts) to netCDF.",
        epilog=SIMULATE_EPILOG,
        formatter_class=HelpFormatter,
    )
    g = p.add_argument_group("wall (--height and --thickness, or --alpha and --p)")
    g.add_argument("--height", type=POSITIVE, metavar="M", help="wall height h [m]")
    g.add_argument("--thickness", type=POSITIVE, metavar="M", help="wall thickness b [m]")
    g.add_argument("--alpha", type=ANGLE, metavar="RAD", help="slenderness angle, in (0, pi/2) [rad]")
    g.add_argument("--p", type=POSITIVE, metavar="RAD/S", help="frequency parameter [rad/s]")
    g.add_argument(
        "--alpha-rock", type=ANGLE, metavar="RAD", help="rocking angle of the positive hinge [rad] (default: alpha)"
    )
    g.add_argument(
        "--alpha-neg", type=ANGLE, metavar="RAD", help="rocking angle of the negative hinge [rad] (default: alpha-rock)"
    )
    g.add_argument(
        "--boundary",
        choices=list(Boundary),
        default=Boundary.TWO_SIDED,
        help="boundary condition",
    )
    g.add_argument(
        "--gap",
        type=number(0.0, math.pi / 2, lo_closed=True),
        default=0.0,
        metavar="RAD",
        help="one-sided only: inward rotation before the transverse walls are struck [rad]",
    )
    g.add_argument("--form", choices=["exact", "linear"], default="exact", help="equation of motion")
    g.add_argument(
        "--impact",
        choices=sorted(LAWS),
        help="impact law (default: housner for two-sided and for a gap, one-sided without a gap)",
    )
    g.add_argument(
        "--e-scale", type=NON_NEGATIVE, default=1.0, metavar="C", help="multiply the impact law by C [-], |e| <= 1"
    )
    add_eq17_option(g, "--amplitude-law", "Eq. 17: e times (A - B (thetadot/thetadot_r)^2)", "none")
    g.add_argument(
        "--zeta",
        type=number(0.0, 1.0, lo_closed=True),
        default=0.0,
        metavar="ZETA",
        help="viscous loss between impacts, -2 zeta p thetadot, in [0, 1) [-]",
    )
    m = p.add_argument_group("motion (a record, or free rocking from --theta0/--thetadot0)")
    add_record_options(m, required=False)
    m.add_argument(
        "--scale", type=FINITE, default=1.0, metavar="X", help="amplitude scale of the record [-] (< 0 flips it)"
    )
    m.add_argument("--theta0", type=FINITE, default=0.0, metavar="RAD", help="initial rotation [rad]")
    m.add_argument("--thetadot0", type=FINITE, default=0.0, metavar="RAD/S", help="initial angular velocity [rad/s]")
    m.add_argument("--t-end", type=POSITIVE, metavar="S", help="duration [s] (default: record length, or 30 s free)")
    m.add_argument(
        "--fs", type=POSITIVE, metavar="HZ", help="output sampling frequency [Hz] (default: the record's, or 400 Hz)"
    )
    m.add_argument(
        "--overturn",
        type=number(0.0, math.pi / 2, hi_closed=True),
        default=OVERTURN,
        metavar="RAD",
        help="overturning rotation, in (0, pi/2] [rad] (default: pi/2)",
    )
    p.add_argument("-o", "--output", required=True, metavar="FILE.nc", help="netCDF file to write (folder must exist)")
    p.set_defaults(func=simulate, parser=p)
