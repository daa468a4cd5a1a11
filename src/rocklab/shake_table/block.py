"""The planar rocking block of each specimen on its contact, and its outcome under the table records.

The contact is one thing
------------------------
The bases of both replicas are gently convex (geometry.json, caveats: a
best-fit plane leaves 3.6 mm rms; within 1 mm of its lowest point the SP1
scan spans only -47 to +27 mm about the centre of mass), so a specimen does
not rock on the rim of its 3 mm footprint but on a contact near its lowest
point.  The block here rocks on two contact edges at horizontal distances
b_+ and b_- [m] from the centre of mass (towards +x and -x), inset from the
footprint's edges, with the body's own mass m, centre-of-mass height h and
moment of inertia I_G = m k_G^2 (the mesh's, geometry.json).  Everything of
the block follows that one contact:

- rocking angles alpha_+- = atan(b_+- / h), so the uplift threshold is
  g tan alpha_+- (the exact form of
  :class:`rocklab.simulation.rocking_model.RockingModel`, theta > 0 on the +x edge);
- frequency parameters p_+- = sqrt(m g R_+- / I_O,+-), I_O,+- = I_G + m R_+-^2
  (their geometric mean: the model has one p; they differ by under 3 %);
- the coefficient of restitution of leaving edge +- for edge -+, from
  angular momentum about the edge landed on
  (:func:`rocklab.physics.restitution.two_sided_asymmetric`,
  e = 1 - m b_2 (b_1 + b_2) / I_O,new; Eq. 1 for a symmetric contact).

Any loss beyond the rigid impact of that contact is a separate factor c on
both e (the catalogue's ``restitution_scale`` law, :mod:`rocklab.physics.law`),
bounded to [:data:`C` lower, 1]: an impact never gains energy over the rigid
one.  A small contact's own e is close to 1 (0.98-0.996 for 16-40 mm), so a
large fitted loss shows as c well below 1, not as a contact angle traded
against a footprint's e.

This is the model of inset rocking points of precariously balanced rocks
(Purvance, Anooshehpoor & Brune 2008, Earthquake Engng Struct. Dyn. 37,
791-808: a PBR rocks about its basal contact points, its fragility set by
their alpha and p), with Housner's (1963) plastic impact at the new edge
(the standard rocking model of Lipscombe & Pellegrino 1993, J. Eng. Mech.
119, 1387-1410) written for a body whose edges are not symmetric about its
centre of mass; pivots inset from the corners by a rounded base are those
of Ther & Kollar (2017, Bull. Earthquake Eng. 15, 2305-2319).

Limitation: a flat contact ties the uplift threshold to the
overturning capacity (both set by alpha); a base of finite curvature, whose
contact rolls outwards as the block tilts, unties them, but needs an
equation of motion with a moving contact that the batch engine does not
have.  The scatter of the contact from test to test
(:mod:`rocklab.shake_table.calibration`) stands in for it.

Parameters are in physical units (:data:`PARAMS`: mm of contact, c), so one
set applies to both replicas (:func:`node_on`).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr

from rocklab.diagnosis.causes import restitution_scale
from rocklab.diagnosis.parameters import Param
from rocklab.physics import impact, restitution
from rocklab.physics.constants import G
from rocklab.physics.law import Restitution
from rocklab.simulation.batch import ground_batch
from rocklab.simulation.rocking_model import RockingModel

log = logging.getLogger(__name__)

#: Contact half-widths [mm] from the centre of mass towards +x and -x.  Their
#: null is the footprint's edge (the nominal block, specimen by specimen), so
#: the Param's null and upper bound are placeholders that :func:`grid` replaces.
CONTACT_PLUS = Param("contact_plus_mm", 5.0, np.inf, np.nan)
CONTACT_MINUS = Param("contact_minus_mm", 5.0, np.inf, np.nan)
#: The factor on both e beyond the rigid impact of the contact (``restitution_scale``), at most 1.
C = restitution_scale.C._replace(lower=0.8, upper=1.0)
PARAMS = (CONTACT_PLUS, CONTACT_MINUS, C)

#: Nodes [mm] of the contact half-widths, fixed before any fit: from 5 mm (a
#: rocking angle of 1 deg at h = 0.29 m) in steps of 2^(1/3), each specimen's
#: up to its footprint's edge, which closes the axis (:func:`grid`).
CONTACT_NODES_MM = 5.0 * 2.0 ** (np.arange(18) / 3.0)
#: Nodes of the extra-loss factor c.
C_NODES = np.array([0.8, 0.9, 1.0])

#: Longest free motion [s] followed after a record (rocklab.simulation.batch).
TAIL = 20.0

#: RK4 steps per 200 Hz sample (p dt = 0.02: the exact form is resolved).
SUBSTEPS = 1


def specimen_block(geometry: Mapping[str, Any], specimen: str) -> dict[str, float]:
    """The body of one specimen from geometry.json: what the contact does not change.

    Returns
    -------
    dict
        ``mass_kg``; ``h_m`` (centre-of-mass height above the lowest point);
        ``k_g_m`` (radius of gyration about the centre of mass in the rocking
        plane, from the +x edge's I_O - m R^2); ``footprint_plus_mm``,
        ``footprint_minus_mm`` (the 3 mm footprint's edges from the centre of
        mass).
    """
    g = geometry[specimen]
    mass = float(g["mass_kg"])
    edges = g["footprint"]["rocking_2d"]
    plus, minus = edges["plus_x_edge"], edges["minus_x_edge"]
    h = float(plus["h_m"])
    k2 = float(plus["I_o_kgm2"]) / mass - float(plus["R_m"]) ** 2
    return {
        "mass_kg": mass,
        "h_m": h,
        "k_g_m": math.sqrt(k2),
        "footprint_plus_mm": 1e3 * float(plus["b_m"]),
        "footprint_minus_mm": 1e3 * float(minus["b_m"]),
    }


def contact(block: Mapping[str, float], contact_plus_mm: float, contact_minus_mm: float) -> dict[str, float]:
    """The rocking block of a body on contact edges ``contact_plus_mm``, ``contact_minus_mm`` [mm] from its COM.

    Returns
    -------
    dict
        ``alpha_plus``, ``alpha_minus`` [rad]; ``p_plus``, ``p_minus`` and
        their geometric mean ``p`` [rad/s]; ``e_plus``, ``e_minus`` [-], e of
        the impact on leaving the +x (-x) edge for the other
        (:func:`rocklab.physics.restitution.two_sided_asymmetric`); ``energy_kept`` [-],
        the share of kinetic energy either impact keeps
        (:func:`rocklab.physics.restitution.energy_ratio_asymmetric`, the same both ways).
    """
    h, k = block["h_m"], block["k_g_m"]
    b = {"plus": 1e-3 * float(contact_plus_mm), "minus": 1e-3 * float(contact_minus_mm)}
    out: dict[str, float] = {}
    for side, other in (("plus", "minus"), ("minus", "plus")):
        r2 = b[side] ** 2 + h**2
        out[f"alpha_{side}"] = math.atan2(b[side], h)
        out[f"p_{side}"] = math.sqrt(G * math.sqrt(r2) / (k**2 + r2))
        out[f"e_{side}"] = restitution.two_sided_asymmetric(b[side], b[other], h, k)
    out["p"] = math.sqrt(out["p_plus"] * out["p_minus"])
    out["energy_kept"] = restitution.energy_ratio_asymmetric(b["plus"], b["minus"], h, k)
    return out


def footprint(block: Mapping[str, float]) -> dict[str, float]:
    """:func:`contact` on the footprint's edges: the nominal block."""
    return contact(block, block["footprint_plus_mm"], block["footprint_minus_mm"])


def grid(block: Mapping[str, float]) -> dict[str, np.ndarray]:
    """The parameter grid of a specimen: :data:`CONTACT_NODES_MM` inside its footprint, then its edge; :data:`C_NODES`.

    Every test is simulated once at every node, and every fit (folds,
    resamples) reads the outcomes from it; the last contact nodes with
    c = 1 are the nominal block.
    """
    out: dict[str, np.ndarray] = {}
    for q, edge in ((CONTACT_PLUS, block["footprint_plus_mm"]), (CONTACT_MINUS, block["footprint_minus_mm"])):
        inside = CONTACT_NODES_MM[CONTACT_NODES_MM < edge / 2 ** (1 / 6)]
        out[q.name] = np.append(inside, edge)
    out[C.name] = C_NODES
    return out


def node_on(values: Mapping[str, float], grid_: Mapping[str, np.ndarray]) -> dict[str, float]:
    """``values`` at the nearest node of ``grid_`` (in ln for the contacts): one parameter set on another specimen."""
    out: dict[str, float] = {}
    for q in PARAMS:
        nodes = np.asarray(grid_[q.name], float)
        dist = np.abs(np.log(nodes / values[q.name])) if q is not C else np.abs(nodes - values[q.name])
        out[q.name] = float(nodes[int(np.argmin(dist))])
    return out


def block_model(
    block: Mapping[str, float],
    contact_plus_mm: float | None = None,
    contact_minus_mm: float | None = None,
    c: float = 1.0,
) -> RockingModel:
    """The specimen's :class:`RockingModel` on a contact (None: the footprint's edge) with the extra loss c."""
    cp = block["footprint_plus_mm"] if contact_plus_mm is None else contact_plus_mm
    cm = block["footprint_minus_mm"] if contact_minus_mm is None else contact_minus_mm
    k = contact(block, cp, cm)
    (scale,) = restitution_scale.laws({C.name: c})
    if not isinstance(scale, Restitution):
        raise TypeError(f"restitution_scale's law is {type(scale).__name__}, the block needs a Restitution")
    rigid = impact.AsymmetricBody(1e-3 * cp, 1e-3 * cm, block["h_m"], block["k_g_m"])
    law = impact.calibrated(rigid, *scale.factors())
    # alpha sets the rest threshold (REST_TOL thetadot_r): that of the weaker edge.
    return RockingModel(
        alpha=min(k["alpha_plus"], k["alpha_minus"]),
        p=k["p"],
        alpha_rock=k["alpha_plus"],
        alpha_neg=k["alpha_minus"],
        impact=law,
    )


def grid_models(block: Mapping[str, float], grid_: Mapping[str, np.ndarray]) -> list[RockingModel]:
    """The block at every node of ``grid_``, in C order of :data:`PARAMS`."""
    names = [q.name for q in PARAMS]
    return [block_model(block, a, b, c) for a in grid_[names[0]] for b in grid_[names[1]] for c in grid_[names[2]]]


def outcome_grid(
    inputs: Sequence[np.ndarray],
    dts: Sequence[float],
    block: Mapping[str, float],
    tests: Sequence[int],
    grid_: Mapping[str, np.ndarray] | None = None,
    specimen: str = "",
) -> xr.Dataset:
    """Whether the block overturns under each record at every node of the parameter grid.

    One batch per record: its histories are the grid's models, run in
    parallel by :func:`rocklab.simulation.batch.ground_batch`.

    Parameters
    ----------
    inputs : sequence of ndarray
        Table accelerations [m/s^2] along +x, one per test
        (:func:`rocklab.shake_table.asu_data.block_input`).
    dts : sequence of float
        Their sample intervals [s].
    block : dict
        :func:`specimen_block`.
    tests : sequence of int
        Test numbers (the ``test`` coordinate).
    grid_ : dict, optional
        Nodes by parameter name (default :func:`grid` of the block).

    Returns
    -------
    xarray.Dataset
        ``overturned`` (bool) on (test, contact_plus_mm, contact_minus_mm, c),
        the block in the attributes, ``compute_s``.
    """
    grid_ = grid(block) if grid_ is None else grid_
    models = grid_models(block, grid_)
    shape = tuple(len(grid_[q.name]) for q in PARAMS)
    over = np.zeros((len(inputs), *shape), bool)
    t0 = time.perf_counter()
    for i, (ag, dt) in enumerate(zip(inputs, dts)):
        ds = ground_batch(ag, dt, models, tail=TAIL, substeps=SUBSTEPS)
        over[i] = ds.overturned.values.reshape(shape)
        if (i + 1) % 50 == 0 or i + 1 == len(inputs):
            log.info("%s: %d of %d records simulated, %.1f s", specimen, i + 1, len(inputs), time.perf_counter() - t0)
    coords: dict[str, tuple[str, np.ndarray]] = {"test": ("test", np.asarray(tests, int))}
    coords.update({q.name: (q.name, np.asarray(grid_[q.name], float)) for q in PARAMS})
    return xr.Dataset(
        {"overturned": (("test", *(q.name for q in PARAMS)), over)},
        coords=coords,
        attrs={
            "specimen": specimen,
            **block,
            "n_histories": int(over.size),
            "compute_s": time.perf_counter() - t0,
        },
    )


def grid_of(outcomes: xr.Dataset) -> dict[str, np.ndarray]:
    """The parameter grid of an outcome grid, by name."""
    return {q.name: outcomes[q.name].values for q in PARAMS}


def nominal(outcomes: xr.Dataset) -> np.ndarray:
    """The nominal block's outcome per test: the footprint's edges (the last contact nodes), c = 1."""
    at = {CONTACT_PLUS.name: -1, CONTACT_MINUS.name: -1}
    return outcomes.overturned.isel(at).sel({C.name: C.null}).values.astype(bool)
