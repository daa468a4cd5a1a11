"""The indices of an overturning map (Sect. 5, Fig. 22): how much of it overturns, and how scattered.

:func:`map_indices` reads one map of :func:`rocklab.seismic.maps.overturning_map`;
:func:`summary_table` is one row of them per map (``results/maps/summary.csv``),
what the paper's comparison (:mod:`rocklab.seismic.paper_comparison`) and the
calibrated walls' table (:func:`rocklab.seismic.calibrated.calibrated_table`) read.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import numpy.typing as npt
import pandas as pd
import xarray as xr

#: Fraction of a map's cells that may flip between machines: 0.2 %, 20 cells of a
#: calibrated wall's map (101 x 101), 80 of the paper's (201 x 201), a tenth of the
#: cells next to an overturning boundary that crosses the map. A cell next to
#: that boundary lies on a chaotic one: its history turns on the last bits of
#: the machine's arithmetic. Seen: one cell of a paper's map, some eight of
#: sixteen calibrated ones (``bench/environments.py``); earlier, four of a
#: calibrated map between two machines.
FLIPPED_FRACTION = 0.002


def map_indices(overturned: xr.DataArray | npt.ArrayLike) -> dict[str, float]:
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


def summary_table(maps: Iterable[xr.Dataset]) -> pd.DataFrame:
    """One row of :func:`map_indices` per map, with its record and model.

    Parameters
    ----------
    maps : iterable of xarray.Dataset
        Results of :func:`rocklab.seismic.maps.overturning_map`.

    Returns
    -------
    pandas.DataFrame
        record, model and the fields of :func:`map_indices`.
    """
    rows = [{"record": ds.attrs["record"], "model": ds.attrs["model"], **map_indices(ds["overturned"])} for ds in maps]
    return pd.DataFrame(rows)
