"""The walls of the overturning maps (Sect. 5, Figs. 21 and 23), by name.

The paper's five walls (:data:`MODELS`) are Housner's wall of one boundary
with the causes of the catalogue that change its e (:func:`causes_of`); the
calibrated walls of a campaign are named by
:func:`rocklab.seismic.calibrated.name_pattern`.  :func:`named_model` builds
either as the simulator's :class:`rocklab.simulation.rocking_model.RockingModel`,
which :func:`rocklab.seismic.maps.overturning_map` sweeps over the scaled
records.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from rocklab.physics.boundary import Boundary
from rocklab.physics.restitution import (
    AMPLITUDE_LAW_ONE_SIDED,
    CALIBRATED_RATIO_ONE_SIDED,
    CALIBRATED_RATIO_TWO_SIDED,
)
from rocklab.seismic import calibrated

if TYPE_CHECKING:
    from rocklab.seismic.calibrated import DiagnosisLike
    from rocklab.simulation.rocking_model import RockingModel

#: Paper's wall of Figs. 21 and 23: slenderness [rad] and half diagonal [m].
ALPHA = 0.1
R = 3.0

#: The five maps of Sect. 5: name -> (boundary, description).
MODELS = {
    "2s-housner": (Boundary.TWO_SIDED, "two-sided, e = e_an,2s (Housner, Eq. 2); Fig. 21a"),
    "2s-0.95": (Boundary.TWO_SIDED, "two-sided, e = 0.95 e_an,2s (experimentally calibrated, Sect. 3); Fig. 21b"),
    "1s-zero": (Boundary.ONE_SIDED, "one-sided, e = 0 (Liberatore & Spera 2003: motion stops at impact); Fig. 23a"),
    "1s-1.05": (Boundary.ONE_SIDED, "one-sided, e = 1.05 e_an,1s (Eq. 14 calibrated, Table 3); Fig. 23b"),
    "1s-eq17": (Boundary.ONE_SIDED, "one-sided, e = e_an,1s (a - b (thetadot^-/thetadot_r)^2) (amplitude law, Eq. 17)"),
}


def causes_of(
    name: str, eq17: tuple[float, float] = AMPLITUDE_LAW_ONE_SIDED
) -> tuple[dict[str, dict[str, float]], str]:
    """What a map model of :data:`MODELS` adds to Housner's wall of its boundary.

    Parameters
    ----------
    name : str
        A key of :data:`MODELS`.
    eq17 : tuple of float
        (a, b) of Eq. 17 for ``"1s-eq17"``.

    Returns
    -------
    causes : dict
        Cause of the catalogue (:mod:`rocklab.diagnosis.catalogue`) -> its values.
    base : {"analytic", "zero"}
        The literature base e (:meth:`rocklab.diagnosis.wall_model.ModelParams.with_base`).
    """
    # imported here: the workflow reads MODELS at every start, without the diagnosis package (0.25 s)
    from rocklab.diagnosis.causes import restitution_amplitude, restitution_scale

    scale, amplitude = restitution_scale.CAUSE.name, restitution_amplitude.CAUSE.name
    return {
        "2s-housner": ({}, "analytic"),
        "2s-0.95": ({scale: {"c": CALIBRATED_RATIO_TWO_SIDED}}, "analytic"),
        "1s-zero": ({}, "zero"),
        "1s-1.05": ({scale: {"c": CALIBRATED_RATIO_ONE_SIDED}}, "analytic"),
        "1s-eq17": ({amplitude: dict(zip("ab", eq17))}, "analytic"),
    }[name]


def named_model(
    name: str,
    alpha: float = ALPHA,
    R: float = R,
    form: str = "linear",
    eq17: tuple[float, float] | None = None,
    diagnosis: DiagnosisLike | None = None,
) -> RockingModel:
    """The wall of a named map model (:data:`MODELS`, or a calibrated wall).

    Parameters
    ----------
    name : str
        A key of :data:`MODELS`, or a calibrated model
        (:func:`rocklab.seismic.calibrated.name_pattern`, with ``diagnosis``).
    alpha : float
        Slenderness angle [rad] (Fig. 21: 0.1).
    R : float
        Half diagonal [m] of the homogeneous wall (Fig. 21: 3), giving
        p = sqrt(3 g / 4 R).
    form : {"linear", "exact"}
        Equation of motion (:mod:`rocklab.seismic.maps`: the maps use "linear").
    eq17 : tuple of float, optional
        (a, b) of Eq. 17 for ``"1s-eq17"``; default the paper's fit
        (:data:`rocklab.physics.restitution.AMPLITUDE_LAW_ONE_SIDED`).
    diagnosis : list of dict or path, optional
        ``results/diagnosis.json`` of a campaign, for the calibrated walls
        (:func:`rocklab.seismic.calibrated.calibrated_model`).

    Returns
    -------
    rocklab.simulation.rocking_model.RockingModel
    """
    if calibrated.is_calibrated(name):
        if diagnosis is None:
            raise ValueError(f"the calibrated model {name!r} needs the diagnosis of a campaign (diagnosis=)")
        return calibrated.calibrated_model(diagnosis, name, alpha, R, form)
    if name not in MODELS:
        raise KeyError(f"unknown map model {name!r}; choose one of {', '.join(MODELS)}")
    causes, base = causes_of(name) if eq17 is None else causes_of(name, eq17)
    values = {k: v for p in causes.values() for k, v in p.items()}
    return calibrated.map_wall_model(MODELS[name][0], alpha, R, tuple(causes), values, base, form)
