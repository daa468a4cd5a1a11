"""The planar rocking block of each specimen and its outcome under the table records.

Each specimen is the rocking block of ``geometry.json``'s footprint edges:
theta > 0 rotates it about its +x edge (rocking angle alpha_+), theta < 0
about its -x edge (alpha_-), with the exact form of
:class:`rocklab.simulation.model.RockingModel` and Housner's e of each edge,
e = 1 - 2 (m R^2 / I_O) sin^2 alpha (Eq. 1, :func:`rocklab.physics.restitution.two_sided`),
on the hinge being left.  The table acceleration along +x is the model's
``ag`` (positive towards +theta).

The causes of the diagnosis catalogue (:data:`CAUSES`) change the block
by their own laws (:mod:`rocklab.physics.law`, :func:`block_laws`), as they
change a wall (their parameters are the catalogue's
:class:`~rocklab.diagnosis.parameters.Param`):

- ``instability_angle``: both hinges at r times their footprint angle (the
  rounded base rocks on a smaller contact than the 3 mm footprint);
- ``hinge_asymmetry``: alpha_+- further times exp(+-s_alpha/2) (its s_e at
  its null);
- ``restitution_scale``: e = c e_an on both edges.

Limitation: :class:`RockingModel` has one frequency parameter; the block
takes the geometric mean of the two edges' p (they differ by 3 %).
"""

from __future__ import annotations

import logging
import math
import time

import numpy as np
import xarray as xr

from rocklab.diagnosis import catalogue
from rocklab.diagnosis.causes import hinge_asymmetry, instability_angle, restitution_scale
from rocklab.physics import impact, restitution
from rocklab.physics.law import Hinge, Restitution
from rocklab.simulation.batch import ground_batch
from rocklab.simulation.model import RockingModel

log = logging.getLogger(__name__)

#: The causes' parameters, bounds widened to what the rounded bases need (the
#: catalogue's bounds are those of the lab walls).
R = instability_angle.R._replace(lower=0.04, upper=1.0)
S_ALPHA = hinge_asymmetry.S_ALPHA._replace(lower=-1.5, upper=1.5)
C = restitution_scale.C._replace(lower=0.8, upper=1.05)
PARAMS = (R, S_ALPHA, C)

#: The causes of the block, in the catalogue's order (the order their laws act in).
CAUSES = tuple(
    c for c in catalogue.CAUSES if c in (instability_angle.CAUSE, hinge_asymmetry.CAUSE, restitution_scale.CAUSE)
)

#: Grid of each parameter: every test is simulated once at every node, and
#: every fit (folds, resamples) reads the outcomes from it.  Each grid holds
#: the null value (the nominal block).
GRID = {
    R.name: np.geomspace(R.lower, R.upper, 20),
    S_ALPHA.name: np.linspace(S_ALPHA.lower, S_ALPHA.upper, 7),
    C.name: np.array([0.8, 0.9, 1.0, 1.05]),
}

#: Longest free motion [s] followed after a record (rocklab.simulation.batch).
TAIL = 20.0

#: RK4 steps per 200 Hz sample (p dt = 0.02: the exact form is resolved).
SUBSTEPS = 1


def specimen_block(geometry: dict, specimen: str) -> dict:
    """The planar block of one specimen from geometry.json.

    Returns
    -------
    dict
        ``alpha_plus``, ``alpha_minus`` [rad] (rocking angles of the +x and
        -x footprint edges), ``p_plus``, ``p_minus`` [rad/s], ``p`` (their
        geometric mean), ``e_plus``, ``e_minus`` (Housner's e of each edge
        with its m R^2 / I_O), ``mass_kg``.
    """
    g = geometry[specimen]
    mass = float(g["mass_kg"])
    edges = g["footprint"]["rocking_2d"]
    out = {"mass_kg": mass}
    for key, name in (("plus", "plus_x_edge"), ("minus", "minus_x_edge")):
        e = edges[name]
        alpha = float(e["alpha_rad"])
        out[f"alpha_{key}"] = alpha
        out[f"p_{key}"] = float(e["p_rad_per_s"])
        out[f"e_{key}"] = float(restitution.two_sided(alpha, mass * float(e["R_m"]) ** 2 / float(e["I_o_kgm2"])))
    out["p"] = math.sqrt(out["p_plus"] * out["p_minus"])
    return out


def block_laws(r=1.0, s_alpha=0.0, c=1.0):
    """The laws of :data:`CAUSES` at the parameters of :data:`PARAMS`, in the order they act."""
    values = {R.name: r, S_ALPHA.name: s_alpha, C.name: c}
    return [law for cause in CAUSES for law in cause.laws(cause.values(values))]


def _under(block, laws):
    """alpha_+, alpha_- [rad] of the block under ``laws`` and the factors of e on leaving each edge."""
    a_pos, a_neg, c_pos, c_neg = block["alpha_plus"], block["alpha_minus"], 1.0, 1.0
    for law in laws:
        if isinstance(law, Hinge):
            a_pos, a_neg = law.angles(a_pos, a_neg)
        elif isinstance(law, Restitution):
            pos, neg = law.factors()
            c_pos, c_neg = pos * c_pos, neg * c_neg
        else:
            raise NotImplementedError(f"the shake-table block has no {type(law).__name__}")
    return a_pos, a_neg, c_pos, c_neg


def hinge_angles(block, r=1.0, s_alpha=0.0):
    """alpha_+, alpha_- [rad] under the instability angle r and the hinge asymmetry s_alpha."""
    return _under(block, block_laws(r, s_alpha))[:2]


def block_model(block: dict, alpha_r_over_alpha=1.0, s_alpha=0.0, c=1.0) -> RockingModel:
    """The specimen's :class:`RockingModel` with the causes' parameters (null: the nominal block)."""
    a_pos, a_neg, c_pos, c_neg = (float(x) for x in _under(block, block_laws(alpha_r_over_alpha, s_alpha, c)))
    housner = impact.Sided(impact.Constant(block["e_plus"]), impact.Constant(block["e_minus"]))
    law = impact.calibrated(housner, c_pos, c_neg)
    # alpha sets the rest threshold (REST_TOL thetadot_r): that of the weaker hinge.
    return RockingModel(alpha=min(a_pos, a_neg), p=block["p"], alpha_rock=a_pos, alpha_neg=a_neg, impact=law)


def grid_models(block: dict, grid=None) -> list[RockingModel]:
    """The block at every node of ``grid`` (default :data:`GRID`), r fastest-last (C order)."""
    grid = GRID if grid is None else grid
    return [block_model(block, r, s, c) for r in grid[R.name] for s in grid[S_ALPHA.name] for c in grid[C.name]]


def outcome_grid(inputs, dts, block: dict, tests, grid=None, specimen="") -> xr.Dataset:
    """Whether the block overturns under each record at every node of the parameter grid.

    One batch per record: its histories are the grid's models, run in
    parallel by :func:`rocklab.simulation.batch.ground_batch`.

    Parameters
    ----------
    inputs : sequence of ndarray
        Table accelerations [m/s^2] along +x, one per test
        (:func:`rocklab.shake_table.records.block_input`).
    dts : sequence of float
        Their sample intervals [s].
    block : dict
        :func:`specimen_block`.
    tests : sequence of int
        Test numbers (the ``test`` coordinate).

    Returns
    -------
    xarray.Dataset
        ``overturned`` (bool) on (test, alpha_r_over_alpha, s_alpha, c), the
        block in the attributes, ``compute_s``.
    """
    grid = GRID if grid is None else grid
    models = grid_models(block, grid)
    shape = tuple(len(grid[q.name]) for q in PARAMS)
    over = np.zeros((len(inputs), *shape), bool)
    t0 = time.perf_counter()
    for i, (ag, dt) in enumerate(zip(inputs, dts)):
        ds = ground_batch(ag, dt, models, tail=TAIL, substeps=SUBSTEPS)
        over[i] = ds.overturned.values.reshape(shape)
        if (i + 1) % 50 == 0 or i + 1 == len(inputs):
            log.info("%s: %d of %d records simulated, %.1f s", specimen, i + 1, len(inputs), time.perf_counter() - t0)
    coords = {"test": ("test", np.asarray(tests, int))}
    coords.update({q.name: (q.name, np.asarray(grid[q.name], float)) for q in PARAMS})
    return xr.Dataset(
        {"overturned": (("test", *(q.name for q in PARAMS)), over)},
        coords=coords,
        attrs={
            "specimen": specimen,
            **{k: v for k, v in block.items()},
            "n_histories": int(over.size),
            "compute_s": time.perf_counter() - t0,
        },
    )


def nominal(outcomes: xr.Dataset) -> np.ndarray:
    """The nominal block's outcome per test (every cause at its null)."""
    return outcomes.overturned.sel({q.name: q.null for q in PARAMS}, method="nearest").values.astype(bool)
