"""What the shake-table stage publishes for the docs (target ``shake_table``).

Written by the calibration job from the tables it has just written
(``results/summaries/shake_table.json``, :mod:`rocklab.summaries`); the page
``docs/shake-table.md`` quotes it, with the job times of the stage from
:func:`rocklab.benchmarks.performance_summary`.
"""

from __future__ import annotations

import pandas as pd
import xarray as xr


def shake_table_summary(tables, outcomes) -> dict:
    """The shake-table outcomes against the nominal block and the fitted causes (target ``shake_table``).

    Parameters
    ----------
    tables : mapping
        Paths of the tables of the rule ``shake_table_calibration`` as written
        (``scores``, ``parameters``, ``predictions``, ``nominal_errors``).
    outcomes : sequence of str or pathlib.Path
        The outcome grids of the specimens (``shake_table/outcomes_<specimen>.nc``).

    Returns
    -------
    dict
        ``specimens`` and per specimen its tests, observed and predicted
        overturnings, scores and parameters; ``n_histories`` and ``grid``, the
        histories simulated and the nodes of the causes' grid.
    """
    scores, params, preds, errors = (
        pd.read_csv(tables[k]) for k in ("scores", "parameters", "predictions", "nominal_errors")
    )
    out = {"specimens": sorted(scores.specimen.unique())}
    for s, g in preds.groupby("specimen"):
        obs, nom = g.observed.astype(bool), g.nominal_overturns.astype(bool)
        e = errors[(errors.specimen == s) & (errors.by == "onset_edge")].set_index("bin")
        neither = e.loc["neither edge"] if "neither edge" in e.index else None
        out[s] = {
            "n_tests": len(g),
            "n_ground_motions": g.ground_motion.nunique(),
            "observed_overturns": int(obs.sum()),
            "nominal_overturns": int(nom.sum()),
            "nominal_missed": int((obs & ~nom).sum()),
            "nominal_false_alarms": int((~obs & nom).sum()),
            "min_pga_overturned_g": g.pga_g[obs].min() if obs.any() else None,
            "neither_edge_tests": None if neither is None else int(neither.n_tests),
            "neither_edge_overturns": None if neither is None else int(neither.observed_overturns),
            "scores": {
                r.model: {"accuracy": r.accuracy, "brier": r.brier, "log_loss": r.log_loss, "n_tests": r.n_tests}
                for r in scores[scores.specimen == s].itertuples()
            },
            "parameters": {
                r.parameter: {
                    "value": r.value,
                    "ci_low": r.ci_low,
                    "ci_high": r.ci_high,
                    "null": r.null,
                    "named": bool(r.named),
                    "cause": r.cause,
                }
                for r in params[params.specimen == s].itertuples()
            },
        }
    grids = [xr.load_dataset(path) for path in sorted(map(str, outcomes))]
    out["n_histories"] = sum(int(ds.attrs["n_histories"]) for ds in grids) if grids else None
    out["grid"] = {k: int(v) for k, v in grids[0].overturned.sizes.items() if k != "test"} if grids else None
    return out
