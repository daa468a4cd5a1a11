"""Overturning maps of rocking walls under scaled records (Sect. 5, Figs. 21-23).

A map is the overturning decision of one wall under one record whose
amplitude A and duration D are scaled to A_S and D_S, on a grid of ``n x n``
values of A_S/A and D_S/D between ``lo`` and ``hi`` (the paper: 201 values,
50-150 %, i.e. 40401 histories per map).  The amplitude scale multiplies the
ground acceleration; the duration scale stretches time (the record is read
with interval ``dt D_S/D``).

Form of the equation of motion
------------------------------
The maps use Housner's piecewise-linear form (``form="linear"``, see
:mod:`rocklab.simulation.model`).  Sect. 5 reads the maps through the scaling
equivalences of that model, and for the paper's wall (alpha = 0.1 rad) the
linearisation changes the restoring moment by less than 0.2 %; the batch
engine integrates the linear form in closed form per record interval, so the
map carries no time-step error, and it is about twice as fast as the exact
form.  ``form="exact"`` is available for comparison.

Scaling equivalences (Sect. 5)
------------------------------
Duration <-> size
    Scaling the duration by ``s = D_S/D`` is the same as multiplying ``p`` by
    ``s``, i.e. R by ``(D/D_S)^2``.  Only ``p`` sets the time scale of the
    equation of motion and of Eq. 16, so this holds for both forms and every
    impact law of this module (up to the free-motion tail followed after the
    record, which is not rescaled).
Amplitude <-> slenderness
    Scaling the amplitude by ``lambda = A_S/A`` is the same as dividing alpha
    by ``lambda`` (the rotation scales by ``lambda``), but only for the linear
    form, and only if the coefficient of restitution and the overturning
    rotation are scaled with it: e stays that of the unscaled alpha (Eqs. 2,
    14 depend on alpha) and the wall overturns at ``pi/2 / lambda``.  For the
    exact form (sin, cos of alpha - theta) it does not hold.
The maps are computed by simulating the scaled records themselves, so they
use neither equivalence; the tests check both where they hold.
"""

from __future__ import annotations

import logging
import time

import numpy as np
import pandas as pd
import xarray as xr

from rocklab import __version__
from rocklab.diagnosis.causes import restitution_amplitude, restitution_scale
from rocklab.io import cf_attrs
from rocklab.physics.restitution import (
    AMPLITUDE_LAW_ONE_SIDED,
    CALIBRATED_RATIO_ONE_SIDED,
    CALIBRATED_RATIO_TWO_SIDED,
)
from rocklab.seismic import calibrated
from rocklab.seismic.reductions import record_reductions
from rocklab.simulation.model import OVERTURN

log = logging.getLogger(__name__)

#: Paper's wall of Figs. 21 and 23: slenderness [rad] and half diagonal [m].
ALPHA = 0.1
R = 3.0

#: The five maps of Sect. 5: name -> (boundary, description).
MODELS = {
    "2s-housner": ("two-sided", "two-sided, e = e_an,2s (Housner, Eq. 2); Fig. 21a"),
    "2s-0.95": ("two-sided", "two-sided, e = 0.95 e_an,2s (experimentally calibrated, Sect. 3); Fig. 21b"),
    "1s-zero": ("one-sided", "one-sided, e = 0 (Liberatore & Spera 2003: motion stops at impact); Fig. 23a"),
    "1s-1.05": ("one-sided", "one-sided, e = 1.05 e_an,1s (Eq. 14 calibrated, Table 3); Fig. 23b"),
    "1s-eq17": ("one-sided", "one-sided, e = e_an,1s (a - b (thetadot^-/thetadot_r)^2) (amplitude law, Eq. 17)"),
}

#: What each map model adds to Housner's wall of its boundary: causes of the catalogue
#: (:mod:`rocklab.diagnosis.catalogue`) with their values, and the literature base e
#: (:meth:`rocklab.diagnosis.model.ModelParams.with_base`); ``"1s-eq17"`` takes Eq. 17's (a, b).
CAUSES_OF = {
    "2s-housner": ({}, "analytic"),
    "2s-0.95": ({restitution_scale.CAUSE.name: {"c": CALIBRATED_RATIO_TWO_SIDED}}, "analytic"),
    "1s-zero": ({}, "zero"),
    "1s-1.05": ({restitution_scale.CAUSE.name: {"c": CALIBRATED_RATIO_ONE_SIDED}}, "analytic"),
    "1s-eq17": ({restitution_amplitude.CAUSE.name: dict(zip("ab", AMPLITUDE_LAW_ONE_SIDED))}, "analytic"),
}

#: Pairs (baseline, model) compared record by record (Sect. 5).
COMPARISONS = (("2s-housner", "2s-0.95"), ("1s-zero", "1s-1.05"), ("1s-1.05", "1s-eq17"))

#: What the paper reports for a comparison: (baseline, model, index) -> {statistic: %}.
PAPER_REDUCTIONS = {
    ("2s-housner", "2s-0.95", "N_O"): {"mean": 25.0, "min": 3.0, "max": 89.0},
    ("2s-housner", "2s-0.95", "scatter"): {"mean": 43.0},
}

OVERTURNING_CRITERION = (
    "|theta| >= {overturn:.6g} rad (wall lying on the ground); after the record a wall still rocking is "
    "followed in free motion up to {tail:g} s while it leans beyond alpha or its energy can reach alpha "
    "(rocklab.simulation.model)"
)


def named_model(name, alpha=ALPHA, R=R, form="linear", eq17=None, diagnosis=None):
    """The wall of a named map model (:data:`MODELS`, or a calibrated wall).

    Parameters
    ----------
    name : str
        A key of :data:`MODELS`, or a calibrated model
        (:func:`rocklab.seismic.calibrated.name_pattern`, with ``diagnosis``).
    alpha : float
        Slenderness angle [rad] (Fig. 21: 0.1).
    R : float
        Half diagonal [m] of the homogeneous wall (Fig. 21: 3), giving
        p = sqrt(3 g / 4 R).
    form : {"linear", "exact"}
        Equation of motion (module docstring: the maps use "linear").
    eq17 : tuple of float, optional
        (a, b) of Eq. 17 for ``"1s-eq17"``; default the paper's fit
        (:data:`rocklab.physics.restitution.AMPLITUDE_LAW_ONE_SIDED`).
    diagnosis : list of dict or path, optional
        ``results/diagnosis.json`` of a campaign, for the calibrated walls
        (:func:`rocklab.seismic.calibrated.calibrated_model`).

    Returns
    -------
    rocklab.simulation.model.RockingModel
    """
    if calibrated.is_calibrated(name):
        if diagnosis is None:
            raise ValueError(f"the calibrated model {name!r} needs the diagnosis of a campaign (diagnosis=)")
        return calibrated.calibrated_model(diagnosis, name, alpha, R, form)
    if name not in MODELS:
        raise KeyError(f"unknown map model {name!r}; choose one of {', '.join(MODELS)}")
    causes, base = CAUSES_OF[name]
    if name == "1s-eq17" and eq17 is not None:
        causes = {restitution_amplitude.CAUSE.name: dict(zip("ab", eq17))}
    values = {k: v for p in causes.values() for k, v in p.items()}
    return calibrated.map_wall_model(MODELS[name][0], alpha, R, tuple(causes), values, base, form)


def scales(n=201, lo=0.5, hi=1.5):
    """Grid of A_S/A (or D_S/D) values: ``n`` values from ``lo`` to ``hi``."""
    return np.linspace(float(lo), float(hi), int(n))


def subgrid_step(n, n_sub):
    """Stride k such that every k-th of :func:`scales` ``(n)`` is :func:`scales` ``(n_sub)`` (same range).

    Raises
    ------
    ValueError
        When ``n_sub - 1`` does not divide ``n - 1`` (no such stride).
    """
    n, n_sub = int(n), int(n_sub)
    if n_sub < 2 or n_sub > n or (n - 1) % (n_sub - 1):
        raise ValueError(
            f"a grid of {n_sub} values is not a subgrid of one of {n} ({n - 1} is not a multiple of {n_sub - 1})"
        )
    return (n - 1) // (n_sub - 1)


def subgrid(ds, n):
    """Map ``ds`` (:func:`overturning_map`) read on the cells of an ``n`` x ``n`` grid of the same range.

    The scatter index of :func:`map_indices` depends on the grid (changes
    grow as n, overturnings as n^2): maps are compared on the same cells.
    """
    k = subgrid_step(ds.sizes["amplitude_scale"], n)
    return ds.isel(amplitude_scale=slice(None, None, k), duration_scale=slice(None, None, k))


def overturning_map(
    record,
    dt=None,
    model="2s-housner",
    n=201,
    lo=0.5,
    hi=1.5,
    *,
    alpha=ALPHA,
    R=R,
    form="linear",
    eq17=None,
    diagnosis=None,
    polarity=1,
    chunks=10,
    overturn=OVERTURN,
    tail=120.0,
    name=None,
    progress=None,
):
    """Overturning map of a named wall under one record (Sect. 5, Figs. 21, 23).

    Parameters
    ----------
    record : obspy.Trace or array_like
        Ground acceleration [m/s^2], positive towards +theta (a positive
        value pushes the wall towards negative rotations, i.e. a one-sided
        wall against the transverse walls); a Trace gives ``dt`` and the
        record's name.
    dt : float, optional
        Sample interval [s]; required for an array.
    model : str
        A key of :data:`MODELS`, or a calibrated model (with ``diagnosis``).
    n, lo, hi : int, float, float
        Grid of A_S/A and D_S/D (:func:`scales`); the paper: 201, 0.5, 1.5.
    alpha, R, form, eq17, diagnosis
        Wall and law, see :func:`named_model`.
    polarity : {1, -1}
        Multiplies the record: the maps of one-sided walls depend on it.
    chunks : int
        The map is computed in this many blocks of amplitude rows, each
        logged (logger ``rocklab.seismic.overturning``) as it completes.
    overturn, tail
        Overturning rotation [rad] and longest free motion after the record
        [s], see :func:`rocklab.simulation.batch.overturning_batch`.
    name : str, optional
        Record name for the attributes; default the Trace's ``stats.record``.
    progress : callable, optional
        Called as ``progress(rows_done, rows_total)`` after each block of
        amplitude rows, e.g. to draw a progress bar (``rocklab map``).

    Returns
    -------
    xarray.Dataset
        Boolean ``overturned`` on (``amplitude_scale``, ``duration_scale``),
        with the wall (alpha, R, p, form, boundary), the impact law, the
        overturning criterion and the record in the attributes.
    """
    if dt is None:
        if not hasattr(record, "stats"):
            raise TypeError("an array record needs its sample interval dt")
        ag, dt = np.asarray(record.data, float), float(record.stats.delta)
        name = name or record.stats.get("record") or record.id
    else:
        ag = np.asarray(record, float)
    if polarity not in (1, -1):
        raise ValueError(f"polarity must be 1 or -1, not {polarity!r}")
    # imported here: numba (0.4 s) is for the map jobs, not for the jobs and
    # the Snakefile that import this module for its tables and model names
    from rocklab.simulation.batch import overturning_batch

    wall_model = named_model(model, alpha, R, form, eq17, diagnosis)
    amp, dur = scales(n, lo, hi), scales(n, lo, hi)
    over = np.zeros((amp.size, dur.size), bool)
    signed = polarity * ag
    t0 = time.perf_counter()
    for rows in np.array_split(np.arange(amp.size), max(1, min(int(chunks), amp.size))):
        over[rows] = overturning_batch(signed, dt, wall_model, amp[rows], dur, overturn=overturn, tail=tail)
        log.info(
            "%s %s: amplitude rows %d-%d of %d done, %.1f s",
            name,
            model,
            rows[0] + 1,
            rows[-1] + 1,
            amp.size,
            time.perf_counter() - t0,
        )
        if progress is not None:
            progress(int(rows[-1]) + 1, amp.size)
    e0, a, b, v_stick = wall_model.numba_law()[0]
    return xr.Dataset(
        {
            "overturned": (
                ("amplitude_scale", "duration_scale"),
                over,
                {
                    "long_name": "wall overturned",
                    # a boolean is stored as a byte, and CF flags have the type of the variable
                    "flag_values": np.array([0, 1], np.int8),
                    "flag_meanings": "standing overturned",
                },
            )
        },
        coords={
            "amplitude_scale": (
                "amplitude_scale",
                amp,
                {"long_name": "A_S/A, amplitude scale of the record", "units": "1"},
            ),
            "duration_scale": (
                "duration_scale",
                dur,
                {"long_name": "D_S/D, duration scale of the record", "units": "1"},
            ),
        },
        attrs={
            **cf_attrs(
                f"overturning map, record {name}, model {model} (Sect. 5)",
                f"rocking simulation of a wall under a scaled accelerogram, model {model}",
            ),
            "record": str(name),
            "dt": dt,
            "npts": int(ag.size),
            "polarity": int(polarity),
            "model": model,
            "model_description": (
                calibrated.describe(diagnosis, model) if calibrated.is_calibrated(model) else MODELS[model][1]
            ),
            "alpha": wall_model.alpha,
            "R": float(R),
            "p": wall_model.p,
            "form": form,
            "boundary": wall_model.boundary,
            "impact_law": type(wall_model.base_law).__name__,
            # the engines' law e = e0 clip(a - b (thetadot^-/thetadot_r)^2) (rocklab.physics.impact),
            # 0 below a landing of v_stick thetadot_r; positive hinge (the calibrated walls'
            # other hinge and transverse impacts are in model_description)
            "impact_e0": float(e0),
            "impact_a": float(a),
            "impact_b": float(b),
            "impact_v_stick": float(v_stick),
            "alpha_rock": wall_model.alpha_pos,
            "alpha_neg": wall_model.alpha_minus,
            "gap": wall_model.gap,
            "overturning_criterion": OVERTURNING_CRITERION.format(overturn=overturn, tail=tail),
            "compute_s": time.perf_counter() - t0,
            "rocklab_version": __version__,
        },
    )


def map_indices(overturned):
    """Normalised overturning and change counts of one map (Sect. 5, Fig. 22).

    N_O is the number of overturnings over the number of histories (Fig. 22a).
    N_D and N_A are the numbers of changes overturning <-> no overturning met
    scaling up the duration (along each row of constant A_S/A) and the
    amplitude (along each column of constant D_S/D), normalised by the number
    of overturnings, "to take into account how many changes were actually
    possible".  Their average is the scatter of Fig. 22b.

    Parameters
    ----------
    overturned : xarray.DataArray or array_like of bool
        A map; a DataArray is read on (amplitude_scale, duration_scale), an
        array with amplitude along axis 0.

    Returns
    -------
    dict
        N_O, N_D, N_A, scatter = (N_D + N_A)/2 (N_D, N_A, scatter NaN without
        overturnings), n_overturned, n_cells, changes_duration,
        changes_amplitude, and reversals_duration, reversals_amplitude: the
        changes from overturning to standing as the scale grows (a map
        regular in that direction has none).
    """
    if isinstance(overturned, xr.DataArray):
        overturned = overturned.transpose("amplitude_scale", "duration_scale").values
    o = np.asarray(overturned, bool)
    n_over = int(o.sum())
    ch_d = int(np.count_nonzero(o[:, 1:] != o[:, :-1]))
    ch_a = int(np.count_nonzero(o[1:, :] != o[:-1, :]))
    n_d = ch_d / n_over if n_over else np.nan
    n_a = ch_a / n_over if n_over else np.nan
    return {
        "N_O": n_over / o.size,
        "N_D": n_d,
        "N_A": n_a,
        "scatter": 0.5 * (n_d + n_a),
        "n_overturned": n_over,
        "n_cells": int(o.size),
        "changes_duration": ch_d,
        "changes_amplitude": ch_a,
        "reversals_duration": int(np.count_nonzero(o[:, :-1] & ~o[:, 1:])),
        "reversals_amplitude": int(np.count_nonzero(o[:-1, :] & ~o[1:, :])),
    }


def summary_table(maps):
    """One row of :func:`map_indices` per map, with its record and model.

    Parameters
    ----------
    maps : iterable of xarray.Dataset
        Results of :func:`overturning_map`.

    Returns
    -------
    pandas.DataFrame
        record, model and the fields of :func:`map_indices`.
    """
    rows = [{"record": ds.attrs["record"], "model": ds.attrs["model"], **map_indices(ds["overturned"])} for ds in maps]
    return pd.DataFrame(rows)


def reductions(summary, comparisons=COMPARISONS, subsets=None):
    """Mean, min and max over records of the per-record reductions (Sect. 5).

    The paper reports, from e_an,2s to 0.95 e_an,2s over its 20 records, an
    N_O reduction of 25 % on average (3 % min, 89 % max) and a scatter
    reduction of 43 % on average: statistics over maps of the per-map
    reduction (:func:`record_reductions`), as computed here.

    Parameters
    ----------
    summary : pandas.DataFrame
        :func:`summary_table`.
    comparisons : sequence of (baseline, model)
        Default :data:`COMPARISONS`; pairs missing from ``summary`` are skipped.
    subsets : dict of str to iterable of str, optional
        Named sets of records to summarise as well (e.g. the records that
        match Table 4); every record of ``summary`` is always summarised,
        as subset ``"all"``.

    Returns
    -------
    pandas.DataFrame
        records (subset name), baseline, model, index (N_O | scatter),
        statistic (mean | min | max), reduction_pct, n_records (records
        where it is defined), paper_pct.
    """
    rows = []
    present = set(summary["model"])
    groups = {"all": list(dict.fromkeys(summary["record"])), **{k: list(v) for k, v in (subsets or {}).items()}}
    for baseline, model in comparisons:
        if not {baseline, model} <= present:
            continue
        red = record_reductions(summary, baseline, model)
        for group, records in groups.items():
            for index in ("N_O", "scatter"):
                values = red[index].reindex(records).dropna()
                paper = PAPER_REDUCTIONS.get((baseline, model, index), {})
                for stat in ("mean", "min", "max"):
                    rows.append(
                        {
                            "records": group,
                            "baseline": baseline,
                            "model": model,
                            "index": index,
                            "statistic": stat,
                            "reduction_pct": getattr(values, stat)() if len(values) else np.nan,
                            "n_records": int(len(values)),
                            "paper_pct": paper.get(stat, np.nan),
                        }
                    )
    return pd.DataFrame(
        rows, columns=["records", "baseline", "model", "index", "statistic", "reduction_pct", "n_records", "paper_pct"]
    )


#: Records summarised apart in :func:`reductions`: those of Table 4's station and
#: component whose PGA and PGV match Table 4 (:func:`rocklab.seismic.accelerograms.table4_agreement`).
TABLE4_SUBSET = "table4_pga_pgv"

#: Columns of :func:`record_comparison`.
COMPARISON_COLUMNS = [
    "table4_row",
    "record",
    "baseline",
    "model",
    "N_O_baseline",
    "N_O_model",
    "N_O_reduction_pct",
    "scatter_baseline",
    "scatter_model",
    "scatter_reduction_pct",
    "paper_min_pct",
    "paper_max_pct",
    "in_paper_range",
    "table4_match",
    "table4_differences",
    "reason",
]


def _in_paper_range(reduction, paper):
    """True if ``reduction`` [%] rounds into the paper's range (it prints whole percents)."""
    return bool(paper["min"] - 0.5 <= reduction < paper["max"] + 0.5)


def _comparison_reason(row, paper):
    """Why a record's reduction is undefined or outside the paper's per-record range (empty if it is not)."""
    base, new, red = row["N_O_baseline"], row["N_O_model"], row["N_O_reduction_pct"]
    b, m = row["baseline"], row["model"]
    if pd.isna(base):
        return "no map of this record in the run" if row["table4_match"] is not None else "no record of this row"
    if base == 0:
        return f"no overturning with {b}: reduction undefined"
    words = []
    if new == 0:
        words.append(f"every overturning of {b} removed (N_O {base:.3f} -> 0)")
    elif red < 0:
        words.append(f"more overturnings with {m}")
    if paper and not _in_paper_range(red, paper):
        side = "below the paper's smallest" if red < paper["min"] else "above the paper's largest"
        words.append(f"{side} reduction")
        if base >= 0.9:
            words.append(f"the wall falls in {100 * base:.0f} % of the {b} map, few cells are left to stand")
        elif base < 0.1:
            words.append(f"only {100 * base:.0f} % of the {b} map overturns, in thin bands")
        if row["table4_differences"]:
            words.append(f"record differs from Table 4: {row['table4_differences']}")
    return "; ".join(words)


def record_comparison(summary, agreement=None, table4=None, comparisons=COMPARISONS):
    """Record by record: each comparison's reductions beside Table 4 and the paper's range.

    The paper gives no per-record value in its text (Fig. 22 shows them as
    bars); it gives, for e_an,2s -> 0.95 e_an,2s, the range of the per-record
    N_O reduction, 3 % to 89 % (:data:`PAPER_REDUCTIONS`), in whole percents,
    so a reduction is within it when it rounds into it (2.5 % to 89.5 %).
    Each record's reduction is set against that range, with the record's
    agreement with its Table 4 row, and the reason where the reduction is
    undefined or out of the range.

    Parameters
    ----------
    summary : pandas.DataFrame
        :func:`summary_table`.
    agreement : pandas.DataFrame, optional
        :func:`rocklab.seismic.accelerograms.table4_agreement` (default: of
        the shipped records).
    table4 : pandas.DataFrame, optional
        :func:`rocklab.seismic.accelerograms.read_table4` (default: the
        paper's).
    comparisons : sequence of (baseline, model)
        Default :data:`COMPARISONS`; pairs missing from ``summary`` are skipped.

    Returns
    -------
    pandas.DataFrame
        :data:`COMPARISON_COLUMNS`, one row per comparison and Table 4 row
        (rows without a shipped record have no indices), then the records of
        ``summary`` that are not Table 4's (no ``table4_row``).
        ``in_paper_range`` is empty where the paper gives no range or the
        reduction is undefined.
    """
    from rocklab.seismic.accelerograms import read_table4, table4_agreement

    agreement = table4_agreement() if agreement is None else agreement
    table4 = read_table4() if table4 is None else table4
    present = set(summary["model"])
    s = summary.set_index(["record", "model"])
    records = [(int(r.row), r.record) for r in table4.itertuples()]
    records += [(None, r) for r in dict.fromkeys(summary["record"]) if r not in set(table4["record"])]
    rows = []
    for baseline, model in comparisons:
        if not {baseline, model} <= present:
            continue
        red = record_reductions(summary, baseline, model)
        paper = PAPER_REDUCTIONS.get((baseline, model, "N_O"), {})
        paper = paper if {"min", "max"} <= set(paper) else {}
        for t4_row, record in records:
            shipped = (record, baseline) in s.index and (record, model) in s.index
            known = record in agreement.index
            row = {
                "table4_row": t4_row,
                "record": record,
                "baseline": baseline,
                "model": model,
                "N_O_baseline": s.loc[(record, baseline), "N_O"] if shipped else np.nan,
                "N_O_model": s.loc[(record, model), "N_O"] if shipped else np.nan,
                "N_O_reduction_pct": red.loc[record, "N_O"] if shipped else np.nan,
                "scatter_baseline": s.loc[(record, baseline), "scatter"] if shipped else np.nan,
                "scatter_model": s.loc[(record, model), "scatter"] if shipped else np.nan,
                "scatter_reduction_pct": red.loc[record, "scatter"] if shipped else np.nan,
                "paper_min_pct": paper.get("min", np.nan),
                "paper_max_pct": paper.get("max", np.nan),
                "table4_match": bool(agreement.loc[record, "pga_pgv_match"]) if known else None,
                "table4_differences": agreement.loc[record, "differences"] if known else "",
            }
            defined = not pd.isna(row["N_O_reduction_pct"])
            row["in_paper_range"] = _in_paper_range(row["N_O_reduction_pct"], paper) if paper and defined else None
            row["reason"] = _comparison_reason(row, paper)
            rows.append(row)
    out = pd.DataFrame(rows, columns=COMPARISON_COLUMNS)
    # integers with gaps for the records that are not Table 4's (a float column would write "1.0")
    out["table4_row"] = pd.Series([r["table4_row"] for r in rows], index=out.index, dtype=object)
    return out


# ---------------------------------------------------------------------------
# validation against the event-driven reference


def _reference_one(args):
    # imported here: scipy.integrate is 0.4 s of the start-up of every map job,
    # which never calls the reference
    from rocklab.simulation.reference import simulate_ground

    model, ag, dt, a, d, rtol, atol, overturn, tail = args
    return simulate_ground(model, a * ag, dt * d, overturn=overturn, rtol=rtol, atol=atol, tail=tail).overturned


def reference_decisions(ag, dt, model, cells, *, rtol=1e-10, atol=1e-12, overturn=OVERTURN, tail=120.0, pool=None):
    """Overturning of the scipy event-driven reference at given (A_S/A, D_S/D) cells.

    Parameters
    ----------
    ag, dt : array_like, float
        Record [m/s^2] (polarity applied) and sample interval [s].
    model : rocklab.simulation.model.RockingModel
    cells : sequence of (float, float)
        Amplitude and duration scales.
    rtol, atol : float
        Tolerances of :func:`rocklab.simulation.reference.simulate_ground`.
    pool : multiprocessing.pool.Pool, optional
        Spreads the histories over its workers.

    Returns
    -------
    ndarray of bool
    """
    ag = np.asarray(ag, float)
    jobs = [(model, ag, dt, float(a), float(d), rtol, atol, overturn, tail) for a, d in cells]
    results = pool.map(_reference_one, jobs, chunksize=4) if pool is not None else map(_reference_one, jobs)
    return np.fromiter(results, bool, count=len(jobs))


def check_against_reference(ag, dt, model, amplitude_scales, duration_scales, fast, step, *, pool=None, **kw):
    """Compare a map with the reference and explain each difference by the boundary.

    Criterion: a cell where the map and the reference disagree lies on the
    boundary of the map when the reference itself reaches the map's decision
    at one of the cell's four neighbours of the full grid (A_S/A or D_S/D
    moved by one grid step ``step``); both engines then place the boundary
    within one grid step of each other.

    Parameters
    ----------
    ag, dt, model
        As :func:`reference_decisions`.
    amplitude_scales, duration_scales : array_like
        Scales of the checked cells (a subgrid).
    fast : array_like of bool
        The map's decisions on that subgrid, amplitude along axis 0.
    step : float
        Grid step of the full map (0.005 for 201 values over 0.5-1.5).
    **kw
        rtol, atol, overturn, tail of :func:`reference_decisions`.

    Returns
    -------
    dict
        cells, agree, agreement_pct, mismatches (list of {amplitude_scale,
        duration_scale, map, reference, boundary}), unexplained (count),
        reference (the reference decisions, nested lists).
    """
    amp = np.asarray(amplitude_scales, float)
    dur = np.asarray(duration_scales, float)
    fast = np.asarray(fast, bool)
    cells = [(a, d) for a in amp for d in dur]
    ref = reference_decisions(ag, dt, model, cells, pool=pool, **kw).reshape(fast.shape)
    bad = np.argwhere(ref != fast)
    # the neighbours of every difference in one call, spread over the pool
    around = [
        (a, d)
        for i, j in bad
        for a, d in ((amp[i] - step, dur[j]), (amp[i] + step, dur[j]), (amp[i], dur[j] - step), (amp[i], dur[j] + step))
    ]
    neighbours = reference_decisions(ag, dt, model, around, pool=pool, **kw).reshape(-1, 4)
    mismatches = [
        {
            "amplitude_scale": float(amp[i]),
            "duration_scale": float(dur[j]),
            "map": bool(fast[i, j]),
            "reference": bool(ref[i, j]),
            "boundary": bool((nb == fast[i, j]).any()),
        }
        for (i, j), nb in zip(bad, neighbours)
    ]
    agree = int((ref == fast).sum())
    return {
        "cells": int(fast.size),
        "agree": agree,
        "agreement_pct": 100.0 * agree / fast.size,
        "mismatches": mismatches,
        "unexplained": sum(not m["boundary"] for m in mismatches),
        "reference": ref.tolist(),
    }
