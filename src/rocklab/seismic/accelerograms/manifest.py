"""Table 4 records shipped with rocklab: manifest, loading, comparison with Table 4.

The records are package data in ``rocklab/data/accelerograms/``
(:func:`accelerogram_dir`, found through :mod:`importlib.resources`, so an
installed rocklab finds them as the checkout does), with their
``README.md`` (sources, stand-ins).

``records.csv`` (package data) says which shipped file stands for which
Table 4 row (file, format, column, units, identity, source, notes);
:func:`build_manifest` reads each file, baseline-corrects it with
:data:`DEFAULT_PROCESSING` and adds what it measures (dt, npts, PGA, PGV,
record length, D5-95) next to Table 4's values and their differences.  The
result is ``manifest.csv`` beside the records; regenerate it with
``python -c "from rocklab.seismic.accelerograms import write_manifest; write_manifest()"``.

Comparison rules: PGA and PGV differences are signed percentages of the
Table 4 value; ``pga_ok`` is ``|pga_match_pct| <= 2``.  The record length is
``(npts - 1) dt``, which reproduces Table 4's D (e.g. 2990 x 0.005 s ->
14.945 s); ``duration_match`` says ``match`` (within 1 %), ``truncated`` or
``longer``, and for longer records ``arias_beyond_t4_pct`` is the share of the
Arias intensity after Table 4's D.
"""

from __future__ import annotations

import hashlib
import os
from importlib import resources
from pathlib import Path
from typing import Any, TypedDict

import numpy as np
import pandas as pd
from obspy import Stream, Trace

from rocklab.data import data_path
from rocklab.disk import StrPath

from . import processing
from .native import read_accelerogram


#: Baseline correction applied by :func:`load_record` and :func:`build_manifest`
#: (the records are already corrected; see :mod:`rocklab.seismic.accelerograms.processing`).
class Processing(TypedDict):
    """A setting of :func:`rocklab.seismic.accelerograms.processing.baseline_correct`."""

    pre_event: float | None
    velocity_order: int | None
    freqmin: float | None
    freqmax: float | None


DEFAULT_PROCESSING: Processing = {"pre_event": None, "velocity_order": 1, "freqmin": None, "freqmax": None}

#: Environment variable overriding the folder of shipped records.
ENV_DIR = "ROCKLAB_ACCELEROGRAMS"

PGA_TOLERANCE_PCT = 2.0
#: PGV depends more on the processing (filter corners) than PGA: a record of Table 4's
#: station and component matches its PGV within this bound [%].
PGV_TOLERANCE_PCT = 4.0
DURATION_TOLERANCE_PCT = 1.0

MANIFEST_COLUMNS = [
    "record",
    "table4_row",
    "identity",
    "file",
    "format",
    "column",
    "component",
    "units",
    "dt",
    "npts",
    "pga_g",
    "pgv_cm_s",
    "duration_s",
    "d5_95_s",
    "t4_pga_g",
    "t4_pgv_cm_s",
    "t4_duration_s",
    "pga_match_pct",
    "pgv_match_pct",
    "duration_match_pct",
    "pga_ok",
    "duration_match",
    "arias_beyond_t4_pct",
    "processing",
    "source",
    "sha256",
    "notes",
]


def accelerogram_dir() -> Path:
    """Folder of the shipped records and their ``manifest.csv``.

    Returns
    -------
    Path
        ``$ROCKLAB_ACCELEROGRAMS`` when set, else the package data
        ``rocklab/data/accelerograms/`` (:func:`rocklab.data.data_path`).
    """
    if os.environ.get(ENV_DIR):
        return Path(os.environ[ENV_DIR])
    return data_path("accelerograms")


def read_table4() -> pd.DataFrame:
    """Table 4 of the paper (20 rows): row, event, mw, station, record, distance_km, pga_g, pgv_cm_s, duration_s."""
    with resources.files(__package__).joinpath("table4.csv").open() as fh:
        return pd.read_csv(fh)


def read_selection() -> pd.DataFrame:
    """Which shipped file stands for which Table 4 row (``records.csv``)."""
    with resources.files(__package__).joinpath("records.csv").open() as fh:
        return pd.read_csv(fh, dtype={"column": "Int64"}, keep_default_na=False, na_values={"column": [""]})


def read_manifest(path: StrPath | None = None) -> pd.DataFrame:
    """The manifest (one row per shipped Table 4 record) as a DataFrame.

    Parameters
    ----------
    path : str or Path, optional
        Manifest CSV; default ``accelerogram_dir() / "manifest.csv"``.
    """
    path = Path(path) if path is not None else accelerogram_dir() / "manifest.csv"
    return pd.read_csv(
        path, dtype={"column": "Int64"}, keep_default_na=False, na_values={"column": [""], "arias_beyond_t4_pct": [""]}
    )


def _reader_kwargs(row: pd.Series) -> dict[str, Any]:
    kwargs = {"format": row["format"]}
    if row["format"] in ("TWO_COLUMN", "MULTI_COLUMN", "CSV_TWO_COLUMN", "SOMERVILLE", "SLAMMER"):
        kwargs["units"] = row["units"]
    return kwargs


def _pick(stream: Stream, column: int | str | None, path: StrPath) -> Trace:
    if len(stream) == 1:
        return stream[0]
    if column is None or pd.isna(column):
        raise ValueError(f"{path} holds {len(stream)} traces: say which column/component to load")
    for tr in stream:
        if tr.stats.get("text_columns", {}).get("column") == int(column) or tr.stats.channel == str(column):
            return tr
    raise ValueError(f"{path}: no trace for column/component {column!r}")


def _find(name: StrPath, manifest: pd.DataFrame) -> pd.Series | None:
    key = str(name).lower()
    hits = manifest[(manifest["record"].str.lower() == key) | (manifest["file"].str.lower() == key)]
    return None if hits.empty else hits.iloc[0]


def load_record(
    name: StrPath,
    corrected: bool = True,
    column: int | str | None = None,
    manifest: pd.DataFrame | None = None,
    **kwargs: Any,
) -> Trace:
    """One accelerogram as an obspy Trace in m/s^2, baseline-corrected by default.

    Parameters
    ----------
    name : str or Path
        Table 4 record name (``"Pac164"``, case-insensitive), a shipped file
        name from the manifest, or the path of any supported file.
    corrected : bool
        Apply :func:`~rocklab.seismic.accelerograms.processing.baseline_correct` with
        :data:`DEFAULT_PROCESSING` (recorded in ``stats.processing``).
    column : int or str, optional
        For multi-trace files not in the manifest: 1-based file column
        (column text) or channel name.
    manifest : DataFrame, optional
        Defaults to :func:`read_manifest`.
    **kwargs
        Passed to the reader for files not in the manifest (``units=``...).

    Returns
    -------
    obspy.Trace
        With ``stats.record`` and ``stats.table4_row`` for manifest records.
    """
    row = _find(name, manifest if manifest is not None else read_manifest())
    if row is not None:
        path = accelerogram_dir() / row["file"]
        tr = _pick(read_accelerogram(path, **_reader_kwargs(row)), row["column"], path)
        tr.stats.record, tr.stats.table4_row = row["record"], int(row["table4_row"])
    else:
        path = Path(name)
        if not path.exists():
            raise FileNotFoundError(f"{name!r} is neither a manifest record nor an existing file")
        tr = _pick(read_accelerogram(path, **kwargs), column, path)
    return processing.baseline_correct(tr, **DEFAULT_PROCESSING) if corrected else tr


def _pct(value: float, reference: float) -> float:
    return round(100.0 * (value - reference) / reference, 2)


def _sha256(path: StrPath) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def build_manifest(raw_dir: StrPath | None = None) -> pd.DataFrame:
    """Manifest DataFrame measured from the files in ``raw_dir`` (default :func:`accelerogram_dir`)."""
    raw_dir = Path(raw_dir) if raw_dir is not None else accelerogram_dir()
    table4 = read_table4().set_index("row")
    rows = []
    for _, sel in read_selection().iterrows():
        path = raw_dir / sel["file"]
        tr = _pick(read_accelerogram(path, **_reader_kwargs(sel)), sel["column"], path)
        tr = processing.baseline_correct(tr, **DEFAULT_PROCESSING)
        gm = processing.ground_motion_parameters(tr)
        t4 = table4.loc[int(sel["table4_row"])]
        dur_pct = _pct(gm["duration_s"], t4["duration_s"])
        if abs(dur_pct) <= DURATION_TOLERANCE_PCT:
            dur_match, beyond = "match", np.nan
        elif dur_pct < 0:
            dur_match, beyond = "truncated", np.nan
        else:
            ia = processing.arias_intensity(tr.data, tr.stats.delta)
            k = int(np.floor(t4["duration_s"] / tr.stats.delta))
            dur_match, beyond = "longer", round(100.0 * (1.0 - ia[k] / ia[-1]), 2)
        rows.append(
            {
                **sel.to_dict(),
                "dt": tr.stats.delta,
                "npts": tr.stats.npts,
                "pga_g": round(gm["pga_g"], 4),
                "pgv_cm_s": round(gm["pgv_cm_s"], 2),
                "duration_s": round(gm["duration_s"], 4),
                "d5_95_s": round(gm["d5_95_s"], 2),
                "t4_pga_g": t4["pga_g"],
                "t4_pgv_cm_s": t4["pgv_cm_s"],
                "t4_duration_s": t4["duration_s"],
                "pga_match_pct": _pct(gm["pga_g"], t4["pga_g"]),
                "pgv_match_pct": _pct(gm["pgv_cm_s"], t4["pgv_cm_s"]),
                "duration_match_pct": dur_pct,
                "pga_ok": bool(abs(_pct(gm["pga_g"], t4["pga_g"])) <= PGA_TOLERANCE_PCT),
                "duration_match": dur_match,
                "arias_beyond_t4_pct": beyond,
                "processing": processing.describe(**DEFAULT_PROCESSING),
                "sha256": _sha256(path),
            }
        )
    return pd.DataFrame(rows)[MANIFEST_COLUMNS].astype({"column": "Int64"})


def table4_agreement(manifest: pd.DataFrame | None = None) -> pd.DataFrame:
    """How each shipped record compares with its Table 4 row, in a flag and in words.

    Parameters
    ----------
    manifest : DataFrame, optional
        :func:`read_manifest` (default: the shipped one).

    Returns
    -------
    pandas.DataFrame
        Indexed by record: ``table4_row``; ``pga_pgv_match``, PGA within
        :data:`PGA_TOLERANCE_PCT` and PGV within :data:`PGV_TOLERANCE_PCT` of
        Table 4; ``duration_match`` (match, truncated or longer, see the
        module doc); ``differences``, what departs from Table 4 in words
        (empty for a full match), e.g. ``"PGA +13.3 %, PGV -9.1 %; 48.1 s
        long against 40 s"``.
    """
    m = read_manifest() if manifest is None else manifest
    rows: dict[str, dict[str, Any]] = {}
    for r in m.itertuples():
        pga_ok = abs(r.pga_match_pct) <= PGA_TOLERANCE_PCT
        pgv_ok = abs(r.pgv_match_pct) <= PGV_TOLERANCE_PCT
        words = [f"PGA {r.pga_match_pct:+.1f} %"] * (not pga_ok) + [f"PGV {r.pgv_match_pct:+.1f} %"] * (not pgv_ok)
        if r.duration_match != "match":
            words.append(f"{r.duration_s:.1f} s long against {r.t4_duration_s:g} s")
        rows[r.record] = {
            "table4_row": int(r.table4_row),
            "pga_pgv_match": bool(pga_ok and pgv_ok),
            "duration_match": r.duration_match,
            "differences": ", ".join(words),
        }
    return pd.DataFrame.from_dict(rows, orient="index").rename_axis("record")


def write_manifest(raw_dir: StrPath | None = None) -> Path:
    """Write ``manifest.csv`` into ``raw_dir`` and return its path."""
    raw_dir = Path(raw_dir) if raw_dir is not None else accelerogram_dir()
    out = raw_dir / "manifest.csv"
    build_manifest(raw_dir).to_csv(out, index=False)
    return out
