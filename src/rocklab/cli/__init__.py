"""Command-line entry point ``rocklab`` (argparse with subcommands).

``rocklab simulate`` runs one wall, free or under a record, with the
event-driven reference of :mod:`rocklab.simulation.rocking_model` and writes its
history to netCDF.  ``rocklab map`` computes overturning maps of Sect. 5
(:func:`rocklab.seismic.maps.overturning_map`) for a shipped or a
user's record, writes them to netCDF and a figure and prints their indices.
``rocklab track`` tracks the markers of a filmed test and writes its
rotation record (:mod:`rocklab.lab.video_tracking`).
One module per command (:mod:`rocklab.cli.simulate`, :mod:`rocklab.cli.map`, :mod:`rocklab.cli.track`),
each registering its parser in :data:`COMMANDS`; what they share (argument
types and checks, records, outputs) is in :mod:`rocklab.cli.arguments`.

Every argument is checked before anything is computed.  A wrong one ends the
command with one line on stderr, ``rocklab <command>: <option>: <what is
wrong>``, and exit status 2 (argparse's convention for usage errors); a
failure while writing the results ends it with one line and status 1.  The
options, their units and the exit statuses: ``docs/cli.md``.
"""

from __future__ import annotations

import argparse
import shlex
import sys
from collections.abc import Sequence
from datetime import UTC, datetime

from rocklab import __version__
from rocklab.cli import map, simulate, track
from rocklab.cli.arguments import CommandError, Parser, UsageError

#: Subcommand registrars: each adds its parser and sets ``func`` and ``parser``.
COMMANDS = [simulate.add_parser, map.add_parser, track.add_parser]


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


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``rocklab`` with ``argv`` (default ``sys.argv[1:]``) and return its exit status.

    Usage errors exit (``SystemExit``) with status 2 after one line on stderr.
    """
    argv = sys.argv[1:] if argv is None else list(argv)
    args = build_parser().parse_args(argv)
    args.history = f"{datetime.now(UTC):%Y-%m-%dT%H:%M:%SZ}: rocklab {shlex.join(argv)}"
    parser: argparse.ArgumentParser = args.parser  # the subcommand's (its add_parser sets it)
    try:
        return args.func(args)
    except UsageError as err:
        parser.error(str(err))
    except CommandError as err:
        print(f"{parser.prog}: {err}", file=sys.stderr)
        return 1
