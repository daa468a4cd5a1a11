"""The command line: `rocklab simulate` writes a netCDF history equal to the
library's, `rocklab map` a map equal to `overturning_map`'s; every wrong
argument ends in one line naming the option and exit status 2, before
anything is computed."""

import argparse
import io
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import rocklab
from rocklab import cli
from rocklab.cli.arguments import HelpFormatter
from rocklab.cli.map import ProgressBar
from rocklab.simulation.reference import simulate_ground
from rocklab.simulation.rocking_model import RockingModel


def run(argv, capsys):
    """Exit status, stdout and stderr of ``rocklab argv``."""
    try:
        code = cli.main(argv)
    except SystemExit as exc:
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


def test_simulate_free_writes_netcdf(tmp_path):
    out = tmp_path / "free.nc"
    assert (
        cli.main(
            [
                "simulate",
                "--alpha",
                "0.1",
                "--p",
                "2.0",
                "--form",
                "linear",
                "--theta0",
                "0.05",
                "--t-end",
                "5",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    ds = xr.load_dataset(out)
    assert ds.theta.attrs["units"] == "rad" and ds.attrs["form"] == "linear"
    assert ds.sizes["impact"] >= 1
    assert 2.0 * float(ds.impact_time[0]) == pytest.approx(np.arccosh(2.0), rel=1e-9)


def test_simulate_record_matches_library(tmp_path):
    dt = 0.01
    t = np.arange(0, 3, dt)
    ag = -2.0 * np.sin(2 * np.pi * t) * (t < 1)  # in m/s^2
    rec = tmp_path / "rec.txt"
    np.savetxt(rec, ag)
    out = tmp_path / "rec.nc"
    assert (
        cli.main(
            [
                "simulate",
                "--height",
                "1.63",
                "--thickness",
                "0.113",
                "--boundary",
                "one-sided",
                "--record",
                str(rec),
                "--dt",
                str(dt),
                "-o",
                str(out),
            ]
        )
        == 0
    )
    ds = xr.load_dataset(out)
    ref = simulate_ground(RockingModel.from_wall(1.63, 0.113, boundary="one-sided"), ag, dt)
    np.testing.assert_allclose(ds.theta.values, ref.theta, atol=1e-12)
    assert ds.attrs["boundary"] == "one-sided" and bool(ds.attrs["overturned"]) == ref.overturned


def test_simulate_requires_a_wall():
    with pytest.raises(SystemExit):
        cli.main(["simulate", "--theta0", "0.01", "-o", "x.nc"])


def test_simulate_shipped_record_by_name(tmp_path, capsys):
    """A Table 4 record by manifest name, read through the obspy plugins."""
    from rocklab.seismic.accelerograms import load_record

    out = tmp_path / "elc.nc"
    assert (
        cli.main(
            [
                "simulate",
                "--alpha",
                "0.1",
                "--p",
                "1.5658",
                "--form",
                "linear",
                "--record",
                "40EIC180",
                "--scale",
                "0.5",
                "--t-end",
                "10",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    tr = load_record("40EIC180")
    ref = simulate_ground(RockingModel(alpha=0.1, p=1.5658, form="linear"), 0.5 * tr.data, tr.stats.delta, t_end=10)
    np.testing.assert_allclose(xr.load_dataset(out).theta.values, ref.theta, atol=1e-12)
    code, _, err = run(
        ["simulate", "--alpha", "0.1", "--p", "1.5", "--record", "no-such-record", "-o", str(out)], capsys
    )
    assert code == 2 and err.startswith("rocklab simulate: --record: 'no-such-record' is neither")


# --- wrong arguments: one line naming the option, exit status 2, nothing computed -----------


@pytest.fixture
def nothing_computed(monkeypatch):
    """Fail the test if a simulation or a map starts: the checks come first."""
    import rocklab.simulation.batch as batch
    import rocklab.simulation.reference as reference

    def forbidden(*args, **kwargs):
        raise AssertionError("computed before the arguments were checked")

    for module, name in (
        (reference, "simulate_free"),
        (reference, "simulate_ground"),
        (batch, "overturning_batch"),
    ):
        monkeypatch.setattr(module, name, forbidden)


WALL = ["--height", "1.63", "--thickness", "0.113"]
FREE = [*WALL, "--theta0", "0.05"]


def _bad_simulate(tmp):
    """(argv, option named in the error, text of the error) of wrong ``simulate`` calls."""
    out = ["-o", str(tmp / "out.nc")]
    text = tmp / "notes.txt"
    text.write_text("not an accelerogram\n")
    (tmp / "file").write_text("")
    two_columns = tmp / "two.txt"
    np.savetxt(two_columns, np.ones((5, 2)))
    return [
        (["--height", "-3", "--thickness", "0.2", "--theta0", "0.01", *out], "--height", "must be > 0 (got -3)"),
        (["--height", "3", "--thickness", "0", "--theta0", "0.01", *out], "--thickness", "must be > 0 (got 0)"),
        (["--height", "abc", "--thickness", "0.2", *out], "--height", "must be a number"),
        (["--height", "inf", "--thickness", "0.2", *out], "--height", "must be > 0 (got inf)"),
        (["--alpha", "1.6", "--p", "2", "--theta0", "0.01", *out], "--alpha", "must be in (0, pi/2) (got 1.6)"),
        (["--alpha", "0", "--p", "2", "--theta0", "0.01", *out], "--alpha", "must be in (0, pi/2)"),
        (["--alpha", "0.1", "--p", "-2", "--theta0", "0.01", *out], "--p", "must be > 0"),
        ([*FREE, "--alpha", "0.1", *out], "--alpha", "not both"),
        (["--height", "3", "--theta0", "0.01", *out], "--thickness", "missing"),
        (["--alpha", "0.1", "--theta0", "0.01", *out], "--p", "missing"),
        (["--theta0", "0.01", *out], "--alpha", "missing"),
        ([*FREE, "--alpha-rock", "2", *out], "--alpha-rock", "must be in (0, pi/2)"),
        ([*FREE, "--gap", "0.01", *out], "--gap", "only for --boundary one-sided"),
        ([*FREE, "--gap", "-0.01", "--boundary", "one-sided", *out], "--gap", "must be in [0, pi/2)"),
        ([*FREE, "--e-scale", "-1", *out], "--e-scale", "must be >= 0"),
        ([*FREE, "--e-scale", "1.5", *out], "--e-scale", "would create energy"),
        ([*FREE, "--amplitude-law", "0", "0.5", *out], "--amplitude-law", "A must be > 0"),
        ([*FREE, "--amplitude-law", "1.2", "-0.5", *out], "--amplitude-law", "B must be >= 0"),
        ([*FREE, "--zeta", "1", *out], "--zeta", "must be in [0, 1)"),
        ([*FREE, "--t-end", "0", *out], "--t-end", "must be > 0"),
        ([*FREE, "--fs", "-400", *out], "--fs", "must be > 0"),
        ([*FREE, "--fs", "1e9", *out], "--fs", "samples over 30 s"),
        ([*FREE, "--overturn", "2", *out], "--overturn", "must be in (0, pi/2]"),
        ([*WALL, "--theta0", "1.6", *out], "--theta0", "must be < --overturn"),
        ([*WALL, "--theta0", "-0.01", "--boundary", "one-sided", *out], "--theta0", "below -gap"),
        ([*WALL, *out], "--theta0", "free rocking needs"),
        ([*FREE, "--dt", "0.01", *out], "--dt", "only with --record"),
        ([*WALL, "--record", "no-such-record", *out], "--record", "shipped records: 40EIC180"),
        ([*WALL, "--record", str(text), *out], "--record", "cannot read"),
        ([*WALL, "--record", str(tmp / "none.txt"), "--dt", "0.01", *out], "--record", "no such file"),
        ([*WALL, "--record", str(text), "--dt", "0.01", *out], "--record", "not a one-column text file"),
        ([*WALL, "--record", str(two_columns), "--dt", "0.01", *out], "--record", "2 columns"),
        ([*WALL, "--record", str(two_columns), "--dt", "0", *out], "--dt", "must be > 0"),
        ([*WALL, "--record", "40EIC180", "--units", "g", *out], "--units", "only for a one-column"),
        ([*WALL, "--record", "40EIC180", "--boundary", "three-sided", *out], "--boundary", "invalid choice"),
        ([*FREE, "-o", str(tmp / "missing" / "out.nc")], "--output", "does not exist"),
        ([*FREE, "-o", str(tmp / "file" / "out.nc")], "--output", "is not a folder"),
        ([*FREE, "-o", str(tmp)], "--output", "is a folder"),
        ([*WALL, "--record", "40EIC180", "-o", str(tmp / "missing" / "out.nc")], "--output", "does not exist"),
        (FREE, "-o/--output", "required"),
    ]


def _bad_map(tmp):
    rec = ["--record", "40EIC180"]
    (tmp / "file").write_text("")
    return [
        (["--n", "5"], "--record", "required"),
        (["--record", "no-such-record"], "--record", "shipped records: 40EIC180"),
        ([*rec, "--model", "2s-foo"], "--model", "unknown model '2s-foo'; choose from 2s-housner"),
        ([*rec, "--model", "2s-housner", "--all-models"], "--all-models", "not allowed with argument --model"),
        ([*rec, "--eq17", "1.2", "0.4"], "--eq17", "only for --model 1s-eq17"),
        ([*rec, "--model", "1s-eq17", "--eq17", "-1", "0.4"], "--eq17", "A must be > 0"),
        ([*rec, "--n", "1"], "--n", "must be >= 2 (got 1)"),
        ([*rec, "--n", "2.5"], "--n", "must be an integer"),
        ([*rec, "--lo", "0"], "--lo", "must be > 0"),
        ([*rec, "--lo", "1.5", "--hi", "0.5"], "--hi", "must be > --lo"),
        ([*rec, "--hi", "nan"], "--hi", "must be > 0 (got nan)"),
        ([*rec, "--alpha", "2"], "--alpha", "must be in (0, pi/2)"),
        ([*rec, "--R", "-3"], "--R", "must be > 0"),
        ([*rec, "--height", "3", "--alpha", "0.1"], "--alpha", "not both"),
        ([*rec, "--thickness", "0.3"], "--height", "missing"),
        ([*rec, "--threads", "0"], "--threads", "must be >= 1"),
        ([*rec, "--threads", "100000"], "--threads", "at most"),
        ([*rec, "--polarity", "2"], "--polarity", "invalid choice"),
        ([*rec, "--all-models", "-o", str(tmp / "map.nc")], "--output", "{model}"),
        ([*rec, "-o", str(tmp / "missing" / "map.nc")], "--output", "does not exist"),
        ([*rec, "--figure", str(tmp / "file" / "map.png")], "--figure", "is not a folder"),
        ([*rec, "--figure", str(tmp / "map.xyz")], "--figure", "unknown figure format 'xyz'"),
    ]


@pytest.mark.parametrize("command, cases", [("simulate", _bad_simulate), ("map", _bad_map)])
def test_every_wrong_argument_is_one_line_and_exit_2(command, cases, tmp_path, capsys, nothing_computed):
    for argv, option, text in cases(tmp_path):
        code, out, err = run([command, *argv], capsys)
        assert code == 2, argv
        assert err.startswith(f"rocklab {command}: {option}: ") and text in err, (argv, err)
        assert err.count("\n") == 1 and "Traceback" not in err and out == "", (argv, err)
    assert not list(tmp_path.glob("*.nc")) and not list(tmp_path.glob("*.png"))


def test_a_real_process_prints_one_line_and_exits_2(tmp_path):
    """The installed command: no traceback reaches the terminal."""
    env = {**os.environ, "PYTHONPATH": str(Path(rocklab.__file__).parents[1])}
    for argv in (["--height", "-3", "--thickness", "0.2"], ["--theta0", "0.1", "--alpha", "0.1", "--p", "2"]):
        done = subprocess.run(
            [sys.executable, "-m", "rocklab.cli", "simulate", *argv, "-o", str(tmp_path / "no" / "x.nc")],
            capture_output=True,
            text=True,
            env=env,
        )
        assert done.returncode == 2 and done.stdout == ""
        assert done.stderr.count("\n") == 1 and done.stderr.startswith("rocklab simulate: --")


def test_a_failing_write_is_one_line_and_exit_1(tmp_path, capsys, monkeypatch):
    """A disk that fills up after the checks: one line, status 1, no traceback."""
    import rocklab.io

    def full(ds, path):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(rocklab.io, "write_netcdf", full)
    code, out, err = run(["simulate", *FREE, "--t-end", "1", "-o", str(tmp_path / "x.nc")], capsys)
    assert code == 1 and out == ""
    assert err == f"rocklab simulate: --output: cannot write {tmp_path / 'x.nc'}: [Errno 28] No space left on device\n"


# --- help, version --------------------------------------------------------------------------


def _subparsers():
    parser = cli.build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices


@pytest.mark.parametrize("command", ["simulate", "map"])
def test_help_gives_every_default_and_unit(command, capsys):
    code, out, _ = run([command, "--help"], capsys)
    assert code == 0 and "examples:" in out and f"rocklab {command} " in out
    flat = " ".join(out.split())
    for action in _subparsers()[command]._actions:
        if action.dest in ("help", "quiet", "all_models"):
            continue
        text = " ".join(HelpFormatter("rocklab")._get_help_string(action).split())
        text = text % {"default": action.default}
        assert text in flat, text
        # a number carries its unit ([m], [rad], [-]...), a count (metavar N) is one; every default is shown
        counted = action.metavar == "N" or action.dest == "n"
        assert action.type is None or action.choices or counted or "[" in text, f"{action.option_strings}: no unit"
        assert action.default is None or "(default:" in text, f"{action.option_strings}: no default"


def test_help_of_simulate_names_defaults_and_units(capsys):
    _, out, _ = run(["simulate", "--help"], capsys)
    flat = " ".join(out.split())
    for text in ("wall height h [m]", "(default: two-sided)", "--e-scale C", "(default: 1.0)", "(default: pi/2)"):
        assert text in flat


def test_version(capsys):
    code, out, _ = run(["--version"], capsys)
    assert code == 0 and out == f"rocklab {rocklab.__version__}\n"


# --- rocklab map ----------------------------------------------------------------------------


def test_map_of_a_shipped_record_equals_the_library(tmp_path, capsys):
    from rocklab.seismic.accelerograms import load_record
    from rocklab.seismic.indices import map_indices
    from rocklab.seismic.maps import overturning_map

    nc, png = tmp_path / "map.nc", tmp_path / "map.png"
    code, out, err = run(
        ["map", "--record", "40EIC180", "--n", "5", "--chunks", "5", "-o", str(nc), "--figure", str(png)], capsys
    )
    assert code == 0
    ref = overturning_map(load_record("40EIC180"), n=5)
    ds = xr.load_dataset(nc)
    np.testing.assert_array_equal(ds.overturned.values, ref.overturned.values)
    np.testing.assert_array_equal(ds.amplitude_scale.values, ref.amplitude_scale.values)
    for key in ("record", "model", "alpha", "R", "p", "form", "boundary", "dt", "npts"):
        assert ds.attrs[key] == ref.attrs[key], key
    assert "rocklab map --record 40EIC180" in ds.attrs["history"]
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    ix = map_indices(ref.overturned)
    assert f"{nc}: 40EIC180 2s-housner: N_O = {ix['N_O']:.4f}, N_D = {ix['N_D']:.4f}, N_A = {ix['N_A']:.4f}" in out
    assert out.rstrip().endswith(f"{png}: 1 map")
    # not a terminal: one line of progress per 10 % (5 blocks of rows: 0, 20, 40, 60, 80, 100 %)
    lines = err.splitlines()
    assert len(lines) == 6 and lines[-1].startswith("[" + "#" * 30 + "] 100 %") and "\r" not in err


def test_map_of_a_column_file_for_a_wall_and_two_models(tmp_path, capsys):
    """A user's one-column record in g, a wall by height and thickness, Eq. 17 coefficients."""
    from rocklab.physics import wall
    from rocklab.seismic.maps import overturning_map

    dt = 0.01
    t = np.arange(0, 4, dt)
    ag_g = 0.4 * np.sin(2 * np.pi * 1.5 * t) * (t < 2)
    rec = tmp_path / "pulse.txt"
    np.savetxt(rec, ag_g)
    argv = ["map", "--record", str(rec), "--dt", str(dt), "--units", "g", "--height", "2", "--thickness", "0.25"]
    argv += ["--model", "2s-housner", "1s-eq17", "--eq17", "1.1", "0.4", "--n", "4", "-q", "-o"]
    code, out, err = run([*argv, str(tmp_path / "m_{model}.nc")], capsys)
    assert code == 0 and err == ""
    ds = xr.load_dataset(tmp_path / "m_1s-eq17.nc")
    assert ds.attrs["record"] == "pulse" and (ds.attrs["impact_a"], ds.attrs["impact_b"]) == (1.1, 0.4)
    assert ds.attrs["alpha"] == pytest.approx(float(wall.slenderness_angle(2, 0.25)))
    assert ds.attrs["R"] == pytest.approx(float(wall.half_diagonal(2, 0.25)))
    ref = overturning_map(9.80665 * ag_g, dt, "2s-housner", 4, alpha=ds.attrs["alpha"], R=ds.attrs["R"], name="pulse")
    np.testing.assert_array_equal(xr.load_dataset(tmp_path / "m_2s-housner.nc").overturned, ref.overturned)
    assert out.count("\n") == 2


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_progress_bar_redraws_on_a_terminal_and_logs_every_10_percent_elsewhere():
    tty, log = _Terminal(), io.StringIO()
    for stream in (tty, log):
        bar = ProgressBar("40EIC180 2s-housner", stream=stream, width=10)
        for done in range(101):
            bar(done, 100)
    assert tty.getvalue().count("\r") == 101 and tty.getvalue().endswith("40EIC180 2s-housner\n")
    assert "[#####     ]  50 %" in tty.getvalue()
    lines = log.getvalue().splitlines()
    assert len(lines) == 11 and lines[5].startswith("[#####     ]  50 %") and "\r" not in log.getvalue()
