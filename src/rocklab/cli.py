"""Command-line entry point ``rocklab`` (argparse with subcommands).

``rocklab simulate`` runs one wall, free or under a record, with the
event-driven reference of :mod:`rocklab.simulation.model` and writes its history to
netCDF.  Further subcommands register themselves in :data:`COMMANDS`.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from rocklab.physics import impact
from rocklab.simulation.model import OVERTURN, RockingModel
from rocklab.simulation.reference import simulate_free, simulate_ground

LAWS = {"housner": impact.HousnerTwoSided, "one-sided": impact.OneSided, "zero": impact.Zero}


def _read_record(name, dt, units):
    """Ground acceleration [m/s^2] and its sample interval [s].

    With ``dt``: a one-column text file in ``units``.  Without: a Table 4
    record of the manifest (e.g. ``40EIC180``) or any file the accelerogram
    readers detect (PEER AT2, Caltech, K-NET, column text...), in m/s^2 and
    baseline-corrected (:func:`rocklab.seismic.accelerograms.load_record`).
    """
    from rocklab.seismic.accelerograms import load_record, to_si

    if dt is not None:
        return to_si(np.loadtxt(name, ndmin=2)[:, 0], units), dt

    try:
        tr = load_record(name)
    except (FileNotFoundError, TypeError, ValueError) as err:
        raise SystemExit(f"rocklab simulate: --record {name}: {err} (a one-column text file needs --dt)") from err
    return tr.data, tr.stats.delta


def _model(args):
    if (args.height is None) != (args.thickness is None):
        raise SystemExit("rocklab simulate: give both --height and --thickness, or --alpha and --p")
    law = None
    if args.impact is not None:
        law = LAWS[args.impact]()
    if args.e_scale != 1.0:
        law = impact.Scaled(
            law or (impact.OneSided() if args.boundary == "one-sided" and args.gap == 0 else impact.HousnerTwoSided()),
            args.e_scale,
        )
    if args.amplitude_law is not None:
        a, b = args.amplitude_law
        law = impact.AmplitudeLaw(law or impact.OneSided(), a, b)
    kw = dict(
        boundary=args.boundary,
        impact=law,
        alpha_rock=args.alpha_rock,
        alpha_neg=args.alpha_neg,
        flight_damping=args.flight_damping,
        gap=args.gap,
        form=args.form,
    )
    if args.height is not None:
        return RockingModel.from_wall(args.height, args.thickness, **kw)
    if args.alpha is None or args.p is None:
        raise SystemExit("rocklab simulate: give --height/--thickness or --alpha/--p")
    return RockingModel(alpha=args.alpha, p=args.p, **kw)


def simulate(args) -> int:
    """Run one wall and write its history (netCDF)."""
    model = _model(args)
    if args.record is not None:
        ag, dt = _read_record(args.record, args.dt, args.units)
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
    else:
        if args.theta0 == 0 and args.thetadot0 == 0:
            raise SystemExit("rocklab simulate: free rocking needs --theta0 or --thetadot0 (or give --record)")
        hist = simulate_free(
            model, args.theta0, args.thetadot0, t_end=args.t_end or 30.0, fs=args.fs or 400.0, overturn=args.overturn
        )
    ds = hist.to_xarray()
    ds.attrs["history"] = "rocklab " + " ".join(sys.argv[1:]) if sys.argv else "rocklab simulate"
    ds.to_netcdf(args.output)
    state = f"overturned at t = {hist.t_overturn:.3f} s" if hist.overturned else "standing"
    print(f"{args.output}: {len(hist.impacts)} impacts, {state}")
    return 0


def _add_simulate(sub):
    p = sub.add_parser(
        "simulate", help="simulate one rocking wall (free or under a record) to netCDF", description=simulate.__doc__
    )
    g = p.add_argument_group("wall")
    g.add_argument("--height", type=float, help="wall height h [m]")
    g.add_argument("--thickness", type=float, help="wall thickness b [m]")
    g.add_argument("--alpha", type=float, help="slenderness angle [rad] (instead of h, b)")
    g.add_argument("--p", type=float, help="frequency parameter [rad/s] (instead of h, b)")
    g.add_argument("--alpha-rock", type=float, help="rocking angle of the positive hinge [rad]")
    g.add_argument("--alpha-neg", type=float, help="rocking angle of the negative hinge [rad]")
    g.add_argument("--boundary", choices=["two-sided", "one-sided"], default="two-sided")
    g.add_argument("--gap", type=float, default=0.0, help="one-sided gap [rad]")
    g.add_argument("--form", choices=["exact", "linear"], default="exact")
    g.add_argument("--impact", choices=sorted(LAWS), help="impact law (default by boundary)")
    g.add_argument("--e-scale", type=float, default=1.0, help="multiply the impact law by this constant")
    g.add_argument("--amplitude-law", type=float, nargs=2, metavar=("A", "B"), help="Eq. 17 coefficients")
    g.add_argument("--flight-damping", type=float, default=0.0, help="zeta between impacts")
    m = p.add_argument_group("motion")
    m.add_argument(
        "--record",
        help="Table 4 record name (raw/accelerograms/manifest.csv) or accelerogram file "
        "(any format rocklab reads; one-column text with --dt)",
    )
    m.add_argument("--dt", type=float, help="sample interval of a one-column text record [s]")
    m.add_argument("--units", choices=["g", "m/s2", "cm/s2"], default="m/s2", help="units of a one-column record")
    m.add_argument("--scale", type=float, default=1.0, help="amplitude scale of the record")
    m.add_argument("--theta0", type=float, default=0.0, help="initial rotation [rad]")
    m.add_argument("--thetadot0", type=float, default=0.0, help="initial angular velocity [rad/s]")
    m.add_argument("--t-end", type=float, help="duration [s] (default: record length or 30 s)")
    m.add_argument("--fs", type=float, help="output sampling frequency [Hz]")
    m.add_argument("--overturn", type=float, default=OVERTURN, help="overturning rotation [rad] (default pi/2)")
    p.add_argument("-o", "--output", required=True, help="netCDF file to write")
    p.set_defaults(func=simulate)


#: Subcommand registrars: each adds its parser and sets ``func``.
COMMANDS = [_add_simulate]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="rocklab", description="rocklab: rocking of unreinforced masonry walls")
    sub = parser.add_subparsers(dest="command", required=True)
    for add in COMMANDS:
        add(sub)
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    raise SystemExit(main())
