"""Reduction of one test: raw record to wall motion and validity, as netCDF.

Composes :mod:`rocklab.lab.campaign` and :mod:`rocklab.lab.records`
(readers), :mod:`rocklab.lab.channels` (health),
:mod:`rocklab.lab.kinematics` (four degrees of freedom) and
:mod:`rocklab.lab.validity` (the lab's rules) into one ``xarray.Dataset`` per
test with CF-style attributes, and turns a set of them into the QC table.
A test recorded by another instrument (its record's ``# record:``) is
reduced by :mod:`rocklab.lab.rotation` or :mod:`rocklab.lab.inertial`
to the same variables (``theta``, ``phi``, ``v``, ``w`` on ``time``) and
judged by the same rules, so that everything downstream runs unchanged;
``instrument`` says which (:data:`rocklab.lab.instrument.QC_COLUMNS`).
"""

from __future__ import annotations

import json
import logging
import re
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

from rocklab.disk import write_text
from rocklab.io import cf_attrs
from rocklab.lab import channel_gain, inertial, instrument, kinematics, rotation, validity
from rocklab.lab import channels as health
from rocklab.lab.campaign import TEST_COLUMNS, Campaign, row_series
from rocklab.lab.motion import noise_level
from rocklab.lab.native_files import check_setup_channels, read_test_file
from rocklab.lab.raw_format import RawFormatError
from rocklab.lab.records import (
    INERTIAL_COLUMNS,
    TRANSDUCERS,
    InertialRecord,
    Record,
    RotationRecord,
    check_sensor,
)
from rocklab.physics import wall
from rocklab.physics.boundary import Boundary

log = logging.getLogger(__name__)

#: Defaults of the config sections a reduction reads.
DEFAULTS: dict[str, Mapping[str, Any]] = {"channels": health.OPTIONS, "validity": validity.RULES}

QC_COLUMNS = [
    "test_id",
    "series",
    "valid",
    "reject_reason",
    "reject_detail",
    "residual_top_mm",
    "release_velocity_ratio",
    "channels_used",
    "flags",
    *validity.FAULT_COLUMNS,
    *instrument.QC_COLUMNS,
    *channel_gain.SETUP_COLUMNS,
]


def _options(options: Mapping[str, Any] | None) -> dict[str, dict[str, Any]]:
    out: dict[str, dict[str, Any]] = {k: dict(v) for k, v in DEFAULTS.items()}
    for key, val in (options or {}).items():
        if key in out and isinstance(val, dict):
            out[key].update(val)
    return out


#: Names of the test log's columns that become attributes of a reduced test (``log_<column>``).
LOG_COLUMN = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,63}")


def log_values(row: pd.Series) -> dict[str, float]:
    """The test log's own columns of a tests.csv row (beyond :data:`rocklab.lab.campaign.TEST_COLUMNS`), as numbers.

    ``log_<column>``: a number as written, a date or time (ISO 8601) in
    days since 1970-01-01; a value that is neither (an operator's remark)
    or empty, and a column whose name is no identifier (it names an
    attribute of the reduced test), are left out.  What a drift between
    tests may follow (:mod:`rocklab.diagnosis.causes.restitution_drift`).
    """
    out: dict[str, float] = {}
    for col, text in row.items():
        if col in TEST_COLUMNS or col == "line" or not str(text).strip() or not LOG_COLUMN.fullmatch(str(col)):
            continue
        try:
            value = float(text)
        except ValueError:
            try:
                value = (pd.Timestamp(str(text)).tz_localize(None) - pd.Timestamp(0)) / pd.Timedelta(days=1)
            except (ValueError, TypeError, OverflowError):
                continue
        if np.isfinite(value):
            out[f"log_{col}"] = float(value)
    return out


def test_metadata(campaign: Campaign, test_id: str) -> dict[str, Any]:
    """Specimen, setup and wall constants of a test (lengths in mm, SI for p), its log (:func:`log_values`)."""
    row = campaign.test_row(test_id)
    spec = campaign.specimen(row.specimen)
    h, b = float(spec.height_mm), float(spec.thickness_mm)
    alpha = float(wall.slenderness_angle(h, b))
    R = float(wall.half_diagonal(h, b)) / 1000.0
    p = float(wall.frequency_parameter(R))
    cd = float(row.contact_depth_mm) if row.boundary == Boundary.ONE_SIDED else np.nan
    return {
        "test_id": test_id,
        "specimen": row.specimen,
        "series": row_series(row),
        "boundary": row.boundary,
        "contact_depth_mm": cd,
        "direction": row.direction,
        "setup": row.setup,
        "note": row.note,
        "unit": spec.unit,
        "wall": str(spec.wall),
        "length_mm": float(spec.length_mm),
        "height_mm": h,
        "thickness_mm": b,
        "unit_weight_kN_m3": float(spec.unit_weight_kN_m3),
        "h_over_b": h / b,
        "alpha": alpha,
        "R_m": R,
        "p": p,
        "overturning_velocity": float(wall.overturning_velocity(alpha, p)),
        **log_values(row),
    }


def _row_metadata(campaign: Campaign, test_id: str) -> dict[str, Any]:
    row = campaign.test_row(test_id)
    return {"test_id": test_id, "specimen": row.specimen, "series": "", "boundary": row.boundary}


#: CF ``source`` of a reduced test, by the instrument that recorded it.
SOURCE = {
    TRANSDUCERS: "laboratory free-rocking test, displacement transducers",
    "rotation": "laboratory free-rocking test, rotation record (motion capture, inclinometer or video)",
    "inertial": "laboratory free-rocking test, gyroscope and accelerometer on the wall",
}


def _unreadable(meta: Mapping[str, Any], error: Exception) -> xr.Dataset:
    ds = xr.Dataset(attrs={**_cf_attrs(meta["test_id"]), **{k: v for k, v in meta.items() if v is not None}})
    ds.attrs.update(
        valid=0,
        reject_reason=validity.Verdict.UNREADABLE,
        reject_detail=str(error),
        flags="",
        channels_used="",
        **validity.NO_FAULTS,
    )
    return ds


def _cf_attrs(test_id: str, kind: str = TRANSDUCERS) -> dict[str, str]:
    return cf_attrs(f"rocklab reduction of test {test_id}", SOURCE[kind])


def reduce_test(
    campaign: Campaign,
    test_id: str,
    options: Mapping[str, Any] | None = None,
    layouts: dict[tuple[str, float], validity.SetupLayout] | None = None,
) -> xr.Dataset:
    """Reduce one test to a dataset: raw and repaired readings, motion, QC.

    Never raises for a bad record: an unreadable one gives a dataset with
    ``reject_reason = 'unreadable'`` and the reader's message (file, row,
    problem) in ``reject_detail``.

    Parameters
    ----------
    campaign : Campaign
        From :func:`rocklab.lab.campaign.open_campaign`.
    test_id : str
    options : dict, optional
        ``channels`` and ``validity`` sections of the workflow config.
    layouts : dict, optional
        The :func:`rocklab.lab.validity.setup_layout` of each (setup, wall
        thickness) met so far, filled as tests need them (:func:`reduce_tests`
        shares one between its tests).
    """
    opt = _options(options)
    if test_id in campaign.log.errors:
        return _unreadable(_row_metadata(campaign, test_id), campaign.log.errors[test_id])
    meta = test_metadata(campaign, test_id)
    path = campaign.record_path(test_id)
    meta["source_file"] = str(path)
    try:
        rec = read_test_file(path, expected_test_id=test_id)
        if isinstance(rec, InertialRecord):
            check_sensor(rec, meta["length_mm"], meta["height_mm"], meta["thickness_mm"])
    except RawFormatError as exc:
        return _unreadable(meta, exc)
    if not isinstance(rec, Record):
        return _reduce_instrument(meta, rec, opt)
    if not meta["setup"]:
        return _unreadable(
            meta, RawFormatError(path, None, "a transducer record, but tests.csv gives the test no setup")
        )
    return _reduce_transducers(campaign, meta, rec, opt, {} if layouts is None else layouts)


#: CF ``long_name`` of the wall's degrees of freedom in a reduced test, whatever the instrument.
DOF_LONG_NAMES = {
    "theta": "rocking rotation about the active base edge (Eqs. 3-7)",
    "phi": "twist about the vertical axis",
    "v": "base sliding along x",
    "w": "base sliding along y",
}


#: CF ``long_name`` of the top corners' displacement of a reduced test (the out-of-plumb rule).
TOP_Y_LONG_NAME = "y displacement of the top corners (x = -L/2, +L/2)"


def _reduce_transducers(
    campaign: Campaign,
    meta: dict[str, Any],
    rec: Record,
    opt: Mapping[str, Mapping[str, Any]],
    layouts: dict[tuple[str, float], validity.SetupLayout],
) -> xr.Dataset:
    """:func:`reduce_test` of a transducer record: channel health, four-DOF kinematics, the lab's rules."""
    test_id, path = meta["test_id"], rec.path
    key = (meta["setup"], meta["thickness_mm"])
    if key not in layouts:
        layouts[key] = validity.setup_layout(campaign.setup(meta["setup"]), meta["thickness_mm"])
    layout = layouts[key]
    missing = sorted(set(rec.channels) - set(layout.channels))
    if missing:
        return _unreadable(
            meta,
            RawFormatError(path, None, f"channel(s) {missing} not described in setups.csv for setup {meta['setup']}"),
        )
    try:
        check_setup_channels(rec, layout.channels)
    except RawFormatError as exc:
        return _unreadable(meta, exc)
    # the rows of setups.csv of the record's channels, in its order (a setup's channels are unique)
    row_of = {ch: i for i, ch in enumerate(layout.channels)}
    rows = np.array([row_of[ch] for ch in rec.channels], int)
    c = opt["channels"]
    repaired, reports = health.assess_channels(
        rec.readings, rec.fs, rec.channels, c["flat_run_s"], c["max_gap_s"], c["dead_span_mm"]
    )
    # a transducer of the setup with no column in the record is lost like a dead one (the backup stands in)
    all_roles = layout.roles
    absent = sorted(set(layout.channels) - set(rec.channels))
    lost = {r.channel for r in reports if r.lost} | set(absent)
    choice = validity.choose_channels(
        all_roles, lost, c["backup"], c["policy"], opt["validity"]["max_lost_out_of_plane"], absent
    )

    wall_xyz, frame_xyz = layout.wall_xyz[rows], layout.frame_xyz[rows]
    col = {ch: i for i, ch in enumerate(rec.channels)}
    weights = np.zeros(len(rec.channels))
    weights[[col[ch] for ch in choice.used]] = 1.0
    # every healthy channel, backups included, is a witness of the rigid body: a gain that
    # disagrees with it is corrected before the motion is solved (issue 42, item 1)
    healthy = np.array([ch not in lost for ch in rec.channels], float)
    gains = channel_gain.channel_gains(
        repaired, wall_xyz, frame_xyz, meta["thickness_mm"], rec.channels, weights=healthy, solve_v=choice.solve_v
    )
    named = gains.named
    gain_flags = []
    if named is not None and gains.identifiable:
        repaired = repaired.copy()
        repaired[:, col[named.channel]] /= named.gain
        gain_flags.append(f"ch{named.channel} gain {named.gain:.4f} [{named.low:.4f}, {named.high:.4f}] corrected")
    elif named is not None:
        gain_flags.append(f"a channel's gain disagrees with the rigid body (ch{named.channel}?), not identified")
    motion, motion_attrs = kinematics.wall_motion_variables(
        rec.time,
        repaired,
        wall_xyz,
        frame_xyz,
        meta["thickness_mm"],
        alpha=meta["alpha"],
        weights=weights,
        solve_v=choice.solve_v,
    )

    theta, phi, v, w = (motion[k][1] for k in DOF_LONG_NAMES)
    judged, top = validity.judge_motion(meta, rec.time, rec.fs, theta, phi, v, w, choice.malfunction, opt["validity"])

    flags = [d for d in (r.describe() for r in reports) if d] + choice.flags + gain_flags
    # the channel variables in one assign: each added one by one is a merge
    channel_vars: dict[str, tuple[Any, np.ndarray, dict[str, Any]]] = {
        # an identifier, but CF wants units on a numeric coordinate: a number is dimensionless
        "channel": ("channel", np.asarray(rec.channels, int), {"long_name": "transducer channel number", "units": "1"}),
        "raw": (("time", "channel"), rec.readings, {"units": "mm", "long_name": "transducer elongation as recorded"}),
        "elongation": (
            ("time", "channel"),
            repaired,
            {
                "units": "mm",
                "long_name": "transducer elongation, spikes and short gaps repaired, frozen stretches removed",
            },
        ),
        "channel_status": (
            "channel",
            np.array([r.status for r in reports], dtype=object),
            {"long_name": "ok, repaired, dead, stuck, clipped or dropout"},
        ),
        "channel_role": (
            "channel",
            all_roles.role.to_numpy()[rows].astype(object),
            {"long_name": "out_of_plane, in_plane or monitor (from geometry)"},
        ),
        "channel_used": (
            "channel",
            weights.astype(np.int8),
            {
                "long_name": "transducer used in the kinematics",
                "flag_values": np.array([0, 1], np.int8),
                "flag_meanings": "unused used",
            },
        ),
        "channel_noise": (
            "channel",
            np.array([r.noise_mm for r in reports]),
            {"units": "mm", "long_name": "robust noise standard deviation"},
        ),
        "channel_gain": (
            "channel",
            np.array([next((g.gain for g in gains.gains if g.channel == ch), np.nan) for ch in rec.channels]),
            {
                "units": "1",
                "long_name": "gain of the transducer against the rigid-body fit of the healthy channels "
                "(NaN: in no redundant direction)",
            },
        ),
    }
    for i, axis in enumerate("xyz"):
        channel_vars[f"wall_{axis}"] = (
            "channel",
            wall_xyz[:, i],
            {"units": "mm", "long_name": f"transducer point on the wall, {axis} (body frame)"},
        )
        channel_vars[f"frame_{axis}"] = (
            "channel",
            frame_xyz[:, i],
            {"units": "mm", "long_name": f"transducer point on the frame, {axis} (lab frame)"},
        )
    channel_vars["top_y"] = (
        ("time", "corner"),
        top,
        {"units": "mm", "long_name": TOP_Y_LONG_NAME},
    )
    for k, long_name in DOF_LONG_NAMES.items():
        motion[k][2].update(long_name=long_name)
    motion["residual_rms"][2]["long_name"] = "root mean square residual of the kinematic fit over the used transducers"
    motion["n_channels"][2].update(long_name="number of transducers in the kinematic fit", units="1")
    motion["converged"][2].update(
        long_name="kinematic fit converged", flag_values=np.array([0, 1], np.int8), flag_meanings="no yes"
    )
    if "theta_eq8" in motion:
        motion["theta_eq8"][2].update(long_name="rocking rotation from the highest transducer along y (Eq. 8)")
    # the record has no date, so no CF time axis: seconds from its start (rocklab.io)
    motion["time"][2].update(long_name="time since the start of the record", units="s")
    # one Dataset of the motion's variables and the channels': each added to another is a merge
    ds = xr.Dataset({**motion, **channel_vars}, attrs=motion_attrs)

    ds.attrs.update({k: v for k, v in meta.items() if not (isinstance(v, float) and np.isnan(v))})
    ds.attrs.update(
        **_cf_attrs(test_id),
        sha256=rec.sha256,
        sampling_rate_hz=rec.fs,
        **judged,
        channels_used=" ".join(f"ch{c}" for c in choice.used),
        flags="; ".join(flags),
        **validity.channel_faults(reports, choice),
        channel_reports=json.dumps([r.__dict__ for r in reports], default=float),
        residual_rms_median_mm=float(np.nanmedian(ds.residual_rms.values))
        if np.isfinite(ds.residual_rms.values).any()
        else np.nan,
        instrument=TRANSDUCERS,
        **channel_gain.qc_values(gains),
    )
    return ds


def _reduce_instrument(
    meta: dict[str, Any], rec: RotationRecord | InertialRecord, opt: Mapping[str, Mapping[str, Any]]
) -> xr.Dataset:
    """:func:`reduce_test` of a rotation or inertial record: the instrument's motion, the lab's rules."""
    if isinstance(rec, RotationRecord):
        kind, m = "rotation", rotation.rotation_motion(rec, meta["alpha"], noise_level)
        used = " ".join(f"{k}_{'rad' if k in ('theta', 'phi') else 'mm'}" for k in rec.dof)
    else:
        kind, m = "inertial", inertial.inertial_motion(rec, meta["alpha"], meta["p"])
        used = " ".join(INERTIAL_COLUMNS)
    units = {"theta": "rad", "phi": "rad", "v": "mm", "w": "mm"}
    dof = [getattr(m, k) for k in DOF_LONG_NAMES]
    data = {k: ("time", x, {"units": units[k], "long_name": DOF_LONG_NAMES[k]}) for k, x in zip(DOF_LONG_NAMES, dof)}
    ds = xr.Dataset(
        {**data, **m.variables},
        coords={"time": ("time", rec.time, {"long_name": "time since the start of the record", "units": "s"})},
    )
    b = meta["thickness_mm"]
    rules = opt["validity"]
    judged, top = validity.judge_motion(meta, rec.time, rec.fs, m.theta, m.phi, m.v, m.w, m.malfunction, rules)
    ds["top_y"] = (("time", "corner"), top, {"units": "mm", "long_name": TOP_Y_LONG_NAME})
    ds.attrs.update({k: v for k, v in meta.items() if not (isinstance(v, float) and np.isnan(v))})
    ds.attrs.update(
        **_cf_attrs(meta["test_id"], kind),
        sha256=rec.sha256,
        sampling_rate_hz=rec.fs,
        **judged,
        channels_used=used,
        flags="; ".join(m.flags),
        **{**validity.NO_FAULTS, **m.faults, "in_plane_lost": int("v" not in getattr(rec, "dof", {}))},
        **{f"peak_{k}": v for k, v in kinematics.normalised_peaks(m.theta, m.phi, m.v, m.w, meta["alpha"], b).items()},
        **{**instrument.NO_VALUES, **m.attrs},
        instrument=kind,
    )
    return ds


def reduce_tests(
    campaign: Campaign, test_ids: Iterable[str], options: Mapping[str, Any] | None = None
) -> Iterator[tuple[str, xr.Dataset]]:
    """:func:`reduce_test` of each test, one bad test never stopping the rest.

    A reduction that fails on a record the reader accepted (a defect of
    ours or a record no rule foresaw) gives that test an ``unreadable``
    entry naming the file and the error, and is logged with its traceback.

    Yields
    ------
    (test_id, xarray.Dataset)
    """
    layouts: dict[tuple[str, float], validity.SetupLayout] = {}
    for test_id in test_ids:
        try:
            ds = reduce_test(campaign, test_id, options, layouts)
        except Exception as exc:  # isolate the test: the error is kept in its entry
            log.exception("%s: reduction failed", test_id)
            ds = _unreadable(
                _row_metadata(campaign, test_id),
                RuntimeError(f"{campaign.record_path(test_id)}: reduction failed: {exc!r}"),
            )
        yield test_id, ds


def qc_row(ds: xr.Dataset | SimpleNamespace) -> dict[str, Any]:
    """One row of ``qc.csv`` from a reduced test (or its ``attrs``, :func:`row_attrs`)."""
    a = ds.attrs
    return {
        "test_id": a["test_id"],
        "series": a["series"],
        "valid": bool(a["valid"]),
        "reject_reason": a.get("reject_reason", ""),
        "reject_detail": a.get("reject_detail", ""),
        "residual_top_mm": a.get("residual_top_mm", np.nan),
        "release_velocity_ratio": a.get("release_velocity_ratio", np.nan),
        "channels_used": a.get("channels_used", ""),
        "flags": a.get("flags", ""),
        **{c: a.get(c, validity.NO_FAULTS[c]) for c in validity.FAULT_COLUMNS},
        "in_plane_lost": bool(a.get("in_plane_lost", 0)),
        "instrument": a.get("instrument", ""),
        **{c: a.get(c, v) for c, v in instrument.NO_VALUES.items()},
    }


def qc_table(datasets: Iterable[xr.Dataset | SimpleNamespace], campaign: Campaign) -> pd.DataFrame:
    """QC table, one row per row of ``tests.csv`` (duplicates included).

    ``datasets``: reduced tests, or anything with their ``attrs`` (:func:`row_attrs`).
    """
    rows = {ds.attrs["test_id"]: qc_row(ds) for ds in datasets}
    out: list[dict[str, Any]] = []
    for key, err in campaign.log.errors.items():
        if "@" in key:
            tid, line = key.split("@")
            out.append(
                {
                    "test_id": tid,
                    "series": "",
                    "valid": False,
                    "reject_reason": validity.Verdict.UNREADABLE,
                    "reject_detail": str(err),
                    "residual_top_mm": np.nan,
                    "release_velocity_ratio": np.nan,
                    "channels_used": "",
                    "flags": "",
                    **validity.NO_FAULTS,
                    "in_plane_lost": False,
                    "instrument": "",
                    **instrument.NO_VALUES,
                }
            )
    seen: set[str] = set()
    table: list[dict[str, Any]] = []
    for tid in campaign.tests.test_id:
        if tid in seen or tid not in rows:
            continue
        seen.add(tid)
        table.append(rows[tid])
    _pool_gains(table, campaign)
    for row in out:
        row.update(NO_SETUP_GAIN)
    return pd.DataFrame(table + out, columns=QC_COLUMNS)


#: :data:`rocklab.lab.channel_gain.SETUP_COLUMNS` of a row with no setup pooled.
NO_SETUP_GAIN = dict(zip(channel_gain.SETUP_COLUMNS, ("", np.nan, np.nan, np.nan, 0)))


def _pool_gains(table: list[dict[str, Any]], campaign: Campaign) -> None:
    """Fill the rows' per-setup gain columns (in place): each transducer test's setup pooled over its tests."""
    setups = [str(campaign.test_row(r["test_id"]).setup) if r["instrument"] == TRANSDUCERS else "" for r in table]
    idx = [i for i, s in enumerate(setups) if s]
    pooled = channel_gain.pool_setups(
        [setups[i] for i in idx],
        [table[i]["gain_channel"] for i in idx],
        [table[i]["gain_action"] for i in idx],
        [table[i]["channel_gains"] for i in idx],
    )
    for i, row in enumerate(table):
        row.update(pooled.get(setups[i], NO_SETUP_GAIN) if setups[i] else NO_SETUP_GAIN)


KINEMATICS_COLUMNS = [
    "test_id",
    "series",
    "peak_theta",
    "peak_phi",
    "peak_v",
    "peak_w",
    "theta_eq8_max_abs_diff",
    "residual_rms_median_mm",
]


def kinematics_row(attrs: Mapping[str, Any]) -> dict[str, Any]:
    """One row of ``kinematics.csv``: Fig. 9b peaks and the Eq. 8 difference (Fig. 9a)."""
    return {k: attrs.get(k, np.nan) for k in KINEMATICS_COLUMNS}


#: Attributes of a reduced test that its rows of ``qc.csv`` and ``kinematics.csv`` are made of.
ROW_ATTRS = tuple(dict.fromkeys(QC_COLUMNS + KINEMATICS_COLUMNS))


def row_attrs(ds: xr.Dataset) -> dict[str, Any]:
    """The :data:`ROW_ATTRS` of a reduced test, as plain Python values (JSON).

    What a reduction job writes beside its netCDF files, so that the QC
    table is made without opening them (:func:`qc_table`, :func:`kinematics_table`
    take these as they take the datasets).
    """
    return {k: np.asarray(v).item() for k, v in ds.attrs.items() if k in ROW_ATTRS}


def write_row_attrs(rows: Iterable[Mapping[str, Any]], path: str | Path) -> None:
    """Write :func:`row_attrs` of a job's tests (a list) to ``path`` (JSON; NaN as ``NaN``)."""
    write_text(path, json.dumps(list(rows), indent=0) + "\n")


def read_row_attrs(paths: Iterable[str | Path]) -> list[SimpleNamespace]:
    """The tests of the files of :func:`write_row_attrs`, each with its ``attrs``, in order."""
    return [SimpleNamespace(attrs=attrs) for path in paths for attrs in json.loads(Path(path).read_text())]


def kinematics_table(datasets: Iterable[xr.Dataset | SimpleNamespace], campaign: Campaign) -> pd.DataFrame:
    """``kinematics.csv``: :func:`kinematics_row` of every readable test, in the order of ``tests.csv``.

    ``datasets``: reduced tests, or anything with their ``attrs`` (:func:`row_attrs`).
    """
    readable = {
        d.attrs["test_id"]: d.attrs for d in datasets if d.attrs.get("reject_reason") != validity.Verdict.UNREADABLE
    }
    rows = [kinematics_row(readable[t]) for t in campaign.test_ids if t in readable]
    return pd.DataFrame(rows, columns=KINEMATICS_COLUMNS)
