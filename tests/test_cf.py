"""Every kind of netCDF file rocklab writes passes the CF checker (CF-1.8).

``cfchecker`` (the ``test`` extra) needs the UDUNITS-2 C library
(Debian: ``libudunits2-0``); without either these tests are skipped.  The
checker reads the CF standard-name, area-type and region tables from the
web by default; rocklab's files use no standard name, area type or region,
so the tests hand it empty tables and run offline.  A ``standard_name``
added to a file then fails here until its entry of the CF table (with the
canonical units, which the checker compares) is added to :func:`tables`.
"""

import numpy as np
import pytest
import xarray as xr

from rocklab import cli
from rocklab.io import write_netcdf
from rocklab.lab import virtual_lab
from rocklab.lab.campaign import open_campaign
from rocklab.lab.motion import write_test_with_motion
from rocklab.lab.reduction import reduce_test
from rocklab.seismic.accelerograms import load_record
from rocklab.seismic.maps import overturning_map


def _checker_or_reason():
    try:
        from cfchecker.cfchecks import CFChecker
    except ImportError as exc:
        return None, f"cfchecker not installed ({exc}): pip install '.[test]'"
    except OSError as exc:  # cfunits loads UDUNITS-2 on import
        return None, f"cfchecker needs the UDUNITS-2 C library (Debian: libudunits2-0): {exc}"
    return CFChecker, ""


CFChecker, WHY = _checker_or_reason()
pytestmark = pytest.mark.skipif(CFChecker is None, reason=WHY)


@pytest.fixture(scope="module")
def tables(tmp_path_factory):
    """The checker's three tables, empty: rocklab's files use none of their entries."""
    d = tmp_path_factory.mktemp("cf-tables")
    date = "<date>2026-01-01T00:00:00Z</date>"
    (d / "standard-names.xml").write_text(
        "<standard_name_table><version_number>0</version_number>"
        "<last_modified>2026-01-01T00:00:00Z</last_modified></standard_name_table>"
    )
    (d / "area-types.xml").write_text(f"<area_type_table><version_number>0</version_number>{date}</area_type_table>")
    (d / "regions.xml").write_text(
        f"<standard_region_list><version_number>0</version_number>{date}</standard_region_list>"
    )
    return d


def cf_messages(path, tables):
    """The checker's counts and its error and warning messages for one file."""
    checker = CFChecker(
        cfStandardNamesXML=str(tables / "standard-names.xml"),
        cfAreaTypesXML=str(tables / "area-types.xml"),
        cfRegionNamesXML=str(tables / "regions.xml"),
        version="1.8",
        silent=True,
    )
    checker.checker(str(path))
    counts = checker.get_counts()
    res = checker.results
    sections = {"global": res["global"], **res["variables"]}
    messages = [
        f"{where}: {level} {msg}"
        for where, r in sections.items()
        for level in ("FATAL", "ERROR", "WARN")
        for msg in r[level]
    ]
    return counts, messages


def assert_cf(path, tables):
    counts, messages = cf_messages(path, tables)
    assert counts["FATAL"] + counts["ERROR"] == 0, "\n".join(messages)
    assert counts["WARN"] == 0, "\n".join(messages)


@pytest.fixture(scope="module")
def reduced(tmp_path_factory):
    folder = tmp_path_factory.mktemp("virtual") / "campaign"
    virtual_lab.write_campaign(folder, virtual_lab.default_plan(1, seed=5), seed=5, t_end=8.0)
    c = open_campaign(folder)
    return reduce_test(c, c.tests.test_id[0])


def test_a_reduced_test_is_cf_and_reads_back_as_seconds(reduced, tables, tmp_path):
    path = tmp_path / "T.nc"
    write_netcdf(reduced, path)
    assert_cf(path, tables)
    with xr.open_dataset(path) as back:
        assert back.time.dtype == np.float64
        xr.testing.assert_equal(back, reduced)


def test_a_reduced_test_with_its_motion_is_cf(reduced, tables, tmp_path):
    path = tmp_path / "T.nc"
    write_test_with_motion(reduced, path)
    assert_cf(path, tables)


def test_a_test_without_motion_is_cf(tables, tmp_path):
    path = tmp_path / "T.nc"
    write_test_with_motion(xr.Dataset(attrs={"test_id": "T1", "reject_detail": "no file"}), path)
    assert_cf(path, tables)


def test_an_overturning_map_is_cf(tables, tmp_path):
    path = tmp_path / "map.nc"
    write_netcdf(overturning_map(load_record("40EIC180"), model="2s-housner", n=5), path)
    assert_cf(path, tables)


@pytest.mark.parametrize("motion", [["--theta0", "0.05"], ["--record", "40EIC180", "--t-end", "6"]])
def test_the_command_line_output_is_cf(motion, tables, tmp_path):
    path = tmp_path / "sim.nc"
    assert cli.main(["simulate", "--height", "1.5", "--thickness", "0.2", *motion, "-o", str(path)]) == 0
    assert_cf(path, tables)
