"""``rocklab track``: a filmed test in, its rotation record out, with a figure of the tracked markers.

For labs that only want theta: the four markers of the film tracked
(:func:`rocklab.lab.video_tracking.track_video`), theta written as the lab's
``# record: rotation`` text (``docs/raw-format.md``; lost frames empty), and
the markers found drawn on the first frame (:func:`rocklab.plots.video_tracking.tracked_markers`).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from rocklab.cli.arguments import CommandError, HelpFormatter, UsageError, check_figure_format, check_writable


def _outputs(args: argparse.Namespace) -> tuple[Path, Path]:
    """The record and the figure to write: the options, or beside the video."""
    video = Path(args.video)
    stem = video.with_suffix("")
    record = Path(args.output) if args.output else stem.with_name(stem.name + ".rotation.csv.gz")
    figure = Path(args.figure) if args.figure else stem.with_name(stem.name + ".markers.png")
    return record, figure


def track(args: argparse.Namespace) -> int:
    """Track a film's markers; write its rotation record and the figure.

    Returns
    -------
    int
        Exit status 0.
    """
    from rocklab.lab.raw_format import RawFormatError
    from rocklab.lab.video_tracking import first_frame, track_video
    from rocklab.lab.virtual_instruments import write_instrument_record
    from rocklab.plots import save_png
    from rocklab.plots.video_tracking import tracked_markers

    video = Path(args.video)
    if not video.is_file():
        raise UsageError("VIDEO", f"{video}: no such file")
    record, figure = _outputs(args)
    if not record.name.endswith((".csv", ".csv.gz")):
        raise UsageError("--output", f"{record}: a rotation record is .csv.gz (or .csv)")
    check_writable(record, "--output")
    check_writable(figure, "--figure")
    check_figure_format(figure)
    try:
        tr = track_video(video, progress=None if args.progress else False)
        frame = first_frame(video)
    except RawFormatError as err:
        raise CommandError(str(err)) from None
    test_id = args.test_id or video.stem
    source = f"rocklab track {video.name}: {tr.frames_tracked} of {tr.time.size} frames tracked"
    try:
        write_instrument_record(
            record, test_id, "rotation", tr.fs, tr.time, {"theta_rad": tr.theta}, source=f"{source} ({args.history})"
        )
    except OSError as err:
        raise CommandError(f"--output: cannot write {record}: {err}") from None
    first = next((i for i, c in enumerate(tr.centroids) if (c == c).all()), 0)
    fig = tracked_markers(frame, tr.centroids[first], tr.diameter_px, f"{video.name}: frame {first}")
    save_png(fig, figure, 150)
    print(
        f"{record}: {tr.time.size} frames at {tr.fs:g} Hz, {tr.frames_tracked} tracked,"
        f" tracking noise {tr.noise_rad:.2g} rad; {figure}"
    )
    return 0


TRACK_EPILOG = """\
examples:
  rocklab track wall3.mp4
  rocklab track wall3.mp4 -o tests/W3.csv.gz --figure wall3.png --test-id W3
"""


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = sub.add_parser(
        "track",
        help="track the four markers of a filmed test: its rotation record and a figure",
        description="Track the four markers of a filmed test (two on the wall's end face, two on a\n"
        "plumb post: docs/raw-format.md) and write theta as the lab's rotation record,\n"
        "with a figure of the markers found on the first frame.",
        epilog=TRACK_EPILOG,
        formatter_class=HelpFormatter,
    )
    p.add_argument("video", metavar="VIDEO", help="the film (.mp4, .avi, .mov or any container OpenCV reads)")
    p.add_argument(
        "-o",
        "--output",
        metavar="FILE.csv.gz",
        help="rotation record to write (default: VIDEO's name .rotation.csv.gz)",
    )
    p.add_argument("--figure", metavar="FILE.png", help="figure to write (default: VIDEO's name .markers.png)")
    p.add_argument("--test-id", metavar="ID", help="the record's test_id (default: VIDEO's name)")
    p.add_argument("--progress", action="store_true", help="a progress bar on a terminal, however short the film")
    p.set_defaults(func=track, parser=p)
