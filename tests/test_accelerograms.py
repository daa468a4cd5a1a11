"""Accelerogram readers (obspy plugins), processing and the shipped Table 4 records.

Every reader is checked on a real file: first/last samples against the file
text, units (m/s^2), dt, npts, obspy autodetection, and that the other
formats' ``_is_`` functions reject it.  Files come from ``rocklab/data/accelerograms``
(shipped) or, for obspy's own formats, from obspy's installed test data.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import obspy
import pytest

import rocklab.seismic.accelerograms as acc
from rocklab.seismic.accelerograms import caltech, columns, peer, somerville
from rocklab.seismic.accelerograms._text import G

RAW = acc.accelerogram_dir()
OBSPY_DATA = Path(obspy.__file__).parent / "io"
KNET_FILE = OBSPY_DATA / "nied" / "tests" / "data" / "test.knet"
EVT_FILE = OBSPY_DATA / "kinemetrics" / "tests" / "data" / "BI008_MEMA-04823.evt"

IS_FUNCS = {
    "PEER_NGA_AT2": peer._is_peer_nga_at2,
    "PEER_LEGACY_AT2": peer._is_peer_legacy_at2,
    "CALTECH_VOL2": caltech._is_caltech_vol2,
    "SOMERVILLE": somerville._is_somerville,
    "TWO_COLUMN": columns._is_two_column,
    "MULTI_COLUMN": columns._is_multi_column,
}

# file, format, kwargs, units factor to m/s^2, dt, npts, first and last sample as written in the file,
# (column of the file for column text)
CASES = [
    ("RSN6_IMPVALL.I_I-ELC180.AT2", "PEER_NGA_AT2", {}, G, 0.01, 5372, 0.9984852e-03, -0.1790158e-03, None),
    ("RSN864_LANDERS_JOS090.AT2", "PEER_NGA_AT2", {}, G, 0.02, 2200, 0.2993323e-02, -0.2704593e-04, None),
    ("IELC180.AT2", "PEER_LEGACY_AT2", {}, G, 0.01, 4000, -0.6403182e-02, 0.9459335e-04, None),
    ("elcen07_230fn.dat", "CALTECH_VOL2", {}, 0.01, 0.02, 1845, 1.963, 6.648, None),
    ("pacoima_164.dat", "CALTECH_VOL2", {}, 0.01, 0.02, 1024, 7.754, 20.583, None),
    ("rinaldi_fn.dat", "SOMERVILLE", {}, 0.01, 0.005, 2990, -0.11237e03, -0.10803e02, None),
    ("elcentro_NS_full.dat", "TWO_COLUMN", {}, G, 0.02, 2688, -1.4275799e-003, -1.4275799e-003, 2),
    (
        "Northridge_Sylmar_County.dat",
        "TWO_COLUMN",
        {"units": "m/s2"},
        1.0,
        0.02,
        3000,
        6.1130000e-02,
        -3.5340000e-02,
        2,
    ),
    ("sct190985.txt", "MULTI_COLUMN", {"components": ["NS", "EW", "V"]}, G, 0.02, 8171, -0.00314, -0.00305, 3),
]
# RSN6 is not shipped (row 1 uses elcentro_NS_full.dat): it runs only where ../shared exists.
SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "accelerograms"


def _path(name):
    for folder in (RAW, SHARED):
        if (folder / name).exists():
            return folder / name
    pytest.skip(f"{name} is neither shipped nor in ../shared")


@pytest.mark.parametrize("name, fmt, kwargs, factor, dt, npts, first, last, column", CASES, ids=[c[0] for c in CASES])
def test_reader_on_real_file(name, fmt, kwargs, factor, dt, npts, first, last, column):
    path = _path(name)
    st = obspy.read(str(path), **kwargs)
    assert all(tr.stats._format == fmt for tr in st), "obspy.read must autodetect the format"
    tr = st[0] if column is None else next(t for t in st if t.stats.text_columns["column"] == column)
    assert tr.data.dtype == np.float64
    assert tr.stats.units == "m/s2"
    assert tr.stats.delta == pytest.approx(dt, rel=1e-9)
    assert tr.stats.npts == npts == len(tr.data)
    np.testing.assert_allclose(tr.data[[0, -1]], np.array([first, last]) * factor, rtol=1e-12)
    explicit = obspy.read(str(path), format=fmt, **kwargs)
    np.testing.assert_array_equal(explicit[0].data, st[0].data)
    headonly = obspy.read(str(path), headonly=True, **kwargs)[0]
    assert headonly.stats.npts == npts and len(headonly.data) == 0


@pytest.mark.parametrize("name, fmt", [(c[0], c[1]) for c in CASES], ids=[c[0] for c in CASES])
def test_is_functions_are_exclusive(name, fmt):
    path = str(_path(name))
    claims = {f for f, is_fmt in IS_FUNCS.items() if is_fmt(path)}
    assert claims == {fmt}


@pytest.mark.parametrize("path", [KNET_FILE, EVT_FILE], ids=["knet", "evt"])
def test_plugins_reject_obspy_formats(path):
    assert not any(is_fmt(str(path)) for is_fmt in IS_FUNCS.values())


def test_plugins_reject_sac_and_missing(tmp_path):
    sac = tmp_path / "x.sac"
    obspy.Trace(np.arange(50.0), header={"delta": 0.01}).write(str(sac), format="SAC")
    slist = tmp_path / "x.slist"
    obspy.Trace(np.arange(50.0), header={"delta": 0.01}).write(str(slist), format="SLIST")
    for path in (sac, slist, tmp_path / "missing.txt"):
        assert not any(is_fmt(str(path)) for is_fmt in IS_FUNCS.values())


def test_header_metadata():
    at2 = obspy.read(str(_path("IELC180.AT2")))[0]
    assert (at2.stats.station, at2.stats.channel) == ("EL CENTRO ARRAY #9", "180")
    assert at2.stats.at2["station_id"] == "USGS STATION 117" and at2.stats.at2["units_in_file"] == "g"
    cal = obspy.read(str(_path("elcen07_230fn.dat")))[0]
    assert cal.stats.channel == "S50W" and cal.stats.caltech["station_id"] == "USGS 5028"
    assert cal.stats.caltech["bandpass_hz"] == (0.055, 0.075, 25.0, 27.0)
    assert cal.stats.caltech["padding_dropped"] == 3
    # the header's own peak (cm/s^2) is the data maximum
    assert np.max(np.abs(cal.data)) == pytest.approx(abs(cal.stats.caltech["pga_cm_s2"]) / 100, rel=1e-6)
    som = obspy.read(str(_path("rinaldi_fn.dat")))[0]
    assert som.stats.station == "rrs" and som.stats.somerville["padding_dropped"] == 4
    sct = obspy.read(str(_path("sct190985.txt")), components=["NS", "EW", "V"])
    assert [tr.stats.channel for tr in sct] == ["NS", "EW", "V"]
    assert float(sct[0].stats.starttime.timestamp) == pytest.approx(0.02)


def test_column_units_kwarg():
    path = str(_path("Northridge_Sylmar_County.dat"))
    in_g = obspy.read(path)[0]  # documented default: g
    in_si = obspy.read(path, units="m/s2")[0]
    np.testing.assert_allclose(in_g.data, in_si.data * G)
    with pytest.raises(ValueError):
        obspy.read(path, units="furlongs")


def test_knet_in_si():
    st = acc.read_accelerogram(KNET_FILE)
    tr = st[0]
    assert tr.stats.units == "m/s2" and tr.stats.calib == 1.0
    assert tr.stats.npts == 5900 and tr.stats.delta == 0.01
    # header's max acceleration (gal) is of the mean-removed record
    assert np.max(np.abs(tr.data - tr.data.mean())) * 100 == pytest.approx(tr.stats.knet.accmax, rel=0.01)
    raw = obspy.read(str(KNET_FILE))[0]
    np.testing.assert_allclose(tr.data, raw.data * raw.stats.calib)


def test_evt_in_si():
    raw = obspy.read(str(EVT_FILE))
    st = acc.read_accelerogram(EVT_FILE)
    assert len(st) == 3 and all(tr.stats.units == "m/s2" for tr in st)
    assert st[0].stats.sampling_rate == 250.0 and st[0].stats.npts == 5750
    # 2.5 V full scale, 2.5 V/g sensor, 24 bits: one count is 9.81 / 2**23 m/s^2 (obspy's g)
    assert raw[0].stats.calib == pytest.approx(9.81 / 2**23, rel=1e-6)
    np.testing.assert_allclose(st[0].data, raw[0].data * raw[0].stats.calib)


def test_files_are_not_modified():
    path = _path("pacoima_164.dat")
    before = hashlib.sha256(path.read_bytes()).hexdigest()
    acc.load_record("Pac164")
    assert hashlib.sha256(path.read_bytes()).hexdigest() == before


# --- processing ---------------------------------------------------------------


def test_baseline_correction_removes_offset_and_drift():
    dt, n = 0.01, 4000
    t = np.arange(n) * dt
    quake = np.sin(2 * np.pi * 2.0 * t) * np.exp(-(((t - 20) / 5) ** 2))
    spoiled = quake + 0.05 + 0.002 * t  # offset and linear trend
    fixed = acc.baseline_correct_array(spoiled, dt, velocity_order=2)
    v = acc.velocity(fixed, dt)
    assert abs(v[-1]) < 1e-3 * np.max(np.abs(v))
    np.testing.assert_allclose(fixed, quake, atol=2e-3)
    filtered = acc.baseline_correct_array(quake, dt, freqmin=0.1, freqmax=20.0)
    assert acc.peak_ground_acceleration(filtered) == pytest.approx(acc.peak_ground_acceleration(quake), rel=0.01)


def test_velocity_and_durations_closed_form():
    dt = 0.001
    t = np.arange(0, 2.0 + dt / 2, dt)
    a = np.cos(2 * np.pi * t)  # v = sin(2 pi t) / (2 pi)
    assert acc.peak_ground_velocity(a, dt) == pytest.approx(1 / (2 * np.pi), rel=1e-5)
    assert acc.record_duration(2990, 0.005) == pytest.approx(14.945)  # RRS228 in Table 4
    box = np.ones(1001)  # Arias grows linearly: D5-95 = 0.9 T
    assert acc.significant_duration(box, 0.01) == pytest.approx(9.0, rel=1e-3)


# --- shipped records and Table 4 ------------------------------------------------


def test_table4():
    t4 = acc.read_table4()
    assert len(t4) == 20 and list(t4.row) == list(range(1, 21))
    assert t4.set_index("record").loc["Pac164", "pga_g"] == 1.17


def test_manifest_is_current_and_complete():
    shipped = acc.read_manifest()
    assert len(shipped) == 10 and sorted(shipped.table4_row) == [1, 2, 3, 4, 7, 8, 11, 12, 13, 14]
    fresh = acc.build_manifest()
    for col in ("file", "dt", "npts", "pga_g", "pgv_cm_s", "duration_s", "pga_match_pct", "sha256"):
        assert list(fresh[col]) == list(shipped[col]), col
    for _, row in shipped.iterrows():
        assert hashlib.sha256((RAW / row.file).read_bytes()).hexdigest() == row.sha256


# Rows whose file SOURCES.md says matches Table 4's PGA (same record and processing, or same PGA).
MATCHING = ["40EIC180", "Pac164", "IVC230", "SecreN27", "Joshua90", "Syl360ff"]


@pytest.mark.parametrize("record", MATCHING)
def test_pga_matches_table4(record):
    tr = acc.load_record(record)
    t4 = acc.read_table4().set_index("record").loc[record]
    assert tr.stats.units == "m/s2" and tr.stats.processing
    assert acc.peak_ground_acceleration(tr.data) / G == pytest.approx(t4.pga_g, rel=0.02)


def test_pga_mismatches_are_flagged():
    m = acc.read_manifest().set_index("record")
    assert set(m.index[m.pga_ok.astype(bool)]) == set(MATCHING)
    assert (m.loc[["Taft111", "TolmezWE", "LucN80W", "RRS228"], "pga_match_pct"].abs() > 2).all()
    assert m.loc["Pac164", "duration_match"] == "truncated" and m.loc["Joshua90", "duration_match"] == "truncated"


def test_load_record_by_path_needs_column_for_multitrace():
    with pytest.raises(ValueError, match="column"):
        acc.load_record(_path("sct190985.txt"))
    tr = acc.load_record(_path("sct190985.txt"), column=3)
    assert acc.peak_ground_acceleration(tr.data) / G == pytest.approx(0.17, rel=0.02)
