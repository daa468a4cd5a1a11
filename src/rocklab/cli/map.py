"""``rocklab map``: overturning maps of Sect. 5 for a shipped or a user's record.

The maps of :func:`rocklab.seismic.maps.overturning_map`, written to
netCDF and a figure, their indices printed (:func:`overturning_maps`); the
progress on stderr (:class:`ProgressBar`).
"""

from __future__ import annotations

import argparse
import inspect
import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, TextIO

from rocklab.cli.arguments import (
    ANGLE,
    COUNT,
    POSITIVE,
    CommandError,
    HelpFormatter,
    UsageError,
    add_eq17_option,
    add_record_options,
    check_eq17,
    check_figure_format,
    check_wall,
    check_writable,
    number,
    read_record,
    write_dataset,
)
from rocklab.physics import impact, wall


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

    def __init__(self, label: str = "", stream: TextIO | None = None, width: int = 30) -> None:
        self.label, self.width = label, int(width)
        self.stream = sys.stderr if stream is None else stream
        self.tty = self.stream.isatty()
        self.shown = -1
        self.t0 = time.perf_counter()

    def __call__(self, done: int, total: int) -> None:
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


def map_models(args: argparse.Namespace) -> list[str]:
    """Names of the maps asked for (``--model``, ``--all-models``) and their checks."""
    from rocklab.seismic.walls import MODELS

    models = list(MODELS) if args.all_models else list(dict.fromkeys(args.model))
    unknown = [m for m in models if m not in MODELS]
    if unknown:
        raise UsageError("--model", f"unknown model {unknown[0]!r}; choose from {', '.join(MODELS)}")
    if args.eq17 is not None:
        if "1s-eq17" not in models:
            raise UsageError("--eq17", "only for --model 1s-eq17")
        check_eq17(args.eq17, "--eq17")
    return models


def _map_outputs(args: argparse.Namespace, models: Sequence[str]) -> dict[str, Path]:
    """netCDF path of each map (``-o``, ``{model}`` filled) and the figure path, checked."""
    paths: dict[str, Path] = {}
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


def _format_indices(ix: Mapping[str, Any]) -> str:
    if not ix["n_overturned"]:
        return f"N_O = 0 (no overturning in {ix['n_cells']} histories)"
    return (
        f"N_O = {ix['N_O']:.4f}, N_D = {ix['N_D']:.4f}, N_A = {ix['N_A']:.4f}, "
        f"scatter = {ix['scatter']:.4f} ({ix['n_overturned']} of {ix['n_cells']} histories overturn)"
    )


def overturning_maps(args: argparse.Namespace) -> int:
    """Compute overturning maps (Sect. 5), write them and print their indices.

    Returns
    -------
    int
        Exit status 0.
    """
    import numba

    from rocklab.seismic.indices import map_indices
    from rocklab.seismic.maps import overturning_map
    from rocklab.seismic.walls import ALPHA, R

    if args.hi <= args.lo:
        raise UsageError("--hi", f"must be > --lo (got --lo {args.lo:g} --hi {args.hi:g})")
    # numba.core.config sets its options at run time (from the environment): not in its types
    most = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]
    if args.threads is not None and args.threads > most:
        raise UsageError("--threads", f"at most {most} on this machine (NUMBA_NUM_THREADS)")
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


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``rocklab map`` to the subcommands ``sub`` (:data:`rocklab.cli.COMMANDS`)."""
    from rocklab.seismic.maps import overturning_map
    from rocklab.seismic.walls import ALPHA, MODELS, R

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
    add_record_options(r, required=True)
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
