"""Held-out comparison of the block, the PGV threshold and the DEM model; what the nominal block gets wrong.

Every model is scored on the same tests (those with a motion file), each
predicted by a fit to the other folds (:func:`cross_validate`):

- ``block-nominal``: the specimen's footprint block, no parameter fitted;
- ``block-calibrated``: the causes fitted to the training folds, the
  prediction the mean P over resampled fits (fragility);
- ``pgv-threshold``: a logistic threshold on PGV fitted to the training folds;
- ``dem``: the source's DEM predictions as given, the stiffness setting the
  training folds classify best.

A 0/1 predictor (nominal block, DEM) scores as a probability whose lapse is
its error rate on the training folds
(:func:`rocklab.shake_table.calibration.deterministic_probability`).
"""

from __future__ import annotations

import logging
import time

import numpy as np
import pandas as pd
import xarray as xr

from rocklab.io import cf_attrs
from rocklab.seismic.indices import map_indices
from rocklab.seismic.maps import scales
from rocklab.shake_table import calibration as cal
from rocklab.shake_table import records
from rocklab.shake_table.block import CAUSES, PARAMS, block_model, hinge_angles, nominal
from rocklab.simulation.batch import overturning_batch

log = logging.getLogger(__name__)

#: The models of scores.csv, in its order.
MODELS = ("block-nominal", "block-calibrated", "pgv-threshold", "dem")

#: Bins of the tables by PGA [g] and PGV [m/s].
PGA_BINS = (0.0, 0.1, 0.2, 0.3, 0.5, 0.8, np.inf)
PGV_BINS = (0.0, 0.05, 0.1, 0.15, 0.2, 0.3, np.inf)

#: Cause of each fitted parameter: the block's causes (:data:`rocklab.shake_table.block.CAUSES`), the
#: scatter of the first one's (:data:`rocklab.shake_table.calibration.SIGMA`) and the lapse.
CAUSE_OF = {q.name: c.name for c in CAUSES for q in c.params if q.name in {p.name for p in PARAMS}}
CAUSE_OF |= {cal.SIGMA.name: f"{CAUSE_OF[PARAMS[0].name]} (scatter)", cal.LAPSE.name: "lapse"}


def _col(model):
    """Column suffix of a model's probability in the predictions table."""
    return model.replace("-", "_")


def motion_table(folder, tests: pd.DataFrame) -> pd.DataFrame:
    """One row per test with a motion file: ground motion, PGA, PGV, peaks, offset and the sign check."""
    rows = []
    for _, row in tests[tests.motion_file != ""].iterrows():
        st = records.read_motion(folder, row)
        acc = st.select(channel="ACC")[0].stats
        rows.append(
            {
                "test": int(row.test),
                "ground_motion": row.ground_motion,
                **records.motion_measures(st),
                "offset_g": acc.offset_g,
                "sign_gain": acc.sign_gain,
                "sign_corr": acc.sign_corr,
            }
        )
    return pd.DataFrame(rows)


def scores(y, p) -> dict:
    """Accuracy (P > 0.5 read as overturning), Brier score and log loss of probabilities ``p``."""
    y, p = np.asarray(y, float), np.clip(np.asarray(p, float), cal.PROB_CLIP, 1 - cal.PROB_CLIP)
    return {
        "accuracy": float(np.mean((p > 0.5) == (y > 0.5))),
        "brier": float(np.mean((p - y) ** 2)),
        "log_loss": float(-np.mean(y * np.log(p) + (1 - y) * np.log1p(-p))),
        "n_tests": int(y.size),
    }


def cross_validate(specimen, tests, motions, outcomes: xr.Dataset, k=5, n_boot=50, seed=0) -> pd.DataFrame:
    """Held-out predictions of the four models for every test with a motion file.

    Parameters
    ----------
    specimen : str
    tests : DataFrame
        :func:`rocklab.shake_table.records.read_tests`.
    motions : DataFrame
        :func:`motion_table`.
    outcomes : xarray.Dataset
        :func:`rocklab.shake_table.block.outcome_grid` of the specimen, on the
        tests of ``motions``.
    k : int
        Folds (ground motions never split).
    n_boot : int
        Resamples of the training ground motions per fold (the fragility).

    Returns
    -------
    DataFrame
        One row per test: specimen, test, ground_motion, fold, observed,
        pga_g, pgv_m_s, the nominal outcome and ``p_<model>`` for each of
        :data:`MODELS`.
    """
    df = motions.merge(tests.drop(columns=["ground_motion"]), on="test", how="left")
    if not np.array_equal(outcomes.test.values, df.test.values):
        raise ValueError(f"{specimen}: the outcome grid's tests are not those of the motion table")
    y = df[f"overturned_{specimen.lower()}"].to_numpy(bool)
    groups = df.ground_motion.to_numpy(str)
    fold = cal.folds_by_group(groups, k)
    grid = {q.name: outcomes[q.name].values for q in PARAMS}
    lik = cal.OutcomeLikelihood(outcomes.overturned.values, y, grid)
    nom = nominal(outcomes)
    dem = records.dem_columns(tests, specimen)
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
            "ground_motion": groups,
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


def score_table(predictions: pd.DataFrame) -> pd.DataFrame:
    """scores.csv: held-out accuracy, Brier score and log loss of every specimen and model."""
    rows = [
        {"specimen": s, "model": m, **scores(g.observed, g[f"p_{_col(m)}"])}
        for s, g in predictions.groupby("specimen", sort=True)
        for m in MODELS
    ]
    return pd.DataFrame(rows, columns=["specimen", "model", "accuracy", "brier", "log_loss", "n_tests"])


def onset_edges(peak_plus_g, peak_minus_g, block) -> np.ndarray:
    """Which footprint edges the record can tip the nominal block onto (static onset, exact form).

    The +x edge needs the table to accelerate towards -x by more than
    g tan alpha_+, the -x edge towards +x by more than g tan alpha_-
    (:mod:`rocklab.simulation.model`, rocking onset).
    """
    plus = np.asarray(peak_minus_g) > np.tan(block["alpha_plus"])
    minus = np.asarray(peak_plus_g) > np.tan(block["alpha_minus"])
    return np.select([plus & minus, plus, minus], ["both edges", "+x edge", "-x edge"], "neither edge")


def _bin_labels(x, edges, unit):
    idx = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, len(edges) - 2)
    labels = [f"{lo:g}-{hi:g} {unit}" if np.isfinite(hi) else f">= {lo:g} {unit}" for lo, hi in zip(edges, edges[1:])]
    return np.array(labels)[idx], idx


def nominal_errors(predictions: pd.DataFrame, blocks: dict) -> pd.DataFrame:
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


def fragility_table(predictions: pd.DataFrame) -> pd.DataFrame:
    """Observed overturning rate and every model's mean held-out P by bin of PGA and PGV."""
    rows = []
    for s, g in predictions.groupby("specimen", sort=True):
        for measure, col, edges, unit in (("pga", "pga_g", PGA_BINS, "g"), ("pgv", "pgv_m_s", PGV_BINS, "m/s")):
            label, key = _bin_labels(g[col].to_numpy(), edges, unit)
            for k in np.unique(key):
                m = key == k
                rows.append(
                    {
                        "specimen": s,
                        "measure": measure,
                        "bin": label[m][0],
                        "lower": edges[k],
                        "upper": edges[k + 1] if np.isfinite(edges[k + 1]) else None,
                        "n_tests": int(m.sum()),
                        "observed": float(g.observed.to_numpy(float)[m].mean()),
                        **{_col(x): float(g[f"p_{_col(x)}"].to_numpy()[m].mean()) for x in MODELS},
                    }
                )
    return pd.DataFrame(rows)


def full_fit(specimen, tests, motions, outcomes, n_boot=200, seed=0):
    """The causes fitted to every test of a specimen, with bootstrap intervals and in-sample fragility."""
    df = motions.merge(tests.drop(columns=["ground_motion"]), on="test", how="left")
    y = df[f"overturned_{specimen.lower()}"].to_numpy(bool)
    grid = {q.name: outcomes[q.name].values for q in PARAMS}
    lik = cal.OutcomeLikelihood(outcomes.overturned.values, y, grid)
    groups = df.ground_motion.to_numpy(str)
    return cal.calibrate(lik, groups, np.arange(y.size), n_boot, seed)


def parameter_table(specimen, fit, block) -> pd.DataFrame:
    """parameters.csv rows: every fitted parameter and the hinge angles [deg] with 95 % intervals."""
    ci = cal.intervals(fit["boot"])
    rows = []
    for q in (*PARAMS, cal.SIGMA, cal.LAPSE):
        rows.append(
            {
                "specimen": specimen,
                "parameter": q.name,
                "cause": CAUSE_OF[q.name],
                "value": fit["values"][q.name],
                "ci_low": ci[q.name][0],
                "ci_high": ci[q.name][1],
                "null": q.null,
                "named": cal.named(q, ci[q.name]),
                "units": "1",
            }
        )
    v = fit["values"]
    boot = np.array([hinge_angles(block, b["alpha_r_over_alpha"], b["s_alpha"]) for b in fit["boot"]])
    for j, edge in enumerate(("plus", "minus")):
        value = hinge_angles(block, v["alpha_r_over_alpha"], v["s_alpha"])[j]
        lo, hi = np.percentile(boot[:, j], [2.5, 97.5])
        rows.append(
            {
                "specimen": specimen,
                "parameter": f"alpha_{edge}_deg",
                "cause": "hinge angle (derived)",
                "value": float(np.degrees(value)),
                "ci_low": float(np.degrees(lo)),
                "ci_high": float(np.degrees(hi)),
                "null": float(np.degrees(block[f"alpha_{edge}"])),
                "named": False,
                "units": "deg",
            }
        )
    return pd.DataFrame(rows)


def calibrated_map(ag, dt, block, values, record, n=41, lo=0.5, hi=1.5, specimen="") -> xr.Dataset:
    """Overturning map (Sect. 5) of the calibrated block under one table record.

    The grid of amplitude and duration scales of
    :func:`rocklab.seismic.maps.scales`, simulated by
    :func:`rocklab.simulation.batch.overturning_batch`; its indices in the
    attributes (:func:`rocklab.seismic.indices.map_indices`).
    """
    model = block_model(block, values["alpha_r_over_alpha"], values["s_alpha"], values["c"])
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


def block_inputs(folder, tests: pd.DataFrame, motions: pd.DataFrame):
    """The block input [m/s^2] and sample interval [s] of every test of ``motions``, in its order."""
    rows = tests.set_index("test").loc[list(motions.test)].reset_index()
    traces = [records.read_motion(folder, row).select(channel="ACC")[0] for _, row in rows.iterrows()]
    return [records.block_input(tr) for tr in traces], [tr.stats.delta for tr in traces]


def calibration_tables(tests, motions, outcomes: dict, blocks: dict, folds=5, n_boot=200, n_boot_cv=50, seed=0):
    """Every table of the calibration stage for the specimens of ``outcomes``.

    Returns
    -------
    dict
        ``scores``, ``predictions``, ``nominal_errors``, ``fragility``,
        ``parameters`` (DataFrames; see the schemas of workflow/schemas/shake_table_*).
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
    }


def fitted_values(parameters: pd.DataFrame, specimen: str) -> dict:
    """The fitted causes' parameters of one specimen from parameters.csv."""
    p = parameters[parameters.specimen == specimen].set_index("parameter").value
    return {q.name: float(p[q.name]) for q in PARAMS}


def map_tests(predictions: pd.DataFrame, n=2) -> list[int]:
    """Tests whose records are mapped: of the ``n`` ground motions with most tests, the test of median PGA."""
    g = predictions.drop_duplicates("test")
    counts = g.groupby("ground_motion").size().sort_values(ascending=False, kind="stable")
    out = []
    for gm in counts.index[:n]:
        sub = g[g.ground_motion == gm].sort_values(["pga_g", "test"])
        out.append(int(sub.test.iloc[(len(sub) - 1) // 2]))
    return out


def calibrated_maps(folder, tests, predictions, parameters, blocks, specimen, n=41) -> xr.Dataset:
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
