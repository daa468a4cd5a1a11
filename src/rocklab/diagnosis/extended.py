"""The extended model of named causes: the catalogue's laws on the one wall model.

A model of the diagnosis is named by its causes (``ext``, names of
:mod:`rocklab.diagnosis.catalogue`) and their parameter ``values``; here
the names become the causes' laws (:func:`rocklab.diagnosis.catalogue.laws`)
acting on the base model of :mod:`rocklab.diagnosis.wall_model`: its per-test
arrays (:func:`model_params`), the exact simulator of one wall
(:func:`rocking_model`), what the model's free run gets wrong
(:func:`engineering_errors`) and the tests it would have given, measured
as the lab measures (:func:`simulated_tests`).
"""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from dataclasses import replace

import numpy as np

from rocklab.diagnosis import catalogue
from rocklab.diagnosis.errors import engineering_rows, history_rms, summarise_rows
from rocklab.diagnosis.estimation import finite_mean
from rocklab.diagnosis.evidence import MeasuredTest, measured_test
from rocklab.diagnosis.result import Errors
from rocklab.diagnosis.wall_model import ModelParams, log_columns, model_of, simulate_test, simulator
from rocklab.lab.motion import noise_level
from rocklab.simulation.rocking_model import RockingModel


def model_params(
    tests: Sequence[MeasuredTest],
    ext: Collection[str] = (),
    values: Mapping[str, float] | None = None,
    base: ModelParams | None = None,
) -> ModelParams:
    """ModelParams of the base model extended by the causes ``ext`` with parameter ``values``.

    The causes act in catalogue order; the values of causes outside ``ext``
    are not used.  ``base``: :func:`rocklab.diagnosis.wall_model.base_params` of
    ``tests`` already made (the causes replace its arrays, never change them),
    which holds the columns of their test log
    (:meth:`rocklab.diagnosis.wall_model.ModelParams.log_columns`).
    """
    # a drift along a column of the test log that these tests (the maps' wall) lack still acts
    own = log_columns(tests) if base is None else base.log_columns()
    columns = set(own) | catalogue.log_columns_of(ext)
    return model_of(tests, catalogue.laws(ext, values, tuple(sorted(columns))), base)


def rocking_model(
    test: MeasuredTest, ext: Collection[str] = (), values: Mapping[str, float] | None = None, base: str = "analytic"
) -> RockingModel:
    """The exact simulator of a diagnosis model, for one test (:func:`rocklab.diagnosis.wall_model.simulator`).

    ``base``: ``"analytic"`` (Eq. 2 / Eq. 14), ``"two-sided-e"`` (e_an,2s used
    for a one-sided wall, Hogan 1992) or ``"zero"`` (e = 0, Liberatore & Spera
    2003).
    """
    return simulator(model_params([test], ext, values).row(0), base)


def simulate_measured(
    test: MeasuredTest,
    ext: Collection[str] = (),
    values: Mapping[str, float] | None = None,
    base: str = "analytic",
    t_end: float | None = None,
    fs: float | None = None,
    engine: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Free run of a diagnosis model (exact simulator) from a measured test's release, on its clock
    (:func:`rocklab.diagnosis.wall_model.simulate_test`; ``engine``: by the numba engine where it
    holds the wall)."""
    return simulate_test(test, rocking_model(test, ext, values, base), t_end, fs, engine)


def engineering_errors(
    tests: Sequence[MeasuredTest],
    ext: Collection[str] = (),
    values: Mapping[str, float] | None = None,
    base: str = "analytic",
    n_history: int = 2,
) -> Errors:
    """Series means of :func:`rocklab.diagnosis.errors.engineering_rows` and the RMS of theta/alpha
    on ``n_history`` tests (the numba engine where it holds the wall, else the exact simulator: the
    same record within the tolerance of :func:`rocklab.diagnosis.wall_model.simulate_test`)."""
    out = summarise_rows(engineering_rows(tests, model_params(tests, ext, values).with_base(base)))
    rms = [history_rms(t, rocking_model(t, ext, values, base)) for t in tests[:n_history]]
    out["rms_theta_over_alpha"] = finite_mean(rms) if rms else None
    return out


def simulated_tests(
    tests: Sequence[MeasuredTest], ext: Collection[str] = (), values: Mapping[str, float] | None = None, seed: int = 0
) -> list[MeasuredTest]:
    """The tests a diagnosis model would have given: each measured test run from its release on its
    clock by the numba engine where it holds the wall, else by the exact simulator
    (:func:`simulate_measured`), white noise of its measured level
    added (:func:`rocklab.lab.motion.noise_level`), read by the lab's extraction
    (:func:`rocklab.diagnosis.evidence.measured_test`).

    Each keeps its place in the series and its test log; tests of fewer than two impacts are left out.
    On the embedded campaign the engine's records (against the exact simulator's) moved the model bias
    they give (:mod:`rocklab.diagnosis.estimation.bias`) by 2e-8 at most in the parameters' units
    (1.3e-3 of its ``u_model`` where that is not zero), the parameters' intervals by 2e-7 of their
    bounds, and no verdict.

    Raises
    ------
    ValueError
        For a test without its rotation record.
    NotImplementedError
        For a law the exact simulator lacks (:func:`rocklab.diagnosis.wall_model.simulator`).
    """
    rng = np.random.default_rng(seed)
    out = []
    for t in tests:
        if t.theta is None:
            raise ValueError(f"test {t.test_id}: no rotation record to simulate its measurement")
        fs = 1.0 / t.dt
        # the engine's record is the exact simulator's within the tolerance of wall_model.simulate_test
        # (5.5e-9 rad measured), a thousandth of the noise added (3e-6 rad or more), for a tenth of its cost
        ts, theta = simulate_measured(t, ext, values, engine=True)
        theta = theta + rng.normal(0.0, noise_level(t.theta, fs), theta.size)
        record = dict(test_id=t.test_id, t=ts, theta=theta, fs=fs, alpha=t.alpha, p=t.p, boundary=t.boundary,
                      direction=t.direction, series=t.series, instrument=t.instrument)  # fmt: skip
        sim = measured_test(record)
        if sim.n_impacts >= 2:
            out.append(replace(sim, order=t.order, log=t.log))
    return out
