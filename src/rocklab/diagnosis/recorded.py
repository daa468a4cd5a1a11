"""Virtual series recorded through the lab's files: what the workflow's diagnosis reads of them.

:func:`rocklab.lab.virtual_lab.series_records` makes a series' records in
memory, theta solved from the five rigid-body transducers; the instruments'
own paths (a rotation record's bridges, an inertial sensor's integration and
rate steps) and the reduction's checks (a channel out of calibration, a
dead instrument, the validity rules) are not on it.  :func:`recorded_series`
writes the same tests in the lab's format with any instrument, its effects
and its faults (:func:`rocklab.lab.virtual_lab.write_campaign`), reduces each
as the workflow does (:func:`rocklab.lab.reduction.reduce_test`,
:func:`rocklab.lab.motion.stored_motion`) and gives the records of
:func:`rocklab.diagnosis.evidence.stored_records`: the whole chain between
a wall and its verdict.
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from rocklab.diagnosis.evidence import records_by_series
from rocklab.io import is_valid
from rocklab.lab import virtual_lab as vl
from rocklab.lab.campaign import open_campaign
from rocklab.lab.motion import motion_from_dataset, stored_motion
from rocklab.lab.reduction import reduce_test
from rocklab.physics.boundary import Boundary


def recorded_series(
    name: str,
    specimen: str,
    boundary: str,
    model: Mapping[str, Any] | Callable[[int], Mapping[str, Any]],
    *,
    instrument: str = "transducers",
    n: int = 6,
    fs: float = 400.0,
    alpha_ratio: float | Callable[[int], float] = 1.0,
    noise_mm: float = 0.002,
    theta0_range: tuple[float, float] = (0.97, 0.998),
    contact_depth_mm: float = 120.0,
    faults: Sequence[vl.Fault] = (),
    seed: int = 0,
    t_end: float = 60.0,
) -> tuple[list[dict[str, Any]], list[str]]:
    """Records of ``n`` virtual tests of one series, written in the lab's format and reduced as the workflow does.

    Parameters
    ----------
    name : str
        The tests' ids are ``<name>-<i>``.
    specimen : str
        A specimen of :data:`rocklab.lab.virtual_lab.DEFAULT_SPECIMENS`.
    boundary : {'two-sided', 'one-sided'}
    model : dict or callable
        ``VirtualTest.model`` (the simulator's keywords: impact law, zeta, mu, kappa, gap...), or test index -> it.
    instrument : {'transducers', 'rotation', 'inertial', 'tdms', 'c3d', 'video'}
        What records each test (``VirtualTest.instrument``), with its default effects.
    fs : float
        Sampling rate [Hz].
    alpha_ratio : float or callable
        The rocking angle over the nominal alpha, or test index -> it.
    noise_mm : float
        Noise and mains hum of every transducer channel [mm] (:class:`rocklab.lab.virtual_lab.Effects`).
    theta0_range : tuple of float
        Release rotation over the rocking angle, drawn uniformly per test.
    contact_depth_mm : float
        One-sided walls only.
    faults : sequence of Fault
        Injected in every test's record (a transducer out of calibration: ``Fault("gain", channel, 0.98)``).
    seed : int
        Seed of the release draws and of the campaign's noise.
    t_end : float
        Longest free rocking simulated [s].

    Returns
    -------
    records : list of dict
        The valid tests' records (:func:`rocklab.diagnosis.evidence.records_by_series`), each with its stored
        motion, in the order of the tests.
    rejected : list of str
        The tests the reduction rejected, each with its reason and detail.
    """
    one = boundary == Boundary.ONE_SIDED
    rng = np.random.default_rng(seed)
    plan = [
        vl.VirtualTest(
            f"{name}-{i}",
            specimen,
            boundary,
            contact_depth_mm=contact_depth_mm if one else None,
            fs=fs,
            alpha_ratio=alpha_ratio(i) if callable(alpha_ratio) else alpha_ratio,
            theta0_ratio=float(rng.uniform(*theta0_range)),
            model=dict(model(i) if callable(model) else model),
            faults=list(faults),
            effects=vl.Effects(noise_mm=noise_mm, hum_mm=noise_mm),
            instrument=instrument,
        )
        for i in range(n)
    ]
    datasets, motions, rejected = [], {}, []
    with tempfile.TemporaryDirectory(prefix="rocklab-series-") as folder:
        vl.write_campaign(folder, plan, seed=seed, t_end=t_end)
        campaign = open_campaign(folder)
        for test_id in (vt.test_id for vt in plan):
            if test_id not in campaign.test_ids:
                rejected.append(f"{test_id}: refused by the campaign: {campaign.log.errors.get(test_id, 'its id')}")
                continue
            ds = reduce_test(campaign, test_id)
            if not is_valid(ds.attrs):
                rejected.append(f"{test_id}: {ds.attrs.get('reject_reason', '')} {ds.attrs.get('reject_detail', '')}")
                continue
            motion = stored_motion(ds)
            datasets.append(ds)
            if "motion_error" not in motion.attrs:
                motions[test_id] = motion_from_dataset(motion)
    by_series = records_by_series(datasets, motions)
    return [r for recs in by_series.values() for r in recs], rejected
