"""Held-out comparison of the block, the PGV threshold and the DEM model; transfer between replicas.

Every model is scored on the same tests (those with a motion file), each
predicted by a fit to the other folds (:func:`cross_validate`); the folds
hold every test of an earthquake record (both components, by RSN) together:

- ``block-nominal``: the specimen's footprint block, no parameter fitted;
- ``block-calibrated``: the contact fitted to the training folds, the
  prediction the mean P over resampled fits (fragility);
- ``pgv-threshold``: a logistic threshold on PGV fitted to the training folds;
- ``dem``: the source's DEM predictions as given, the stiffness setting the
  training folds classify best.  The source chose its settings on these
  same tests (in sample), so even the training-fold choice flatters it.

The nominal block and DEM are 0/1 predictors: they are scored by accuracy
alone (a Brier score or log loss would score the lapse we give them, not
them).  As probabilities (the figures, the fragility table) their lapse is
their error rate on the training folds
(:func:`rocklab.shake_table.calibration.deterministic_probability`).
Differences of accuracy carry a paired bootstrap interval over records
(:func:`rocklab.shake_table.calibration.paired_accuracy_difference`).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr
from numpy.typing import ArrayLike

from rocklab.inference.intervals import percentile_interval
from rocklab.io import cf_attrs
from rocklab.seismic.indices import map_indices
from rocklab.seismic.maps import scales
from rocklab.shake_table import asu_data
from rocklab.shake_table import calibration as cal
from rocklab.shake_table.block import (
    CONTACT_MINUS,
    CONTACT_PLUS,
    PARAMS,
    block_model,
    contact,
    footprint,
    grid_of,
    node_on,
    nominal,
)
from rocklab.simulation.batch import overturning_batch

log = logging.getLogger(__name__)

#: The models of scores.csv, in its order.
MODELS = ("block-nominal", "block-calibrated", "pgv-threshold", "dem")
#: The 0/1 predictors: scored by accuracy only.
DETERMINISTIC = ("block-nominal", "dem")
#: The models the calibrated block's accuracy is compared with in scores.csv (column suffix, model).
COMPARED = (("pgv", "pgv-threshold"), ("dem", "dem"), ("nominal", "block-nominal"))
#: The models of transfer.csv.
TRANSFERRED = ("block-calibrated", "pgv-threshold")
#: Bootstrap resamples of the records for the intervals of accuracy differences and binned rates.
N_BOOT_DIFF = 2000

#: Bins of the tables by PGA [g] and PGV [m/s].
PGA_BINS = (0.0, 0.1, 0.2, 0.3, 0.5, 0.8, np.inf)
PGV_BINS = (0.0, 0.05, 0.1, 0.15, 0.2, 0.3, np.inf)

#: What each fitted parameter is.
CAUSE_OF = {
    CONTACT_PLUS.name: "contact (+x edge)",
    CONTACT_MINUS.name: "contact (-x edge)",
    PARAMS[2].name: "restitution_scale (loss beyond the rigid impact)",
    cal.SIGMA.name: "contact scatter",
    cal.LAPSE.name: "lapse",
}


def _col(model: str) -> str:
    """Column suffix of a model's probability in the predictions table."""
    return model.replace("-", "_")


def motion_table(folder: str | Path, tests: pd.DataFrame) -> pd.DataFrame:
    """One row per test with a motion file: ground motion, PGA, PGV, peaks, offset and the sign check."""
    rows = []
    for _, row in tests[tests.motion_file != ""].iterrows():
        st = asu_data.read_motion(folder, row)
        acc = st.select(channel="ACC")[0].stats
        rows.append(
            {
                "test": int(row.test),
                "ground_motion": row.ground_motion,
                **asu_data.motion_measures(st),
                "offset_g": acc.offset_g,
                "sign_gain": acc.sign_gain,
                "sign_corr": acc.sign_corr,
            }
        )
    return pd.DataFrame(rows)


def scores(y: ArrayLike, p: ArrayLike) -> dict[str, float | int]:
    """Accuracy (P > 0.5 read as overturning), Brier score and log loss of probabilities ``p``."""
    obs, prob = np.asarray(y, float), np.clip(np.asarray(p, float), cal.PROB_CLIP, 1 - cal.PROB_CLIP)
    return {
        "accuracy": float(np.mean((prob > 0.5) == (obs > 0.5))),
        "brier": float(np.mean((prob - obs) ** 2)),
        "log_loss": float(-np.mean(obs * np.log(prob) + (1 - obs) * np.log1p(-prob))),
        "n_tests": int(obs.size),
    }


def _problem(
    specimen: str, tests: pd.DataFrame, motions: pd.DataFrame, outcomes: xr.Dataset
) -> tuple[pd.DataFrame, np.ndarray, np.ndarray, cal.OutcomeLikelihood]:
    """The tests of ``motions`` with their outcomes, records and the likelihood on the specimen's grid."""
    df = motions.merge(tests.drop(columns=["ground_motion"]), on="test", how="left")
    if not np.array_equal(outcomes.test.values, df.test.values):
        raise ValueError(f"{specimen}: the outcome grid's tests are not those of the motion table")
    y = df[f"overturned_{specimen.lower()}"].to_numpy(bool)
    groups = df.ground_motion.map(asu_data.record_of).to_numpy(str)
    return df, y, groups, cal.OutcomeLikelihood(outcomes.overturned.values, y, grid_of(outcomes))


def cross_validate(
    specimen: str,
    tests: pd.DataFrame,
    motions: pd.DataFrame,
    outcomes: xr.Dataset,
    k: int = 5,
    n_boot: int = 50,
    seed: int = 0,
) -> pd.DataFrame:
    """Held-out predictions of the four models for every test with a motion file.

    Parameters
    ----------
    specimen : str
    tests : DataFrame
        :func:`rocklab.shake_table.asu_data.read_tests`.
    motions : DataFrame
        :func:`motion_table`.
    outcomes : xarray.Dataset
        :func:`rocklab.shake_table.block.outcome_grid` of the specimen, on the
        tests of ``motions``.
    k : int
        Folds (records never split).
    n_boot : int
        Resamples of the training records per fold (the fragility).

    Returns
    -------
    DataFrame
        One row per test: specimen, test, ground_motion, record, fold,
        observed, pga_g, pgv_m_s, the nominal outcome and ``p_<model>`` for
        each of :data:`MODELS`.
    """
    df, y, groups, lik = _problem(specimen, tests, motions, outcomes)
    fold = cal.folds_by_group(groups, k)
    nom = nominal(outcomes)
    dem = asu_data.dem_columns(tests, specimen)
    out = {m: np.zeros(y.size) for m in MODELS}
    for f in range(fold.max() + 1):
        te, tr = np.flatnonzero(fold == f), np.flatnonzero(fold != f)
        out["block-nominal"][te] = cal.deterministic_probability(nom[te], np.mean(nom[tr] != y[tr]))
        fit = cal.calibrate(lik, groups, tr, n_boot, seed + f)
        out["block-calibrated"][te] = fit["fragility"][te]
        x50, beta = cal.logistic_threshold(df.pgv_m_s.to_numpy()[tr], y[tr])
        out["pgv-threshold"][te] = cal.logistic_probability(df.pgv_m_s.to_numpy()[te], x50, beta)
        err = {c: np.mean(df[c].to_numpy(bool)[tr] != y[tr]) for c in dem}
        best = min(dem, key=lambda c: (err[c], c))
        out["dem"][te] = cal.deterministic_probability(df[best].to_numpy(bool)[te], err[best])
        log.info("%s fold %d: %d tests held out, fit %s, DEM setting %s", specimen, f, te.size, fit["values"], best)
    return pd.DataFrame(
        {
            "specimen": specimen,
            "test": df.test,
            "ground_motion": df.ground_motion,
            "record": groups,
            "fold": fold,
            "observed": y,
            "pga_g": df.pga_g,
            "pgv_m_s": df.pgv_m_s,
            "peak_plus_g": df.peak_plus_g,
            "peak_minus_g": df.peak_minus_g,
            "nominal_overturns": nom,
            **{f"p_{_col(m)}": out[m] for m in MODELS},
        }
    )


def score_table(predictions: pd.DataFrame, n_boot: int = N_BOOT_DIFF, seed: int = 0) -> pd.DataFrame:
    """scores.csv: held-out scores of every specimen and model; the calibrated block's accuracy differences.

    Accuracy for every model; Brier score and log loss for the probabilistic
    ones (empty for :data:`DETERMINISTIC`).  On the ``block-calibrated``
    rows, ``diff_vs_<x>`` is its accuracy minus that of each model of
    :data:`COMPARED` on the same tests, ``_lo``/``_hi`` the 95 % paired
    bootstrap interval over records (``record``).
    """
    diffs = [f"diff_vs_{x}{end}" for x, _ in COMPARED for end in ("", "_lo", "_hi")]
    rows = []
    for s, g in predictions.groupby("specimen", sort=True):
        for m in MODELS:
            row = {"specimen": s, "model": m, **scores(g.observed, g[f"p_{_col(m)}"])}
            if m in DETERMINISTIC:
                row.update(brier=np.nan, log_loss=np.nan)
            if m == "block-calibrated":
                for x, other in COMPARED:
                    d = cal.paired_accuracy_difference(
                        g.observed, g.p_block_calibrated, g[f"p_{_col(other)}"], g.record, n_boot, seed
                    )
                    row.update(dict(zip((f"diff_vs_{x}", f"diff_vs_{x}_lo", f"diff_vs_{x}_hi"), d)))
            rows.append(row)
    return pd.DataFrame(rows, columns=["specimen", "model", "accuracy", "brier", "log_loss", "n_tests", *diffs])


def transfer_table(
    tests: pd.DataFrame,
    motions: pd.DataFrame,
    outcomes: Mapping[str, xr.Dataset],
    k: int = 5,
    n_boot: int = 50,
    seed: int = 0,
) -> pd.DataFrame:
    """transfer.csv: each specimen's fit predicting the other replica, held out by record.

    The replicas shook together under the same records, so the transfer is
    cross-validated too: in each fold the contact (in mm), c, sigma and the
    lapse are fitted to one specimen's training folds and predict the other
    specimen's held-out fold at the same physical values (the nearest node of
    its grid, :func:`rocklab.shake_table.block.node_on`); the PGV threshold
    likewise.

    Returns
    -------
    DataFrame
        ``train``, ``test``, ``model`` (:data:`TRANSFERRED`), ``accuracy``,
        ``brier``, ``log_loss``, ``n_tests``.
    """
    names = sorted(outcomes)
    problems = {s: _problem(s, tests, motions, outcomes[s]) for s in names}
    rows = []
    for a in names:
        for b in names:
            if a == b:
                continue
            _, y_a, groups, lik_a = problems[a]
            df, y_b, _, lik_b = problems[b]
            fold = cal.folds_by_group(groups, k)
            p = {m: np.zeros(y_b.size) for m in TRANSFERRED}
            for f in range(fold.max() + 1):
                te, tr = np.flatnonzero(fold == f), np.flatnonzero(fold != f)
                fit = cal.calibrate(lik_a, groups, tr, n_boot, seed + f)
                on_b = [lik_b.node({**v, **node_on(v, lik_b.grid)}) for v in fit["boot"]]
                p["block-calibrated"][te] = np.mean([lik_b.probability(n, te) for n in on_b], axis=0)
                x50, beta = cal.logistic_threshold(df.pgv_m_s.to_numpy()[tr], y_a[tr])
                p["pgv-threshold"][te] = cal.logistic_probability(df.pgv_m_s.to_numpy()[te], x50, beta)
            rows += [{"train": a, "test": b, "model": m, **scores(y_b, p[m])} for m in TRANSFERRED]
    return pd.DataFrame(rows, columns=["train", "test", "model", "accuracy", "brier", "log_loss", "n_tests"])


def onset_edges(peak_plus_g: ArrayLike, peak_minus_g: ArrayLike, block: Mapping[str, float]) -> np.ndarray:
    """Which footprint edges the record can tip the nominal block onto (static onset, exact form).

    The +x edge needs the table to accelerate towards -x by more than
    g tan alpha_+, the -x edge towards +x by more than g tan alpha_-
    (:mod:`rocklab.simulation.rocking_model`, rocking onset).  ``block``: the
    body (:func:`rocklab.shake_table.block.specimen_block`), on its footprint.
    """
    fp = footprint(block)
    plus = np.asarray(peak_minus_g) > np.tan(fp["alpha_plus"])
    minus = np.asarray(peak_plus_g) > np.tan(fp["alpha_minus"])
    return np.select([plus & minus, plus, minus], ["both edges", "+x edge", "-x edge"], "neither edge")


def _bin_labels(x: np.ndarray, edges: Sequence[float], unit: str) -> tuple[np.ndarray, np.ndarray]:
    idx = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, len(edges) - 2)
    labels = [f"{lo:g}-{hi:g} {unit}" if np.isfinite(hi) else f">= {lo:g} {unit}" for lo, hi in zip(edges, edges[1:])]
    return np.array(labels)[idx], idx


def nominal_errors(predictions: pd.DataFrame, blocks: Mapping[str, Mapping[str, float]]) -> pd.DataFrame:
    """Overturns the nominal block predicts against those observed, by PGA, PGV and onset edge."""
    rows = []
    for s, g in predictions.groupby("specimen", sort=True):
        by = {
            "pga": _bin_labels(g.pga_g.to_numpy(), PGA_BINS, "g"),
            "pgv": _bin_labels(g.pgv_m_s.to_numpy(), PGV_BINS, "m/s"),
        }
        edges = onset_edges(g.peak_plus_g, g.peak_minus_g, blocks[s])
        order = ["neither edge", "+x edge", "-x edge", "both edges"]
        by["onset_edge"] = (edges, np.array([order.index(e) for e in edges]))
        for name, (label, key) in by.items():
            for k in np.unique(key):
                m = key == k
                obs, pred = g.observed.to_numpy(bool)[m], g.nominal_overturns.to_numpy(bool)[m]
                rows.append(
                    {
                        "specimen": s,
                        "by": name,
                        "bin": label[m][0],
                        "n_tests": int(m.sum()),
                        "observed_overturns": int(obs.sum()),
                        "nominal_overturns": int(pred.sum()),
                        "missed": int((obs & ~pred).sum()),
                        "false_alarms": int((~obs & pred).sum()),
                        "calibrated_expected": float(g.p_block_calibrated.to_numpy()[m].sum()),
                    }
                )
    return pd.DataFrame(rows)


def rate_interval(
    y: ArrayLike, groups: ArrayLike, n_boot: int = N_BOOT_DIFF, seed: int = 0, level: float = 0.95
) -> tuple[float, float]:
    """Percentile interval of an overturning rate over resampled records (the tests of a record together)."""
    names, inv = np.unique(np.asarray(groups), return_inverse=True)
    per_y = np.bincount(inv, np.asarray(y, float), names.size)
    per_n = np.bincount(inv, minlength=names.size).astype(float)
    draw = np.random.default_rng(seed).integers(0, names.size, (n_boot, names.size))
    boot = per_y[draw].sum(axis=1) / per_n[draw].sum(axis=1)
    return percentile_interval(boot, level)


def fragility_table(predictions: pd.DataFrame) -> pd.DataFrame:
    """Measured overturning rate (95 % interval over records), every model's mean held-out P, by bin of PGA and PGV."""
    rows = []
    for s, g in predictions.groupby("specimen", sort=True):
        for measure, col, edges, unit in (("pga", "pga_g", PGA_BINS, "g"), ("pgv", "pgv_m_s", PGV_BINS, "m/s")):
            label, key = _bin_labels(g[col].to_numpy(), edges, unit)
            for k in np.unique(key):
                m = key == k
                obs = g.observed.to_numpy(float)[m]
                lo, hi = rate_interval(obs, g.record.to_numpy()[m])
                rows.append(
                    {
                        "specimen": s,
                        "measure": measure,
                        "bin": label[m][0],
                        "lower": edges[k],
                        "upper": edges[k + 1] if np.isfinite(edges[k + 1]) else None,
                        "n_tests": int(m.sum()),
                        "n_records": int(g.record[m].nunique()),
                        "observed": float(obs.mean()),
                        "observed_lo": lo,
                        "observed_hi": hi,
                        **{_col(x): float(g[f"p_{_col(x)}"].to_numpy()[m].mean()) for x in MODELS},
                    }
                )
    return pd.DataFrame(rows)


def full_fit(
    specimen: str, tests: pd.DataFrame, motions: pd.DataFrame, outcomes: xr.Dataset, n_boot: int = 200, seed: int = 0
) -> dict[str, Any]:
    """The contact fitted to every test of a specimen, with bootstrap intervals and in-sample fragility."""
    _, y, groups, lik = _problem(specimen, tests, motions, outcomes)
    fit = cal.calibrate(lik, groups, np.arange(y.size), n_boot, seed)
    return {**fit, "grid": lik.grid}


def _at_edge(value: float, nodes: ArrayLike) -> bool:
    return bool(np.isclose(value, np.min(nodes)) or np.isclose(value, np.max(nodes)))


def parameter_table(specimen: str, fit: Mapping[str, Any], block: Mapping[str, float]) -> pd.DataFrame:
    """parameters.csv rows: the fitted parameters and what follows from the contact, with 95 % intervals.

    The contact half-widths [mm], c, the scatter and the lapse; derived from
    the contact: the rocking angles [deg] and the rigid e of leaving each
    edge.  ``null`` is the nominal block's value (the footprint, c = 1, no
    scatter or lapse); ``at_grid_edge`` says where a value sits on the first
    or last node of its grid (its interval then ends there too).
    """
    ci = cal.intervals(fit["boot"])
    nodes = {**fit["grid"], cal.SIGMA.name: cal.SIGMAS, cal.LAPSE.name: cal.LAPSES}
    null = {
        CONTACT_PLUS.name: block["footprint_plus_mm"],
        CONTACT_MINUS.name: block["footprint_minus_mm"],
        PARAMS[2].name: PARAMS[2].null,
        cal.SIGMA.name: cal.SIGMA.null,
        cal.LAPSE.name: cal.LAPSE.null,
    }
    v = fit["values"]
    rows = []
    for name in null:
        lo, hi = ci[name]
        if name in (CONTACT_PLUS.name, CONTACT_MINUS.name):
            named = hi < null[name]  # a contact narrower than the footprint
        else:
            named = cal.named(next(q for q in (*PARAMS, cal.SIGMA, cal.LAPSE) if q.name == name), (lo, hi))
        rows.append(
            {
                "specimen": specimen,
                "parameter": name,
                "cause": CAUSE_OF[name],
                "value": v[name],
                "ci_low": lo,
                "ci_high": hi,
                "null": null[name],
                "named": bool(named),
                "at_grid_edge": _at_edge(v[name], nodes[name]),
                "units": "mm" if name.endswith("_mm") else "1",
            }
        )
    fp = footprint(block)

    def derived(values: Mapping[str, float]) -> list[float]:
        k = contact(block, values[CONTACT_PLUS.name], values[CONTACT_MINUS.name])
        return [np.degrees(k["alpha_plus"]), np.degrees(k["alpha_minus"]), k["e_plus"], k["e_minus"], k["energy_kept"]]

    boot = np.array([derived(b) for b in fit["boot"]])
    names = ("alpha_plus_deg", "alpha_minus_deg", "e_leaving_plus", "e_leaving_minus", "energy_kept")
    nulls = (
        np.degrees(fp["alpha_plus"]),
        np.degrees(fp["alpha_minus"]),
        fp["e_plus"],
        fp["e_minus"],
        fp["energy_kept"],
    )
    for j, (name, value, nv) in enumerate(zip(names, derived(v), nulls)):
        lo, hi = percentile_interval(boot[:, j])
        rows.append(
            {
                "specimen": specimen,
                "parameter": name,
                "cause": "from the contact (derived)",
                "value": float(value),
                "ci_low": float(lo),
                "ci_high": float(hi),
                "null": float(nv),
                "named": False,
                "at_grid_edge": False,
                "units": "deg" if name.endswith("_deg") else "1",
            }
        )
    return pd.DataFrame(rows)


def calibrated_map(
    ag: np.ndarray,
    dt: float,
    block: Mapping[str, float],
    values: Mapping[str, float],
    record: str,
    n: int = 41,
    lo: float = 0.5,
    hi: float = 1.5,
    specimen: str = "",
) -> xr.Dataset:
    """Overturning map (Sect. 5) of the calibrated block under one table record.

    The grid of amplitude and duration scales of
    :func:`rocklab.seismic.maps.scales`, simulated by
    :func:`rocklab.simulation.batch.overturning_batch`; its indices in the
    attributes (:func:`rocklab.seismic.indices.map_indices`).
    """
    model = block_model(block, *(values[q.name] for q in PARAMS))
    amp, dur = scales(n, lo, hi), scales(n, lo, hi)
    t0 = time.perf_counter()
    over = overturning_batch(ag, dt, model, amp, dur, substeps=1, tail=20.0)
    idx = map_indices(over)
    return xr.Dataset(
        {"overturned": (("amplitude_scale", "duration_scale"), over.astype(np.int8), {"long_name": "overturned"})},
        coords={
            "amplitude_scale": ("amplitude_scale", amp, {"long_name": "A_S/A", "units": "1"}),
            "duration_scale": ("duration_scale", dur, {"long_name": "D_S/D", "units": "1"}),
        },
        attrs={
            **cf_attrs(f"overturning map, {specimen} calibrated, test record {record}", "rocklab.shake_table"),
            "specimen": specimen,
            "record": str(record),
            "alpha_rock": model.alpha_pos,
            "alpha_neg": model.alpha_minus,
            "p": model.p,
            **{f"index_{k}": (np.nan if v is None else float(v)) for k, v in idx.items()},
            "compute_s": time.perf_counter() - t0,
        },
    )


def block_inputs(
    folder: str | Path, tests: pd.DataFrame, motions: pd.DataFrame
) -> tuple[list[np.ndarray], list[float]]:
    """The block input [m/s^2] and sample interval [s] of every test of ``motions``, in its order."""
    rows = tests.set_index("test").loc[list(motions.test)].reset_index()
    traces = [asu_data.read_motion(folder, row).select(channel="ACC")[0] for _, row in rows.iterrows()]
    return [asu_data.block_input(tr) for tr in traces], [tr.stats.delta for tr in traces]


def calibration_tables(
    tests: pd.DataFrame,
    motions: pd.DataFrame,
    outcomes: Mapping[str, xr.Dataset],
    blocks: Mapping[str, Mapping[str, float]],
    folds: int = 5,
    n_boot: int = 200,
    n_boot_cv: int = 50,
    seed: int = 0,
) -> dict[str, pd.DataFrame]:
    """Every table of the calibration stage for the specimens of ``outcomes``.

    Returns
    -------
    dict
        ``scores``, ``predictions``, ``nominal_errors``, ``fragility``,
        ``parameters``, ``transfer`` (DataFrames; see the schemas of workflow/schemas/shake_table_*).
    """
    preds, params = [], []
    for specimen, ds in outcomes.items():
        t0 = time.perf_counter()
        pr = cross_validate(specimen, tests, motions, ds, folds, n_boot_cv, seed)
        fit = full_fit(specimen, tests, motions, ds, n_boot, seed)
        pr["p_fragility_in_sample"] = fit["fragility"]
        preds.append(pr)
        params.append(parameter_table(specimen, fit, blocks[specimen]))
        log.info("%s: calibration with %d folds, %.1f s", specimen, folds, time.perf_counter() - t0)
    predictions = pd.concat(preds, ignore_index=True)
    return {
        "scores": score_table(predictions),
        "predictions": predictions,
        "nominal_errors": nominal_errors(predictions, blocks),
        "fragility": fragility_table(predictions),
        "parameters": pd.concat(params, ignore_index=True),
        "transfer": transfer_table(tests, motions, outcomes, folds, n_boot_cv, seed),
    }


def fitted_values(parameters: pd.DataFrame, specimen: str) -> dict[str, float]:
    """The fitted contact and c of one specimen from parameters.csv."""
    p = parameters[parameters.specimen == specimen].set_index("parameter").value
    return {q.name: float(p[q.name]) for q in PARAMS}


def map_tests(predictions: pd.DataFrame, n: int = 2) -> list[int]:
    """Tests whose records are mapped: of the ``n`` ground motions with most tests, the test of median PGA."""
    g = predictions.drop_duplicates("test")
    counts = g.groupby("ground_motion").size().sort_values(ascending=False, kind="stable")
    out = []
    for gm in counts.index[:n]:
        sub = g[g.ground_motion == gm].sort_values(["pga_g", "test"])
        out.append(int(sub.test.iloc[(len(sub) - 1) // 2]))
    return out


def calibrated_maps(
    folder: str | Path,
    tests: pd.DataFrame,
    predictions: pd.DataFrame,
    parameters: pd.DataFrame,
    blocks: Mapping[str, Mapping[str, float]],
    specimen: str,
    n: int = 41,
) -> xr.Dataset:
    """Maps of the calibrated block of ``specimen`` under the records of :func:`map_tests`, on dim ``record``."""
    values = fitted_values(parameters, specimen)
    chosen = map_tests(predictions)
    sub = tests[tests.test.isin(chosen)].set_index("test").loc[chosen].reset_index()
    inputs, dts = block_inputs(folder, tests, sub[["test"]])
    maps = [
        calibrated_map(ag, dt, blocks[specimen], values, f"Test{t:03d} {gm}", n, specimen=specimen).expand_dims(
            record=[f"Test{t:03d} {gm}"]
        )
        for ag, dt, t, gm in zip(inputs, dts, sub.test, sub.ground_motion)
    ]
    out = xr.concat(maps, dim="record", combine_attrs="drop_conflicts")
    for key in ("N_O", "scatter"):
        out[key] = ("record", [m.attrs[f"index_{key}"] for m in maps], {"long_name": f"{key} of the map (Fig. 22)"})
    return out
