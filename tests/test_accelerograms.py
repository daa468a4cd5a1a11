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
from rocklab.seismic.accelerograms import caltech, columns, peer, slammer, somerville
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
    "CSV_TWO_COLUMN": columns._is_csv_two_column,
    "SLAMMER": slammer._is_slammer,
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
    ("sct190985.txt", "MULTI_COLUMN", {"components": ["NS", "EW", "V"]}, G, 0.02, 8171, -0.00314, -0.00305, 3),
    ("RSN1086_NORTHR_SYL360.AT2", "CSV_TWO_COLUMN", {}, G, 0.02, 2000, 5.832077e-03, -1.946224e-04, 2),
    ("RSN779_LOMAP_LGP000.AT2", "CSV_TWO_COLUMN", {}, G, 0.005, 5001, 2.951824e-04, 4.640200e-04, 2),
    # dt from the shipped EQdata.txt beside the file
    ("TAF-111", "SLAMMER", {}, G, 0.01, 5211, -0.00104012, -9.82012e-4, None),
    ("BCR-230", "SLAMMER", {}, G, 0.005, 7348, None, 6.96108e-4, None),
    ("E07-230", "SLAMMER", {}, G, 0.005, 7155, None, -5.18859e-4, None),
    ("NS1-280", "SLAMMER", {}, G, 0.005, 4113, None, -0.00325017, None),
    ("RRS-228", "SLAMMER", {}, G, 0.01, 1991, None, 0.00115999, None),
    ("KJM-000", "SLAMMER", {}, G, 0.02, 2238, None, -2.527e-4, None),
    ("TAK-000", "SLAMMER", {}, G, 0.01, 3978, None, -9.54109e-4, None),
    ("YPT-330", "SLAMMER", {}, G, 0.005, 5894, None, -0.00275942, None),
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
    if first is None:  # the file's first line, as written
        first = float(path.read_text().split(None, 1)[0])
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


# What each shipped file that is not a record is: claimed by no reader.
NOT_RECORDS = {"manifest.csv", "README.md", "EQdata.txt"}


def test_every_shipped_file_is_claimed_by_one_reader_only():
    """Cross-claims over the whole shipped folder: each record by exactly its own format, the rest by none."""
    manifest = acc.read_manifest().set_index("file")
    formats = {**{c[0]: c[1] for c in CASES}, **manifest["format"].to_dict()}
    shipped = sorted(p.name for p in RAW.iterdir() if p.is_file() and p.name != "__init__.py")
    assert set(shipped) - NOT_RECORDS <= set(formats), "a shipped file has no reader test and no manifest row"
    for name in shipped:
        claims = {f for f, is_fmt in IS_FUNCS.items() if is_fmt(str(RAW / name))}
        assert claims == ({formats[name]} if name in formats else set()), name


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


@pytest.mark.parametrize("name", ["elcentro_NS_full.dat", "RSN1086_NORTHR_SYL360.AT2", "TAF-111"])
def test_units_kwarg(name):
    path = str(_path(name))
    in_g = obspy.read(path)[0]  # documented default: g
    in_si = obspy.read(path, units="m/s2")[0]
    np.testing.assert_allclose(in_g.data, in_si.data * G)
    with pytest.raises(ValueError):
        obspy.read(path, units="furlongs")


def test_slammer_metadata_from_eqdata():
    tr = obspy.read(str(_path("TAF-111")))[0]
    assert (tr.stats.station, tr.stats.channel) == ("Taft, Lincoln School", "111")
    meta = tr.stats.slammer
    assert meta["event"] == "Kern County 1952" and meta["dt_source"] == str(RAW / "EQdata.txt")
    assert meta["units_in_file"] == "g" and meta["extra"] == ["43.5", "46.2", "38.9"]


def test_slammer_dt_without_table(tmp_path):
    """A SLAMMER record away from EQdata.txt needs dt=, and dt= overrides the table."""
    lone = tmp_path / "RRS-228"
    lone.write_bytes(_path("RRS-228").read_bytes())
    with pytest.raises(ValueError, match="pass dt="):
        obspy.read(str(lone))
    tr = obspy.read(str(lone), dt=0.01)[0]
    assert tr.stats.delta == 0.01 and tr.stats.slammer["dt_source"] == "dt argument"
    np.testing.assert_array_equal(tr.data, obspy.read(str(_path("RRS-228")))[0].data)
    assert obspy.read(str(_path("RRS-228")), dt=0.02)[0].stats.delta == 0.02


def test_slammer_table_in_parent_and_ambiguous_ids(tmp_path):
    """SLAMMER's layout, records/<event>/<id> with records/EQdata.txt; an id listed
    under two events with different dt is resolved by the folder, else an error."""
    table = _path("EQdata.txt").read_text()
    row = next(line for line in table.splitlines() if "\tBCR-230\t" in line)
    other = row.replace("Imperial Valley 1979", "Superstition Hills 1987").replace("\t0.005\t", "\t0.010\t")
    (tmp_path / "EQdata.txt").write_text(table + other + "\n")
    event = tmp_path / "Imperial Valley 1979"
    event.mkdir()
    (event / "BCR-230").write_bytes(_path("BCR-230").read_bytes())
    assert obspy.read(str(event / "BCR-230"))[0].stats.delta == 0.005
    elsewhere = tmp_path / "unsorted"
    elsewhere.mkdir()
    (elsewhere / "BCR-230").write_bytes(_path("BCR-230").read_bytes())
    with pytest.raises(ValueError, match="several events"):
        obspy.read(str(elsewhere / "BCR-230"))


def test_slammer_bad_table_row_names_file_and_line(tmp_path):
    (tmp_path / "EQdata.txt").write_text("Kern County 1952\t7.4\tR\tTAF-111\n")
    (tmp_path / "TAF-111").write_bytes(_path("TAF-111").read_bytes())
    with pytest.raises(ValueError, match="EQdata.txt, line 1"):
        obspy.read(str(tmp_path / "TAF-111"))


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


def test_cumulative_trapezoid_is_scipys_bit_for_bit():
    """numpy's integral in place of scipy's changes no PGV, no duration, no map."""
    from scipy.integrate import cumulative_trapezoid

    rng = np.random.default_rng(5)
    samples = [rng.normal(size=n) * 10.0 ** rng.uniform(-3, 3) for n in (1, 2, 3, 1000)]
    names = acc.read_manifest().record
    samples += [acc.load_record(name, corrected=c).data for name in names for c in (False, True)]
    for y in samples:
        for dx in (0.005, 0.01, 1 / 3, rng.uniform(1e-4, 0.1)):
            ours = acc.processing.cumulative_trapezoid(y, dx)
            assert np.array_equal(ours, cumulative_trapezoid(y, dx=dx, initial=0.0))
            assert ours.dtype == np.float64


# --- shipped records and Table 4 ------------------------------------------------


def test_table4():
    t4 = acc.read_table4()
    assert len(t4) == 20 and list(t4.row) == list(range(1, 21))
    assert t4.set_index("record").loc["Pac164", "pga_g"] == 1.17


def test_manifest_is_current_and_complete():
    shipped = acc.read_manifest()
    assert len(shipped) == 16 and sorted(shipped.table4_row) == [*range(1, 5), *range(6, 15), 18, 19, 20]
    assert shipped.record.is_unique and shipped.file.is_unique
    fresh = acc.build_manifest()
    for col in ("file", "dt", "npts", "pga_g", "pgv_cm_s", "duration_s", "pga_match_pct", "sha256"):
        assert list(fresh[col]) == list(shipped[col]), col
    for _, row in shipped.iterrows():
        assert hashlib.sha256((RAW / row.file).read_bytes()).hexdigest() == row.sha256
        assert row.identity and row.source.count("@") == 1 and row.notes, row.record


# The Table 4 check of every shipped record: PGA within 2 % and PGV within 4 % of Table 4
# unless listed here with the bound it keeps and why (the manifest's notes say more).
DEPARTURES = {
    "40EIC180": {"pgv": 28.5},  # Caltech-type processing keeps long periods; T4's PGV is the band-passed PEER one
    "TolmezWE": {"pga": 10.5},  # NGA-West2 processing of T4's component (TMZ000 has T4's PGA, not its PGV)
    "LucN80W": {"pga": 13.5, "pgv": 9.5},  # another processing/orientation than T4's, no closer file found
}
# How each record's length compares with Table 4's D.
LENGTHS = {
    "40EIC180": "match",
    "Taft111": "truncated",  # SLAMMER trims below 0.002 g
    "Pac164": "truncated",  # first 20.46 s of 41.78 s
    "TolmezWE": "match",
    "BCr230": "truncated",
    "IVC230": "truncated",
    "SecreN27": "longer",
    "IS1280": "match",
    "LGPC000": "match",
    "Joshua90": "truncated",  # 44 s of 80 s
    "LucN80W": "longer",
    "RRS228": "longer",  # NGA record, 19.9 s; T4 used the 14.945 s legacy PEER one
    "Syl360ff": "match",
    "KJM000": "truncated",
    "Tak000": "truncated",
    "YPT330": "truncated",
}


@pytest.mark.parametrize("record", list(LENGTHS))
def test_record_against_table4(record):
    """Each shipped record against its Table 4 row, from the file's own samples (not the manifest)."""
    tr = acc.load_record(record)
    t4 = acc.read_table4().set_index("record").loc[record]
    assert tr.stats.units == "m/s2" and tr.stats.processing and tr.stats.table4_row == t4.row
    raw = acc.load_record(record, corrected=False)
    bounds = {"pga": 2.0, "pgv": 4.0, **DEPARTURES.get(record, {})}
    # the baseline correction must not move the peak: the records come corrected
    assert np.max(np.abs(tr.data)) == pytest.approx(np.max(np.abs(raw.data)), rel=2e-3)
    pga = np.max(np.abs(raw.data)) / G
    v = np.concatenate([[0.0], np.cumsum(0.5 * (tr.data[1:] + tr.data[:-1]))]) * tr.stats.delta
    assert 100 * abs(pga / t4.pga_g - 1) <= bounds["pga"]
    assert 100 * abs(100 * np.max(np.abs(v)) / t4.pgv_cm_s - 1) <= bounds["pgv"]
    length = (tr.stats.npts - 1) * tr.stats.delta
    expected = LENGTHS[record]
    rel = length / t4.duration_s - 1
    assert {"match": abs(rel) <= 0.01, "truncated": rel < -0.01, "longer": rel > 0.01}[expected]
    m = acc.read_manifest().set_index("record").loc[record]
    assert m.duration_match == expected and bool(m.pga_ok) == (bounds["pga"] == 2.0)


def test_every_shipped_record_is_checked():
    assert set(acc.read_manifest().record) == set(LENGTHS) and set(DEPARTURES) <= set(LENGTHS)


def test_load_record_by_path_needs_column_for_multitrace():
    with pytest.raises(ValueError, match="column"):
        acc.load_record(_path("sct190985.txt"))
    tr = acc.load_record(_path("sct190985.txt"), column=3)
    assert acc.peak_ground_acceleration(tr.data) / G == pytest.approx(0.17, rel=0.02)


def test_table4_agreement_in_words():
    ag = acc.table4_agreement()
    assert list(ag.index) == list(acc.read_manifest().record)
    assert ag.loc["IS1280", "pga_pgv_match"] and ag.loc["IS1280", "differences"] == ""
    assert ag.loc["LucN80W", "differences"] == "PGA +13.3 %, PGV -9.1 %, 48.1 s long against 40 s"
    assert ag.loc["Pac164", "pga_pgv_match"] and ag.loc["Pac164", "duration_match"] == "truncated"
    assert set(ag.index[~ag.pga_pgv_match]) == set(DEPARTURES)
