"""What the shake-table stage publishes for the docs (target ``shake_table``).

Written by the calibration job from the tables it has just written
(``results/summaries/shake_table.json``, :mod:`rocklab.summaries`); the page
``docs/shake-table.md`` quotes it, with the job times of the stage from
:func:`rocklab.benchmarks.performance_summary`.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

from rocklab.shake_table import calibration
from rocklab.shake_table.asu_data import SPECIMENS
from rocklab.shake_table.block import C_NODES, CONTACT_NODES_MM
from rocklab.summaries import LAST_DIGIT, Tolerance

#: Held-out accuracy the calibrated block is asked for on each replica (issue 25).
TARGET_ACCURACY = 0.93

#: Predictions of the held-out tests that may flip between machines: a test whose
#: simulated histories sit on an overturning boundary turns on the last bits of
#: the arithmetic (measured, bench/environments.py: one test of 490 between four
#: floating-point environments, its Brier score moving 5e-4 and its log loss
#: 3.4e-3); five times that.
_FLIPPED_PREDICTIONS = 5 / 490
#: How far two machines may take the summary apart: an accuracy (and a difference
#: of two, its interval, the shortfall from the target) by the flipped
#: predictions, the probabilistic scores by five times their measured move; the
#: fitted parameters (grid nodes and their intervals), the records and the
#: design, which no environment moved, to the last digit kept.
TOLERANCES = {
    "*.accuracy": Tolerance(abs=_FLIPPED_PREDICTIONS),
    "*.target_shortfall": Tolerance(abs=_FLIPPED_PREDICTIONS),
    "*.diff_vs_*": Tolerance(abs=2 * _FLIPPED_PREDICTIONS),
    "*.brier": Tolerance(abs=0.0025),
    "*.log_loss": Tolerance(abs=0.02),
    "*": LAST_DIGIT,
}


def _number(x: Any) -> Any:
    """A table's value for JSON: None where empty."""
    return None if x is None or (isinstance(x, float) and np.isnan(x)) else x


def unrecorded(tests: pd.DataFrame) -> dict[str, Any]:
    """The tests without a table record: how many, how often each replica overturned, and under what.

    They cannot be simulated nor scored (no motion); their outcome rates,
    beside those of the tests with a record, say what leaving them out does
    to the sample.
    """
    none = tests.motion_file == ""
    out: dict[str, Any] = {"n_tests": int(none.sum()), "n_with_record": int((~none).sum()), "n_total": len(tests)}
    for s in SPECIMENS:
        col = tests[f"overturned_{s.lower()}"]
        out[s] = {
            "rate_without_record": float(col[none].mean()) if none.any() else None,
            "rate_with_record": float(col[~none].mean()),
        }
    counts = tests[none].ground_motion.value_counts()
    out["ground_motions"] = [f"{k} ({v})" for k, v in counts.items()]
    return out


def shake_table_summary(
    tables: Mapping[str, str | Path], outcomes: Iterable[str | Path], tests: pd.DataFrame
) -> dict[str, Any]:
    """The shake-table outcomes against the nominal block and the fitted contact (target ``shake_table``).

    Parameters
    ----------
    tables : mapping
        Paths of the tables of the rule ``shake_table_calibration`` as written
        (``scores``, ``parameters``, ``predictions``, ``nominal_errors``, ``transfer``).
    outcomes : sequence of str or pathlib.Path
        The outcome grids of the specimens (``shake_table/outcomes_<specimen>.nc``).
    tests : DataFrame
        tests.csv (:func:`rocklab.shake_table.asu_data.read_tests`): the tests without a record.

    Returns
    -------
    dict
        ``specimens`` and per specimen its tests, observed and predicted
        overturnings, scores (with the calibrated block's accuracy
        differences), parameters and the shortfall from the target
        accuracy; ``transfer``; ``unrecorded``; ``n_histories`` and ``grid``.
    """
    scores, params, preds, errors, transfer = (
        pd.read_csv(tables[k]) for k in ("scores", "parameters", "predictions", "nominal_errors", "transfer")
    )
    out: dict[str, Any] = {"specimens": sorted(scores.specimen.unique()), "target_accuracy": TARGET_ACCURACY}
    for s, g in preds.groupby("specimen"):
        obs, nom = g.observed.astype(bool), g.nominal_overturns.astype(bool)
        e = errors[(errors.specimen == s) & (errors.by == "onset_edge")].set_index("bin")
        neither = e.loc["neither edge"] if "neither edge" in e.index else None
        sc = {
            r["model"]: {k: _number(v) for k, v in r.items() if k not in ("specimen", "model")}
            for r in scores[scores.specimen == s].to_dict("records")
        }
        acc = sc["block-calibrated"]["accuracy"]
        out[s] = {
            "n_tests": len(g),
            "n_ground_motions": g.ground_motion.nunique(),
            "n_records": g.record.nunique(),
            "observed_overturns": int(obs.sum()),
            "nominal_overturns": int(nom.sum()),
            "nominal_missed": int((obs & ~nom).sum()),
            "nominal_false_alarms": int((~obs & nom).sum()),
            "min_pga_overturned_g": g.pga_g[obs].min() if obs.any() else None,
            "neither_edge_tests": None if neither is None else int(neither.n_tests),
            "neither_edge_overturns": None if neither is None else int(neither.observed_overturns),
            "scores": sc,
            "target_shortfall": max(0.0, TARGET_ACCURACY - acc),
            # tests more it would take to reach the target (rounded up)
            "target_shortfall_tests": int(np.ceil(round(max(0.0, TARGET_ACCURACY - acc) * len(g), 9))),
            "beats_pgv": bool(sc["block-calibrated"]["diff_vs_pgv_lo"] > 0),
            "parameters": {
                r.parameter: {
                    "value": r.value,
                    "ci_low": r.ci_low,
                    "ci_high": r.ci_high,
                    "null": r.null,
                    "named": bool(r.named),
                    "at_grid_edge": bool(r.at_grid_edge),
                    "units": r.units,
                    "cause": r.cause,
                }
                for r in params[params.specimen == s].itertuples()
            },
        }
    out["transfer"] = {
        f"{r.train}_to_{r.test}": {
            "train": r.train,
            "test": r.test,
            "model": r.model,
            "accuracy": r.accuracy,
            "brier": r.brier,
            "log_loss": r.log_loss,
            "n_tests": int(r.n_tests),
        }
        for r in transfer[transfer.model == "block-calibrated"].itertuples()
    }
    out["transfer_pgv"] = {
        f"{r.train}_to_{r.test}": {"accuracy": r.accuracy, "brier": r.brier}
        for r in transfer[transfer.model == "pgv-threshold"].itertuples()
    }
    out["unrecorded"] = unrecorded(tests)
    out["design"] = {
        "contact_lowest_mm": float(CONTACT_NODES_MM[0]),
        "contact_step": float(CONTACT_NODES_MM[1] / CONTACT_NODES_MM[0]),
        "c_nodes": [float(c) for c in C_NODES],
        "sigma_nodes": [float(x) for x in calibration.SIGMAS],
        "lapse_nodes": [float(x) for x in calibration.LAPSES],
    }
    if len(out["specimens"]) == 2:
        a, b = (out[s]["parameters"] for s in out["specimens"])
        out["contacts_overlap"] = {
            k: bool(a[k]["ci_low"] <= b[k]["ci_high"] and b[k]["ci_low"] <= a[k]["ci_high"])
            for k in ("contact_plus_mm", "contact_minus_mm")
        }
        out["transfer_beats_pgv_there"] = all(
            v["accuracy"] >= out[v["test"]]["scores"]["pgv-threshold"]["accuracy"] for v in out["transfer"].values()
        )
    grids = [xr.load_dataset(path) for path in sorted(map(str, outcomes))]
    out["n_histories"] = sum(int(ds.attrs["n_histories"]) for ds in grids) if grids else None
    out["grid"] = (
        {ds.attrs["specimen"]: {k: int(v) for k, v in ds.overturned.sizes.items() if k != "test"} for ds in grids}
        if grids
        else None
    )
    return out
