"""Command-line entry point ``rocklab`` (argparse with subcommands).

``rocklab simulate`` runs one wall, free or under a record, with the
event-driven reference of :mod:`rocklab.simulation.model` and writes its
history to netCDF.  ``rocklab map`` computes overturning maps of Sect. 5
(:func:`rocklab.seismic.overturning.overturning_map`) for a shipped or a
user's record, writes them to netCDF and a figure and prints their indices.
Further subcommands register themselves in :data:`COMMANDS`.

Every argument is checked before anything is computed.  A wrong one ends the
command with one line on stderr, ``rocklab <command>: <option>: <what is
wrong>``, and exit status 2 (argparse's convention for usage errors); a
failure while writing the results ends it with one line and status 1.  The
options, their units and the exit statuses: ``docs/cli.md``.
"""

from __future__ import annotations

import argparse
import inspect
import math
import shlex
import sys
import tempfile
import time
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from rocklab import __version__
from rocklab.physics import impact, wall
from rocklab.simulation.model import OVERTURN, RockingModel

LAWS = {"housner": impact.HousnerTwoSided, "one-sided": impact.OneSided, "zero": impact.Zero}

#: Most output samples ``rocklab simulate`` writes (t_end x fs): 10^7 samples
#: are 240 MB of history in memory, beyond what an analyst means to ask for.
MAX_SAMPLES = 10_000_000


class UsageError(Exception):
    """A wrong argument found after parsing (exit status 2).

    Parameters
    ----------
    option : str
        The option at fault, e.g. ``"--height"``.
    message : str
        What is wrong with it.
    """

    def __init__(self, option, message):
        super().__init__(f"{option}: {message}")


class CommandError(Exception):
    """A command that failed after its arguments were accepted (exit status 1)."""


class Parser(argparse.ArgumentParser):
    """An argument parser that reports a usage error in one line and exits with 2.

    argparse prints the usage and ``prog: error: argument --x: ...``; an
    analyst reading a log wants the option and what is wrong, on one line.
    """

    def error(self, message):
        required = "the following arguments are required: "
        if message.startswith(required):
            message = f"{message.removeprefix(required)}: required"
        self.exit(2, f"{self.prog}: {message.removeprefix('argument ')}\n")


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """Help with every option's default (those without one say why in their text),
    and the description and examples laid out as written."""

    def _get_help_string(self, action):
        text = action.help or ""
        no_default = action.default is None or action.default is False or action.default == argparse.SUPPRESS
        if not no_default and "%(default)" not in text and "(default:" not in text:
            text += " (default: %(default)s)"
        return text


# --- argument types: each says what it accepts in its error --------------------------------

_NAMES = {math.pi / 2: "pi/2"}


def _show(x):
    return _NAMES.get(x, f"{x:g}")


def number(lo=None, hi=None, *, lo_closed=False, hi_closed=False, kind=float):
    """An argparse ``type``: a finite number of ``kind`` within bounds.

    Parameters
    ----------
    lo, hi : float, optional
        Bounds, open unless ``lo_closed`` / ``hi_closed``.
    kind : {float, int}

    Returns
    -------
    callable
        str -> number, raising ``argparse.ArgumentTypeError`` with a message
        such as ``must be > 0 (got -3)``.
    """
    if lo is not None and hi is not None:
        rule = f"in {'[' if lo_closed else '('}{_show(lo)}, {_show(hi)}{']' if hi_closed else ')'}"
    elif lo is not None:
        rule = f"{'>=' if lo_closed else '>'} {_show(lo)}"
    elif hi is not None:
        rule = f"{'<=' if hi_closed else '<'} {_show(hi)}"
    else:
        rule = "finite"

    def convert(text):
        try:
            x = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"must be {'an integer' if kind is int else 'a number'} (got {text!r})"
            ) from None
        below = lo is not None and (x < lo or (x == lo and not lo_closed))
        above = hi is not None and (x > hi or (x == hi and not hi_closed))
        if not math.isfinite(x) or below or above:
            raise argparse.ArgumentTypeError(f"must be {rule} (got {text})")
        return x

    return convert


POSITIVE = number(0.0)
NON_NEGATIVE = number(0.0, lo_closed=True)
FINITE = number()
#: A slenderness or rocking angle [rad]: a wall with alpha >= pi/2 is not a wall.
ANGLE = number(0.0, math.pi / 2)
COUNT = number(1, lo_closed=True, kind=int)


# --- checks shared by the commands ----------------------------------------------------------


def check_wall(args, second):
    """Say which way the wall was given: ``"hb"`` (height, thickness) or ``"alpha"``.

    Parameters
    ----------
    args : argparse.Namespace
    second : str
        The option given with ``--alpha``: ``"--p"`` (simulate) or ``"--R"`` (map).

    Raises
    ------
    UsageError
        When the wall is given both ways or only half of height and thickness.
    """
    hb = {"--height": args.height, "--thickness": args.thickness}
    ap = {"--alpha": args.alpha, second: getattr(args, second.lstrip("-"))}
    given_hb = [k for k, v in hb.items() if v is not None]
    given_ap = [k for k, v in ap.items() if v is not None]
    if given_hb and given_ap:
        raise UsageError(given_ap[0], f"give the wall as --height/--thickness or as --alpha/{second}, not both")
    if len(given_hb) == 1:
        other = "--thickness" if given_hb[0] == "--height" else "--height"
        raise UsageError(other, f"missing: {given_hb[0]} needs it")
    return "hb" if given_hb else "alpha"


def add_eq17_option(group, flag, text, default):
    """Add an option taking the coefficients A, B of Eq. 17 (checked by :func:`check_eq17`)."""
    group.add_argument(
        flag, type=FINITE, nargs=2, metavar=("A", "B"), help=f"{text}, A > 0, B >= 0 [-] (default: {default})"
    )


def check_eq17(values, option):
    """The coefficients (A, B) of Eq. 17, e times (A - B (thetadot/thetadot_r)^2): A > 0
    (else e = 0 at every impact), B >= 0 (else e grows with the amplitude)."""
    a, b = values
    if a <= 0:
        raise UsageError(option, f"A must be > 0 (got {a:g})")
    if b < 0:
        raise UsageError(option, f"B must be >= 0 (got {b:g})")
    return a, b


def check_writable(path, option):
    """Check that ``path`` can be written, before anything is computed.

    Its folder must exist and accept a new file (tried, so that it holds for
    root, read-only mounts and ACLs alike); ``path`` must not be a folder.

    Returns
    -------
    pathlib.Path
    """
    path = Path(path)
    folder = path.parent
    if path.is_dir():
        raise UsageError(option, f"{path} is a folder; give a file name")
    if not folder.is_dir():
        what = "is not a folder" if folder.exists() else "does not exist"
        raise UsageError(option, f"cannot write {path}: {folder} {what}")
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as err:
        raise UsageError(option, f"cannot write {path}: folder {folder} is not writable ({err.strerror})") from None
    return path


def check_figure_format(path, option="--figure"):
    """Check that matplotlib can write a figure named ``path`` (by its suffix)."""
    from matplotlib.backend_bases import FigureCanvasBase

    kinds = FigureCanvasBase.get_supported_filetypes()
    suffix = Path(path).suffix.lstrip(".").lower()
    if suffix not in kinds:
        raise UsageError(option, f"{path}: unknown figure format {suffix!r}; use one of {', '.join(sorted(kinds))}")


def write_dataset(ds, path, option, history):
    """Write ``ds`` to ``path`` (through a temporary file), with the command in ``history``."""
    from rocklab.io import write_netcdf

    ds.attrs["history"] = history
    try:
        write_netcdf(ds, path)
    except (OSError, RuntimeError) as err:
        raise CommandError(f"{option}: cannot write {path}: {err}") from None


def read_record(args):
    """Ground acceleration [m/s^2], its sample interval [s] and its name.

    With ``--dt``: a one-column text file in ``--units``.  Without: a shipped
    Table 4 record of the manifest (e.g. ``40EIC180``) or any file the
    accelerogram readers detect (PEER AT2, Caltech, K-NET, column text...),
    in m/s^2 and baseline-corrected
    (:func:`rocklab.seismic.accelerograms.load_record`).

    Raises
    ------
    UsageError
        Unknown name, missing or unreadable file, a record without finite
        samples.
    """
    import pandas as pd

    from rocklab.seismic.accelerograms import load_record, read_manifest, to_si

    name = args.record
    if args.dt is not None:
        path = Path(name)
        if not path.is_file():
            raise UsageError("--record", f"{name}: no such file (--dt reads a one-column text file)")
        try:
            values = np.loadtxt(path, ndmin=2)
        except ValueError as err:
            raise UsageError("--record", f"{name}: not a one-column text file ({err})") from None
        if values.shape[1] != 1:
            raise UsageError(
                "--record", f"{name}: {values.shape[1]} columns; --dt reads one column (drop --dt to detect the format)"
            )
        ag, dt, name = to_si(values[:, 0], args.units), args.dt, path.stem
    else:
        if args.units != "m/s2":
            raise UsageError("--units", "only for a one-column text record read with --dt")
        try:
            manifest = read_manifest()
        except OSError:  # an installation without the shipped records still reads files
            manifest = pd.DataFrame({"record": [], "file": []}, dtype=str)
        known = list(manifest["record"])
        shipped = str(name).lower() in {s.lower() for s in (*known, *manifest["file"])}
        if not shipped and not Path(name).is_file():
            listing = f"shipped records: {', '.join(known)}" if known else "no shipped records found"
            raise UsageError("--record", f"{name!r} is neither a shipped record nor a file; {listing}")
        try:
            tr = load_record(name, manifest=manifest)
        # a user's file can fail in any reader (obspy's detection, a malformed header...)
        except Exception as err:
            hint = "; a one-column text file needs --dt" if not shipped else ""
            raise UsageError("--record", f"cannot read {name}: {err}{hint}") from None
        ag, dt, name = tr.data, tr.stats.delta, tr.stats.get("record") or Path(name).stem
    if ag.size < 2 or not np.isfinite(ag).all():
        raise UsageError("--record", f"{args.record}: needs at least 2 samples, all finite")
    return np.asarray(ag, float), float(dt), str(name)


# --- rocklab simulate -----------------------------------------------------------------------


def _impact_law(args, alpha):
    """The impact law the options ask for (None: the model's default) and its checks."""
    law = None
    if args.impact is not None:
        law = LAWS[args.impact]()
    if args.e_scale != 1.0:
        default = impact.OneSided() if args.boundary == "one-sided" and args.gap == 0 else impact.HousnerTwoSided()
        law = impact.Scaled(law or default, args.e_scale)
    if args.amplitude_law is not None:
        a, b = check_eq17(args.amplitude_law, "--amplitude-law")
        law = impact.AmplitudeLaw(law or impact.OneSided(), a, b)
    elif law is not None:
        # Eq. 17's bracket is clipped to |e| <= 1; a constant law is not
        e0 = np.abs(law.flat(alpha)[:, 0]).max()
        if e0 > 1.0:
            raise UsageError(
                "--e-scale" if args.e_scale != 1.0 else "--impact",
                f"|e| = {e0:.3g} > 1 for alpha = {alpha:.4g} rad: an impact would create energy",
            )
    return law


def simulate_model(args):
    """The :class:`~rocklab.simulation.model.RockingModel` of ``rocklab simulate``'s options."""
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
    if args.gap > 0 and args.boundary != "one-sided":
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
        flight_damping=args.flight_damping,
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


def _add_record_options(group, required):
    group.add_argument(
        "--record",
        required=required,
        metavar="NAME|FILE",
        help="shipped Table 4 record (e.g. 40EIC180; the manifest of the shipped accelerograms) or an "
        "accelerogram file in any format rocklab reads (PEER AT2, Caltech, K-NET...; one-column text with --dt)",
    )
    group.add_argument("--dt", type=POSITIVE, metavar="S", help="sample interval of a one-column text record [s]")
    group.add_argument(
        "--units", choices=["g", "m/s2", "cm/s2"], default="m/s2", help="units of a one-column text record"
    )


def _add_simulate(sub):
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
    g.add_argument("--boundary", choices=["two-sided", "one-sided"], default="two-sided", help="boundary condition")
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
        "--flight-damping",
        type=number(0.0, 1.0, lo_closed=True),
        default=0.0,
        metavar="ZETA",
        help="damping ratio zeta between impacts, in [0, 1) [-]",
    )
    m = p.add_argument_group("motion (a record, or free rocking from --theta0/--thetadot0)")
    _add_record_options(m, required=False)
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


# --- rocklab map ----------------------------------------------------------------------------


class ProgressBar:
    """Progress of a long computation on a stream (stderr), called as ``bar(done, total)``.

    On a terminal the bar ``[#####     ]  50 %`` is redrawn in place and ends
    its line when complete; in a log (not a terminal) one line is written
    each time another 10 % is done.

    Parameters
    ----------
    label : str
        Written after the bar.
    stream : file, optional
        Default ``sys.stderr``.
    width : int
        Characters of the bar.
    """

    def __init__(self, label="", stream=None, width=30):
        self.label, self.width = label, int(width)
        self.stream = sys.stderr if stream is None else stream
        self.tty = self.stream.isatty()
        self.shown = -1
        self.t0 = time.perf_counter()

    def __call__(self, done, total):
        """Show that ``done`` units of work out of ``total`` are complete."""
        pct = min(max(100 * int(done) // int(total), 0), 100) if total else 100
        step = pct if self.tty else pct - pct % 10
        if step == self.shown:
            return
        self.shown = step
        filled = self.width * pct // 100
        line = (
            f"[{'#' * filled}{' ' * (self.width - filled)}] {pct:3d} %"
            f"  {time.perf_counter() - self.t0:6.1f} s  {self.label}"
        )
        if self.tty:
            self.stream.write("\r" + line + ("\n" if pct == 100 else ""))
        else:
            self.stream.write(line + "\n")
        self.stream.flush()


def map_models(args):
    """Names of the maps asked for (``--model``, ``--all-models``) and their checks."""
    from rocklab.seismic.overturning import MODELS

    models = list(MODELS) if args.all_models else list(dict.fromkeys(args.model))
    unknown = [m for m in models if m not in MODELS]
    if unknown:
        raise UsageError("--model", f"unknown model {unknown[0]!r}; choose from {', '.join(MODELS)}")
    if args.eq17 is not None:
        if "1s-eq17" not in models:
            raise UsageError("--eq17", "only for --model 1s-eq17")
        check_eq17(args.eq17, "--eq17")
    return models


def _map_outputs(args, models):
    """netCDF path of each map (``-o``, ``{model}`` filled) and the figure path, checked."""
    paths = {}
    if args.output is not None:
        if len(models) > 1 and "{model}" not in args.output:
            raise UsageError("--output", "several maps need {model} in the file name, e.g. -o map_{model}.nc")
        paths = {m: check_writable(args.output.replace("{model}", m), "--output") for m in models}
        if len(set(paths.values())) < len(paths):
            raise UsageError("--output", "two maps would be written to the same file")
    if args.figure is not None:
        check_figure_format(args.figure)
        check_writable(args.figure, "--figure")
    return paths


def _format_indices(ix):
    if not ix["n_overturned"]:
        return f"N_O = 0 (no overturning in {ix['n_cells']} histories)"
    return (
        f"N_O = {ix['N_O']:.4f}, N_D = {ix['N_D']:.4f}, N_A = {ix['N_A']:.4f}, "
        f"scatter = {ix['scatter']:.4f} ({ix['n_overturned']} of {ix['n_cells']} histories overturn)"
    )


def overturning_maps(args) -> int:
    """Compute overturning maps (Sect. 5), write them and print their indices.

    Returns
    -------
    int
        Exit status 0.
    """
    import numba

    from rocklab.seismic.overturning import ALPHA, R, map_indices, overturning_map

    if args.hi <= args.lo:
        raise UsageError("--hi", f"must be > --lo (got --lo {args.lo:g} --hi {args.hi:g})")
    if args.threads is not None and args.threads > numba.config.NUMBA_NUM_THREADS:
        raise UsageError("--threads", f"at most {numba.config.NUMBA_NUM_THREADS} on this machine (NUMBA_NUM_THREADS)")
    if check_wall(args, "--R") == "hb":
        alpha = float(wall.slenderness_angle(args.height, args.thickness))
        half_diagonal = float(wall.half_diagonal(args.height, args.thickness))
    else:
        alpha = ALPHA if args.alpha is None else args.alpha
        half_diagonal = R if args.R is None else args.R
    models = map_models(args)
    paths = _map_outputs(args, models)
    ag, dt, name = read_record(args)
    if args.threads is not None:
        numba.set_num_threads(args.threads)

    maps = []
    for model in models:
        label = f"{name} {model}"
        bar = None if args.quiet else ProgressBar(label)
        if bar is not None:
            bar(0, args.n)
        ds = overturning_map(
            ag,
            dt,
            model,
            args.n,
            args.lo,
            args.hi,
            alpha=alpha,
            R=half_diagonal,
            form=args.form,
            eq17=tuple(args.eq17) if args.eq17 is not None else None,
            polarity=args.polarity,
            chunks=args.chunks,
            name=name,
            progress=bar,
        )
        maps.append(ds)
        where = f"{paths[model]}: " if model in paths else ""
        if model in paths:
            write_dataset(ds, paths[model], "--output", args.history)
        print(f"{where}{label}: {_format_indices(map_indices(ds['overturned']))}")
    if args.figure is not None:
        import matplotlib.pyplot as plt

        from rocklab.plots.maps import overturning_maps as draw_maps

        fig = draw_maps(maps)
        try:
            fig.savefig(args.figure, dpi=120)
        except OSError as err:
            raise CommandError(f"--figure: cannot write {args.figure}: {err}") from None
        finally:
            plt.close(fig)
        print(f"{args.figure}: {len(maps)} map{'s' if len(maps) > 1 else ''}")
    return 0


MAP_EPILOG = """\
examples:
  rocklab map --record 40EIC180 --n 51 -o elcentro.nc --figure elcentro.png
  rocklab map --record Pac164 --model 2s-housner 2s-0.95 -o pac_{model}.nc --figure pac.png
  rocklab map --record my.txt --dt 0.005 --units g --height 3 --thickness 0.3 --all-models \\
      -o my_{model}.nc --figure my.png --threads 4

models (Sect. 5):
"""


def _add_map(sub):
    from rocklab.seismic.overturning import ALPHA, MODELS, R, overturning_map

    # the library's defaults are the command's, from one place
    lib = {k: v.default for k, v in inspect.signature(overturning_map).parameters.items()}
    eq17 = inspect.signature(impact.AmplitudeLaw).parameters

    p = sub.add_parser(
        "map",
        help="overturning map of a wall under a scaled record (Sect. 5) to netCDF and a figure",
        description="Compute the overturning map of a wall under one record whose amplitude A and\n"
        "duration D are scaled to A_S and D_S on an n x n grid (Sect. 5, Figs. 21 and 23),\n"
        "write it to netCDF and a figure, and print its indices N_O, N_D, N_A and their\n"
        "scatter (Fig. 22).  The progress goes to stderr.",
        epilog=MAP_EPILOG + "".join(f"  {name:<11} {desc}\n" for name, (_, desc) in MODELS.items()),
        formatter_class=HelpFormatter,
    )
    r = p.add_argument_group("record")
    _add_record_options(r, required=True)
    r.add_argument(
        "--polarity",
        type=int,
        choices=[1, -1],
        default=lib["polarity"],
        help="multiplies the record (one-sided maps depend on it)",
    )
    g = p.add_argument_group("wall (--alpha and --R, or --height and --thickness)")
    g.add_argument("--alpha", type=ANGLE, metavar="RAD", help=f"slenderness angle [rad] (default: {ALPHA}, Fig. 21)")
    g.add_argument("--R", type=POSITIVE, metavar="M", help=f"half diagonal [m] (default: {R}, Fig. 21)")
    g.add_argument("--height", type=POSITIVE, metavar="M", help="wall height h [m]")
    g.add_argument("--thickness", type=POSITIVE, metavar="M", help="wall thickness b [m]")
    g.add_argument("--form", choices=["linear", "exact"], default=lib["form"], help="equation of motion")
    md = p.add_argument_group("model")
    which = md.add_mutually_exclusive_group()
    which.add_argument(
        "--model",
        nargs="+",
        default=[lib["model"]],
        metavar="NAME",
        help=f"one or more of {', '.join(MODELS)} (default: {lib['model']})",
    )
    which.add_argument("--all-models", action="store_true", help="the five models of Sect. 5")
    add_eq17_option(
        md, "--eq17", "coefficients of Eq. 17 for 1s-eq17", f"the paper's {eq17['a'].default} {eq17['b'].default}"
    )
    gr = p.add_argument_group("grid of A_S/A and D_S/D")
    gr.add_argument(
        "--n", type=number(2, lo_closed=True, kind=int), default=lib["n"], help="values per axis (the paper: 201) [-]"
    )
    gr.add_argument("--lo", type=POSITIVE, default=lib["lo"], help="smallest scale [-]")
    gr.add_argument("--hi", type=POSITIVE, default=lib["hi"], help="largest scale, > --lo [-]")
    c = p.add_argument_group("computation and output")
    c.add_argument("--threads", type=COUNT, metavar="N", help="threads of the batch engine (default: all numba's)")
    c.add_argument("--chunks", type=COUNT, default=20, metavar="N", help="blocks of amplitude rows (progress steps)")
    c.add_argument(
        "-o", "--output", metavar="FILE.nc", help="netCDF file to write; with several models it holds {model}"
    )
    c.add_argument("--figure", metavar="FILE.png", help="figure of the maps side by side (png, pdf, svg...)")
    c.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=overturning_maps, parser=p)


#: Subcommand registrars: each adds its parser and sets ``func`` and ``parser``.
COMMANDS = [_add_simulate, _add_map]


def build_parser() -> argparse.ArgumentParser:
    """The ``rocklab`` parser with every subcommand of :data:`COMMANDS`."""
    parser = Parser(
        prog="rocklab",
        description="rocklab: rocking of unreinforced masonry walls. "
        "`rocklab COMMAND --help` gives a command's options, their units and defaults.",
    )
    parser.add_argument("--version", action="version", version=f"rocklab {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for add in COMMANDS:
        add(sub)
    return parser


def main(argv=None) -> int:
    """Run ``rocklab`` with ``argv`` (default ``sys.argv[1:]``) and return its exit status.

    Usage errors exit (``SystemExit``) with status 2 after one line on stderr.
    """
    argv = sys.argv[1:] if argv is None else list(argv)
    args = build_parser().parse_args(argv)
    args.history = f"{datetime.now(UTC):%Y-%m-%dT%H:%M:%SZ}: rocklab {shlex.join(argv)}"
    try:
        return args.func(args)
    except UsageError as err:
        args.parser.error(str(err))
    except CommandError as err:
        print(f"{args.parser.prog}: {err}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    raise SystemExit(main())
