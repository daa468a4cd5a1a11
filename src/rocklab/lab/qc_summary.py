"""What the QC stage publishes for the docs: the verdicts of ``qc.csv``.

Written by the QC job beside ``qc.csv`` (``results/summaries/quality_control.json``,
:mod:`rocklab.summaries`); the page ``docs/quality-control.md`` quotes it.
"""

from __future__ import annotations

from typing import Any

import pandas as pd

from rocklab.lab.validity import Verdict
from rocklab.summaries import LAST_DIGIT

#: How far two machines may take the summary apart: its floats are extremes of
#: release velocities and residual out-of-plumb of least-squares kinematics,
#: which no floating-point environment moved (bench/environments.py): the last
#: digit kept.
TOLERANCES = {"*": LAST_DIGIT}

#: The channel faults the docs count, each by its column of ``qc.csv``
#: (:data:`rocklab.lab.validity.FAULT_COLUMNS`: the channels that had it).
CHANNEL_FAULTS = {
    "spikes_repaired": "channels_spikes_repaired",
    "dead": "channels_dead",
    "stuck": "channels_stuck",
    "clipped": "channels_clipped",
    "dropout": "channels_dropout",
    "backup_used": "channels_backup_used",
}


def _span(values: pd.Series) -> dict[str, Any]:
    values = values.dropna()
    return {"min": values.min(), "max": values.max()} if len(values) else {"min": None, "max": None}


def quality_control_summary(qc: pd.DataFrame) -> dict[str, Any]:
    """Verdicts, the margins of the decisions and the channel faults of a campaign.

    Parameters
    ----------
    qc : DataFrame
        ``qc.csv`` as read back (:data:`rocklab.lab.reduction.QC_COLUMNS`).

    Returns
    -------
    dict
        ``n_tests``, ``n_series``, ``verdicts`` (tests per :class:`Verdict`, 0
        where none), ``release_velocity_pct`` (span of the release velocity over
        Eq. 16 [%] of the valid and the disturbed tests), ``residual_top_mm``
        (largest residual of a valid test, smallest of an out-of-plumb one
        [mm]), ``channel_faults`` (tests with each fault on some channel, v left unsolved) and
        ``series`` (valid, rejected and each rejection per series, in name order).
    """
    verdict = qc["reject_reason"].fillna("").replace("", Verdict.VALID.value)
    counts = pd.crosstab(qc["series"], verdict).reindex(columns=[v.value for v in Verdict], fill_value=0)
    return {
        "n_tests": len(qc),
        "n_series": qc["series"].nunique(),
        "verdicts": {v.value: int((verdict == v).sum()) for v in Verdict},
        "release_velocity_pct": {
            "valid": _span(100 * qc.loc[verdict == Verdict.VALID, "release_velocity_ratio"]),
            "disturbed": _span(100 * qc.loc[verdict == Verdict.DISTURBED_INITIAL_CONDITIONS, "release_velocity_ratio"]),
        },
        "residual_top_mm": {
            "valid_max": _span(qc.loc[verdict == Verdict.VALID, "residual_top_mm"])["max"],
            "out_of_plumb_min": _span(qc.loc[verdict == Verdict.RESIDUAL_OUT_OF_PLUMB, "residual_top_mm"])["min"],
        },
        "channel_faults": {
            # a column without a single fault reads back as all-NaN floats
            **{k: int(qc[c].astype("string").fillna("").ne("").sum()) for k, c in CHANNEL_FAULTS.items()},
            "in_plane_lost": int(qc["in_plane_lost"].astype(bool).sum()),
        },
        "series": [
            {
                "series": series,
                "n_valid": int(row[Verdict.VALID]),
                "n_rejected": int(row.sum() - row[Verdict.VALID]),
                # an unreadable test has no series: its row could not be read
                **{v.value: int(row[v]) for v in Verdict.rejections() if v is not Verdict.UNREADABLE},
            }
            for series, row in counts.iterrows()
        ],
    }
