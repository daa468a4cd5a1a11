"""`rocklab simulate` writes a netCDF history equal to the library's."""

import numpy as np
import pytest
import xarray as xr

from rocklab import cli
from rocklab.simulation.model import RockingModel
from rocklab.simulation.reference import simulate_ground


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


def test_simulate_shipped_record_by_name(tmp_path):
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
    with pytest.raises(SystemExit, match="needs --dt"):
        cli.main(["simulate", "--alpha", "0.1", "--p", "1.5", "--record", "no-such-record", "-o", str(out)])
