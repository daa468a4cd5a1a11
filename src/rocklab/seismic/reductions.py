"""Per-record reductions of the map indices from one model to another (Sect. 5).

Read by the paper's comparison (:func:`rocklab.seismic.paper_comparison.reductions`)
and by the calibrated walls' table (:func:`rocklab.seismic.calibrated.calibrated_table`).
"""

from __future__ import annotations

import pandas as pd


def record_reductions(summary: pd.DataFrame, baseline: str, model: str) -> pd.DataFrame:
    """Per-record reduction [%] of N_O and of the scatter from ``baseline`` to ``model``.

    100 (1 - x_model / x_baseline); NaN where the baseline's index is zero or
    undefined (no overturning).  A negative value is an increase.

    Returns
    -------
    pandas.DataFrame
        Indexed by record: N_O and scatter reductions [%].
    """
    wide = summary.set_index(["record", "model"])[["N_O", "scatter"]].unstack("model")
    out = {}
    for index in ("N_O", "scatter"):
        base, new = wide[(index, baseline)], wide[(index, model)]
        out[index] = 100.0 * (1.0 - new / base.where(base > 0))
    return pd.DataFrame(out)
