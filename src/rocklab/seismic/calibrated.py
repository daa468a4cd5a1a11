"""The calibrated wall: the maps' wall with what the diagnosis of a campaign found.

The paper's maps (Sect. 5) change only the coefficient of restitution of
Housner's wall.  The diagnosis of a free-rocking campaign
(:mod:`rocklab.diagnosis`, ``results/diagnosis.json``) names, per boundary
condition, every cause that sets the walls apart from that model: the
instability angle (alpha_r/alpha), the impact law (e/e_an, its amplitude
dependence a - b (thetadot^-/thetadot_r)^2, Eq. 17 form), the landing speed
below which the walls stop dead (:class:`rocklab.physics.impact.Sticking`),
the contact gap of one-sided walls (Fig. 12), hinge asymmetry, flight damping.

Each boundary's entry of the diagnosis (scope ``"boundary"``) pools its
series: a cause named in at least half of them, with the random-effects
mean of its parameters over all of them
(:func:`rocklab.diagnosis.pooling.diagnose_boundary`).  Every parameter is
dimensionless (ratios to alpha, to e_an, to thetadot_r of Eq. 16), and the
calibrated walls carry them as found: the transfer to the maps' wall
(alpha, R of the configuration), about five times thicker than the lab's
walls (113-123 mm), assumes dimensionless similarity.  That is an
assumption, bounded here by its alternative (issue 24, item 8): if hinge
rounding, the contact gap and sticking are absolute sizes of the contact,
their ratios shrink with the thickness (:data:`ABSOLUTE_SIZE`), and the
``-sizes`` wall carries them so; N_O is reported as the range over the two
(:func:`calibrated_table`).  The calibrated wall is the diagnosis model of that wall
(:func:`rocklab.diagnosis.extended.rocking_model`, :func:`map_wall_model`):
the causes' own laws, no mapping of them here.  What the maps know of a
cause is an attribute of it (:class:`rocklab.diagnosis.causes.Cause`): its
short name in the model names (``short``) and, for a family the maps
cannot carry as found, the member that carries it (``on_the_maps``).

Models
------
``2s-calibrated`` / ``1s-calibrated``
    Every finding of the boundary.
``2s-calibrated-no-<finding>`` ...
    The same with one finding switched off (its cause's short name): the
    change of N_O and of the scatter against the full calibrated wall tells
    which finding matters most.
``2s-calibrated-sizes`` / ``1s-calibrated-sizes``
    Every finding, those of :data:`ABSOLUTE_SIZE` as absolute sizes: the
    other end of the transfer assumption (where the diagnosis gives the
    thickness of its walls and names one of them).
"""

from __future__ import annotations

import logging
import re
from collections.abc import Collection, Iterable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeAlias, cast

import numpy as np
import pandas as pd

from rocklab.physics import wall
from rocklab.physics.boundary import Boundary
from rocklab.seismic.indices import FLIPPED_FRACTION
from rocklab.seismic.reductions import record_reductions

if TYPE_CHECKING:
    from rocklab.diagnosis.evidence import MeasuredTest
    from rocklab.diagnosis.result import CampaignDiagnosis
    from rocklab.simulation.rocking_model import RockingModel

#: A diagnosis as the callers hold it: the object, its entries or the path of its JSON file.
DiagnosisLike: TypeAlias = "CampaignDiagnosis | str | Path | Iterable[Any]"
#: The pooled findings of a boundary: cause name -> {parameter: value}.
Findings: TypeAlias = dict[str, dict[str, float]]

log = logging.getLogger(__name__)

#: Prefix of the model names of a boundary condition (as the paper's models).
PREFIX = {b: b.short for b in Boundary}
#: Suffix of the calibrated wall with the findings of :data:`ABSOLUTE_SIZE` as absolute sizes.
SIZES = "sizes"

#: The findings that may be absolute sizes of the contact rather than ratios, and their parameters on a
#: wall ``s`` times as thick as the lab's (s = b_maps / b_lab), the sizes themselves unchanged:
#: hinge rounding shifts the pivot inwards by a length l, alpha_r / alpha = 1 - 2 l / b; a contact gap of
#: width d at the top is a rotation d / h, gap / alpha = d / b; a wall that sticks below a rebound of
#: amplitude d at the top lands at (v / thetadot_r)^2 = 2 theta_apex / alpha = 2 d / b (Eq. 16, small alpha).
ABSOLUTE_SIZE = {
    "instability_angle": lambda v, s: {"alpha_r_over_alpha": 1.0 - (1.0 - v["alpha_r_over_alpha"]) / s},
    "contact_gap": lambda v, s: {"gap_over_alpha": v["gap_over_alpha"] / s},
    "stop_threshold": lambda v, s: {"v_stop_over_vr": v["v_stop_over_vr"] / np.sqrt(s)},
}


def short_name(cause: str) -> str | None:
    """The short name of a finding in the model names (a drift along a column of the test log
    is a drift): the cause's attribute ``short``."""
    from rocklab.diagnosis.catalogue import by_name

    return by_name(cause).short


def name_pattern() -> str:
    """Model names of the calibrated walls: ``{2s,1s}-calibrated[-no-<short>|-sizes]``, a regular expression."""
    # the catalogue is read at call time: the Snakefile and the map jobs import this module for
    # its names, and the diagnosis package costs 0.7 s to import
    from rocklab.diagnosis.catalogue import short_names

    return r"[12]s-calibrated(?:-no-(?:" + "|".join(short_names()) + f")|-{SIZES})?"


@dataclass(frozen=True)
class MapWall:
    """The maps' wall as the diagnosis model reads a test: alpha [rad], p [rad/s], boundary."""

    alpha: float
    p: float
    boundary: str
    #: place in a series (0 first, 1 last) of a parameter that drifts over the
    #: tests: the maps' wall stands for the middle of the series
    order: float = 0.5


def boundary_findings(diagnosis: DiagnosisLike, boundary: str) -> Findings:
    """The pooled findings of one boundary condition, in the diagnosis' order.

    Parameters
    ----------
    diagnosis : rocklab.diagnosis.result.CampaignDiagnosis, its entries or path
        ``results/diagnosis.json``; without an entry for ``boundary``, its
        series are pooled here (:func:`rocklab.diagnosis.pooling.diagnose_boundary`).
    boundary : {"two-sided", "one-sided"}

    Returns
    -------
    dict
        cause name -> {parameter: value}; empty when the boundary has no
        series or none names a cause.  A finding the maps cannot carry as
        found (its cause's ``on_the_maps``) is carried by the member of its
        family the maps' wall can hold, or left off, with a warning in the log.
    """
    from rocklab.diagnosis.catalogue import by_name
    from rocklab.diagnosis.result import CampaignDiagnosis

    diagnosis = CampaignDiagnosis.of(diagnosis)
    entry = diagnosis.boundary(boundary)
    if entry is None:
        from rocklab.diagnosis.pooling import diagnose_boundary

        entry = diagnose_boundary(diagnosis, boundary)
    if entry is None:
        return {}
    # a finding also reports statistics of its parameters (spread_log): only the cause's own parameters
    out = {}
    for f in entry.named:
        cause = f.effect
        if by_name(cause).on_the_maps is not None:
            # not None: just asked
            member, why = cast(tuple[str | None, str], by_name(cause).on_the_maps)
            found = ", ".join(f"{k} = {float(v):.3g}" for k, v in f.params.items())
            # a member at its null carries nothing: a model switching it off would be the same wall
            if member is None or all(float(f.params[q.name]) == q.null for q in by_name(member).params):
                why = why if member is None else f"its member {member} is at its null; {why}"
                log.warning("%s walls: %s is left off the maps' wall: %s (found: %s)", boundary, cause, why, found)
                continue
            log.warning(
                "%s walls: %s is carried on the maps' wall by %s, %s (found: %s)", boundary, cause, member, why, found
            )
            cause = member
        out[cause] = {q.name: float(f.params[q.name]) for q in by_name(cause).params}
    return out


def lab_thickness(diagnosis: DiagnosisLike, boundary: str) -> float | None:
    """The mean thickness [m] of the lab's walls of a boundary condition (its entry's
    ``wall_thickness_m``), None where the diagnosis does not give it."""
    from rocklab.diagnosis.result import CampaignDiagnosis

    entry = CampaignDiagnosis.of(diagnosis).boundary(boundary)
    return None if entry is None else entry.wall_thickness_m


def has_sizes(diagnosis: DiagnosisLike, boundary: str, found: Findings | None = None) -> bool:
    """Whether a boundary has a ``-sizes`` wall: the thickness of its walls is known and it names a
    finding of :data:`ABSOLUTE_SIZE`."""
    found = boundary_findings(diagnosis, boundary) if found is None else found
    return lab_thickness(diagnosis, boundary) is not None and any(c in ABSOLUTE_SIZE for c in found)


def model_names(diagnosis: DiagnosisLike) -> list[str]:
    """Names of the calibrated models a diagnosis gives: per boundary with findings, the full
    calibrated wall, one variant per finding switched off, and the wall with absolute sizes
    (:func:`has_sizes`)."""
    names = []
    for boundary, prefix in PREFIX.items():
        found = boundary_findings(diagnosis, boundary)
        if found:
            names.append(f"{prefix}-calibrated")
            names += [f"{prefix}-calibrated-no-{short_name(c)}" for c in found]
            names += [f"{prefix}-calibrated-{SIZES}"] if has_sizes(diagnosis, boundary, found) else []
    return names


def parse_name(name: str) -> tuple[Boundary, str | None, bool]:
    """(boundary, cause switched off or None, absolute sizes) of a calibrated model name.

    Raises
    ------
    KeyError
        For a name that is no calibrated model.
    """
    from rocklab.diagnosis.catalogue import by_short, short_names

    m = re.fullmatch(r"([12]s)-calibrated(?:-no-(\w+)|-(sizes))?", name)
    if m is None or (m.group(2) is not None and m.group(2) not in short_names()):
        raise KeyError(
            f"{name!r} is no calibrated model (<2s|1s>-calibrated[-no-<{'|'.join(short_names())}>|-{SIZES}])"
        )
    boundary = {v: k for k, v in PREFIX.items()}[m.group(1)]
    return boundary, (by_short(m.group(2)).name if m.group(2) else None), m.group(3) is not None


def _switched_off(found: Findings, off: str | None, name: str, boundary: str) -> str | None:
    """The finding of ``found`` that model ``name`` switches off (``off`` from :func:`parse_name`;
    a drift along any column of the test log is a drift), None for the full wall."""
    if off is None:
        return None
    match = [c for c in found if short_name(c) == short_name(off)]
    if not match:
        raise KeyError(f"{name}: the diagnosis does not name {off} for {boundary} walls ({', '.join(found)})")
    return match[0]


def is_calibrated(name: object) -> bool:
    """Whether ``name`` is a calibrated model name (:func:`name_pattern`)."""
    return re.fullmatch(name_pattern(), str(name)) is not None


def calibrated_model(diagnosis: DiagnosisLike, name: str, alpha: float, R: float, form: str = "linear") -> RockingModel:
    """The wall of a calibrated model on the maps' wall.

    Parameters
    ----------
    diagnosis : rocklab.diagnosis.result.CampaignDiagnosis, its entries or path
        ``results/diagnosis.json``.
    name : str
        ``2s-calibrated``, ``1s-calibrated-no-stop``, ... (:func:`model_names`).
    alpha : float
        Nominal slenderness of the maps' wall [rad].
    R : float
        Half diagonal [m] (p = sqrt(3 g / 4 R), homogeneous wall).
    form : {"linear", "exact"}

    Returns
    -------
    rocklab.simulation.rocking_model.RockingModel

    Raises
    ------
    KeyError
        A name that is no calibrated model, or whose finding the diagnosis
        does not name.
    ValueError
        A diagnosis whose boundary names no cause the maps' wall carries
        (:func:`boundary_findings`).
    """
    boundary, off, sizes = parse_name(name)
    found = boundary_findings(diagnosis, boundary)
    if not found:
        raise ValueError(f"{name}: the diagnosis names no cause for {boundary} walls, nothing to calibrate")
    off = _switched_off(found, off, name, boundary)
    if sizes:
        found = at_absolute_size(diagnosis, boundary, found, alpha, R)
    ext = [c for c in found if c != off]
    values = {k: v for c in ext for k, v in found[c].items()}
    return map_wall_model(boundary, alpha, R, ext, values, form=form)


def at_absolute_size(diagnosis: DiagnosisLike, boundary: str, found: Findings, alpha: float, R: float) -> Findings:
    """The findings ``found`` on the maps' wall (alpha [rad], R [m]) with those of :data:`ABSOLUTE_SIZE`
    as absolute sizes of the contact, measured on the lab's walls (:func:`lab_thickness`).

    Raises
    ------
    KeyError
        Where the boundary has no such wall (:func:`has_sizes`).
    """
    if not has_sizes(diagnosis, boundary, found):
        raise KeyError(f"{boundary}: the diagnosis gives no wall thickness or names no size ({', '.join(found)})")
    # a thickness: has_sizes asked for one
    s = float(wall.thickness(R, alpha)) / cast(float, lab_thickness(diagnosis, boundary))
    return {c: ABSOLUTE_SIZE[c](v, s) if c in ABSOLUTE_SIZE else v for c, v in found.items()}


def map_wall_model(
    boundary: str,
    alpha: float,
    R: float,
    ext: Collection[str] = (),
    values: Mapping[str, float] | None = None,
    base: str = "analytic",
    form: str = "linear",
) -> RockingModel:
    """The maps' wall (:class:`MapWall`) with the causes ``ext`` of the catalogue at ``values``.

    Parameters
    ----------
    boundary : {"two-sided", "one-sided"}
    alpha : float
        Nominal slenderness [rad].
    R : float
        Half diagonal [m] (p = sqrt(3 g / 4 R), homogeneous wall).
    ext, values
        Names of causes and their parameters (:func:`rocklab.diagnosis.extended.rocking_model`).
    base : {"analytic", "zero", "two-sided-e"}
        The literature base e (:meth:`rocklab.diagnosis.wall_model.ModelParams.with_base`).
    form : {"linear", "exact"}

    Returns
    -------
    rocklab.simulation.rocking_model.RockingModel
    """
    from rocklab.diagnosis.extended import rocking_model

    # the diagnosis model reads of a measured test only what MapWall holds
    model = rocking_model(
        cast("MeasuredTest", MapWall(float(alpha), float(wall.frequency_parameter(R)), boundary)), ext, values, base
    )
    return replace(model, form=form)


def describe(diagnosis: DiagnosisLike, name: str) -> str:
    """One line on what a calibrated model holds, with the pooled parameters."""
    boundary, off, sizes = parse_name(name)
    found = boundary_findings(diagnosis, boundary)
    off = _switched_off(found, off, name, boundary)
    parts = [f"{c} (" + ", ".join(f"{k} = {v:.3g}" for k, v in p.items()) + ")" for c, p in found.items() if c != off]
    text = f"{boundary}, calibrated on the campaign's diagnosis: " + ("; ".join(parts) or "no finding")
    if sizes:
        text += f"; {', '.join(c for c in found if c in ABSOLUTE_SIZE)} as absolute sizes of the lab's walls"
    return text + (f"; {off} switched off" if off else "")


#: The paper's "e alone" calibration of each boundary (Sect. 3, Table 3): the
#: baseline the calibrated walls are compared with.
E_ALONE = {Boundary.TWO_SIDED: "2s-0.95", Boundary.ONE_SIDED: "1s-1.05"}

#: Columns of ``results/maps/calibrated.csv`` (schema map_calibrated.schema.yaml).
TABLE_COLUMNS = [
    "boundary",
    "model",
    "role",
    "finding_off",
    "baseline",
    "n_records",
    "N_O_mean",
    "scatter_mean",
    "N_O_change_pct",
    "scatter_change_pct",
    "N_O_shift",
    "N_O_shift_abs",
    "rank",
    "N_O_low",
    "N_O_high",
]


#: Two findings whose mean shifts of N_O differ by less than this share a rank: each shift
#: may move by twice the flipped fraction between machines (the flips of the two maps it
#: compares), so their difference by four times it, and which of the two comes first is
#: not something the maps can tell. A gap just wider than the margin may still close on
#: another machine; the embedded campaign's narrowest one is 0.025, three times it.
RANK_MARGIN = 4 * FLIPPED_FRACTION


def calibrated_table(summary: pd.DataFrame, diagnosis: DiagnosisLike) -> pd.DataFrame:
    """What the lab's findings do to the maps, per boundary condition.

    Rows: the paper's e-alone model of the boundary (:data:`E_ALONE`), the
    calibrated wall, the calibrated wall with the findings of
    :data:`ABSOLUTE_SIZE` as absolute sizes (role "absolute sizes", where the
    diagnosis has it), and the calibrated wall with each finding switched off.
    Changes are per record, then averaged over the records where they are
    defined: ``N_O_change_pct`` and ``scatter_change_pct`` are
    100 (x_model / x_e-alone - 1) (minus the reductions of
    :func:`rocklab.seismic.reductions.record_reductions`: positive = more);
    ``N_O_shift`` is the mean of N_O(model) - N_O(calibrated) [fraction of
    the map] and ``N_O_shift_abs`` the mean of its absolute value; ``rank``
    orders the findings by ``N_O_shift_abs`` (1: the finding that matters
    most, switched off it moves N_O the most), findings whose shifts lie
    within :data:`RANK_MARGIN` of each other sharing a rank (one plus the
    number of findings that move N_O more by more than the margin).  ``N_O_low`` and ``N_O_high``,
    on the calibrated rows, bound ``N_O_mean`` over the two transfer
    assumptions (ratios, absolute sizes): the calibrated N_O is a range.

    Parameters
    ----------
    summary : pandas.DataFrame
        :func:`rocklab.seismic.indices.summary_table` of the maps of the
        e-alone and calibrated models (other models are ignored).
    diagnosis : rocklab.diagnosis.result.CampaignDiagnosis, its entries or path
        ``results/diagnosis.json``, which names the models.

    Returns
    -------
    pandas.DataFrame
        :data:`TABLE_COLUMNS`; empty (with the columns) when the diagnosis
        names no cause.

    Raises
    ------
    KeyError
        A model the diagnosis names that ``summary`` lacks.
    """
    rows = []
    # no calibrated model, no map: an empty summary has no columns
    present = set(summary["model"]) if "model" in summary else set()
    for boundary, prefix in PREFIX.items():
        found = boundary_findings(diagnosis, boundary)
        if not found:
            continue
        full, base = f"{prefix}-calibrated", E_ALONE[boundary]
        sizes = [f"{full}-{SIZES}"] if has_sizes(diagnosis, boundary, found) else []
        models = [base, full, *sizes] + [f"{full}-no-{short_name(c)}" for c in found]
        roles = ["e alone", "calibrated", *["absolute sizes"] * len(sizes)] + ["finding off"] * len(found)
        missing = [m for m in models if m not in present]
        if missing:
            raise KeyError(f"the maps summary lacks the models {', '.join(missing)}")
        wide = summary.set_index(["record", "model"])[["N_O", "scatter"]].unstack("model")
        block: list[dict[str, Any]] = []
        for model, off, role in zip(models, [None] * (2 + len(sizes)) + list(found), roles):
            change = -record_reductions(summary, base, model)
            shift = wide[("N_O", model)] - wide[("N_O", full)]
            block.append(
                {
                    "boundary": boundary,
                    "model": model,
                    "role": role,
                    "finding_off": off or "",
                    "baseline": base,
                    "n_records": int(wide[("N_O", model)].notna().sum()),
                    "N_O_mean": wide[("N_O", model)].mean(),
                    "scatter_mean": wide[("scatter", model)].mean(),
                    "N_O_change_pct": change["N_O"].mean(),
                    "scatter_change_pct": change["scatter"].mean(),
                    "N_O_shift": shift.mean(),
                    "N_O_shift_abs": shift.abs().mean(),
                    "rank": np.nan,
                }
            )
        offs = sorted((r for r in block if r["role"] == "finding off"), key=lambda r: -r["N_O_shift_abs"])
        for r in offs:
            r["rank"] = 1 + sum(o["N_O_shift_abs"] > r["N_O_shift_abs"] + RANK_MARGIN for o in offs)
        calibrated = [r for r in block if r["role"] in ("calibrated", "absolute sizes")]
        for r in calibrated:
            r["N_O_low"] = min(c["N_O_mean"] for c in calibrated)
            r["N_O_high"] = max(c["N_O_mean"] for c in calibrated)
        rows += block
    table = pd.DataFrame(rows, columns=TABLE_COLUMNS)
    return table.astype({"rank": "Int64"})
