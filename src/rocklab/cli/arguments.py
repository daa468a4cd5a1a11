"""What the commands share: usage errors, argument types and checks, records, outputs.

Every argument is checked before anything is computed: the argparse types of
this module say what they accept in their error, and the checks raise
:class:`UsageError` (exit status 2); :class:`CommandError` is a failure
after the arguments were accepted (status 1).
"""

from __future__ import annotations

import argparse
import math
import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, NoReturn

import numpy as np

if TYPE_CHECKING:
    import xarray as xr


class UsageError(Exception):
    """A wrong argument found after parsing (exit status 2).

    Parameters
    ----------
    option : str
        The option at fault, e.g. ``"--height"``.
    message : str
        What is wrong with it.
    """

    def __init__(self, option: str, message: str) -> None:
        super().__init__(f"{option}: {message}")


class CommandError(Exception):
    """A command that failed after its arguments were accepted (exit status 1)."""


class Parser(argparse.ArgumentParser):
    """An argument parser that reports a usage error in one line and exits with 2.

    argparse prints the usage and ``prog: error: argument --x: ...``; an
    analyst reading a log wants the option and what is wrong, on one line.
    """

    def error(self, message: str) -> NoReturn:
        required = "the following arguments are required: "
        if message.startswith(required):
            message = f"{message.removeprefix(required)}: required"
        self.exit(2, f"{self.prog}: {message.removeprefix('argument ')}\n")


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """Help with every option's default (those without one say why in their text),
    and the description and examples laid out as written."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        no_default = action.default is None or action.default is False or action.default == argparse.SUPPRESS
        if not no_default and "%(default)" not in text and "(default:" not in text:
            text += " (default: %(default)s)"
        return text


# --- argument types: each says what it accepts in its error --------------------------------

_NAMES = {math.pi / 2: "pi/2"}


def _show(x: float) -> str:
    return _NAMES.get(x, f"{x:g}")


def number(
    lo: float | None = None,
    hi: float | None = None,
    *,
    lo_closed: bool = False,
    hi_closed: bool = False,
    kind: Callable[[str], float] = float,
) -> Callable[[str], float]:
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

    def convert(text: str) -> float:
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


def check_wall(args: argparse.Namespace, second: str) -> str:
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


def add_eq17_option(group: argparse._ArgumentGroup, flag: str, text: str, default: str) -> None:
    """Add an option taking the coefficients A, B of Eq. 17 (checked by :func:`check_eq17`)."""
    group.add_argument(
        flag, type=FINITE, nargs=2, metavar=("A", "B"), help=f"{text}, A > 0, B >= 0 [-] (default: {default})"
    )


def check_eq17(values: Sequence[float], option: str) -> tuple[float, float]:
    """The coefficients (A, B) of Eq. 17, e times (A - B (thetadot/thetadot_r)^2): A > 0
    (else e = 0 at every impact), B >= 0 (else e grows with the amplitude)."""
    a, b = values
    if a <= 0:
        raise UsageError(option, f"A must be > 0 (got {a:g})")
    if b < 0:
        raise UsageError(option, f"B must be >= 0 (got {b:g})")
    return a, b


def check_writable(path: str | Path, option: str) -> Path:
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


def check_figure_format(path: str | Path, option: str = "--figure") -> None:
    """Check that matplotlib can write a figure named ``path`` (by its suffix)."""
    from matplotlib.backend_bases import FigureCanvasBase

    kinds = FigureCanvasBase.get_supported_filetypes()
    suffix = Path(path).suffix.lstrip(".").lower()
    if suffix not in kinds:
        raise UsageError(option, f"{path}: unknown figure format {suffix!r}; use one of {', '.join(sorted(kinds))}")


def write_dataset(ds: xr.Dataset, path: str | Path, option: str, history: str) -> None:
    """Write ``ds`` to ``path`` (through a temporary file), with the command in ``history``."""
    from rocklab.io import write_netcdf

    ds.attrs["history"] = history
    try:
        write_netcdf(ds, path)
    except (OSError, RuntimeError) as err:
        raise CommandError(f"{option}: cannot write {path}: {err}") from None


def read_record(args: argparse.Namespace) -> tuple[np.ndarray, float, str]:
    """Ground acceleration [m/s^2], its sample interval [s] and its name.

    Every record is read by :func:`rocklab.seismic.accelerograms.load_record`.
    With ``--dt``: a one-column text file in ``--units``, read as it is (the
    one-value-a-line format of SLAMMER's records, with the caller's dt and
    units, not baseline-corrected).  Without: a shipped Table 4 record of the
    manifest (e.g. ``40EIC180``) or any file the accelerogram readers detect
    (PEER AT2, Caltech, K-NET, column text...), in m/s^2 and
    baseline-corrected.

    Raises
    ------
    UsageError
        Unknown name, missing or unreadable file, a record without finite
        samples.
    """
    import pandas as pd

    from rocklab.seismic.accelerograms import load_record, read_manifest

    name = args.record
    if args.dt is not None:
        path = Path(name)
        if not path.is_file():
            raise UsageError("--record", f"{name}: no such file (--dt reads a one-column text file)")
        try:
            tr = load_record(path, corrected=False, format="SLAMMER", dt=args.dt, units=args.units)
        # a user's file can fail in any way (not text, not numbers, several columns)
        except Exception as err:
            columns = _columns(path)
            if columns is not None and columns > 1:
                raise UsageError(
                    "--record", f"{name}: {columns} columns; --dt reads one column (drop --dt to detect the format)"
                ) from None
            raise UsageError("--record", f"{name}: not a one-column text file ({err})") from None
        # the reader's trace holds 1 / (1 / dt): the interval is the one given
        ag, dt, name = tr.data, args.dt, path.stem
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


def _columns(path: str | Path) -> int | None:
    """Numbers on the first non-blank line of a text file (None where that line holds anything else)."""
    try:
        with open(path, encoding="ascii") as fh:
            fields = next((line.split() for line in fh if line.strip()), [])
        return len([float(f) for f in fields]) or None
    except (OSError, UnicodeDecodeError, ValueError):
        return None


def add_record_options(group: argparse._ArgumentGroup, required: bool) -> None:
    """Add ``--record``, ``--dt`` and ``--units`` to ``group`` (read by :func:`read_record`)."""
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
