"""The catalogue of candidate causes: one module each in :mod:`rocklab.diagnosis.causes`.

:data:`CAUSES` is the ordered list the diagnosis reads: the order in which
the causes' laws act on the model (:func:`laws`) and the causes are
reported when tied.  Adding a cause is one new module (a
:class:`rocklab.diagnosis.causes.Cause` named ``CAUSE``, its physics as
laws of :mod:`rocklab.physics.law`, its metadata as attributes) and one
line here (docs/diagnosis-method.md, "Adding a cause"): the diagnosis, the
exact simulator, the calibrated maps (:mod:`rocklab.seismic.calibrated`)
and the limestone blocks (:mod:`rocklab.diagnosis.block_tests`) read it
from here.
:data:`FAMILIES` are the generalised families (issue 12), each holding a
listed cause as one member, searched only where the listed causes leave
structure.
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING

from rocklab.diagnosis.causes import (
    Cause,
    Law,
    Signature,
    Stage,
    contact_gap,
    flight_damping,
    flight_loss,
    hinge_asymmetry,
    instability_amplitude,
    instability_angle,
    restitution_amplitude,
    restitution_drift,
    restitution_housner_loss,
    restitution_scale,
    restitution_speed,
    stop_threshold,
)
from rocklab.diagnosis.evidence import observe
from rocklab.diagnosis.wall_model import log_columns

if TYPE_CHECKING:
    from rocklab.diagnosis.evidence import MeasuredTest

CAUSES = [
    restitution_scale.CAUSE,
    restitution_amplitude.CAUSE,
    instability_angle.CAUSE,
    flight_damping.CAUSE,
    hinge_asymmetry.CAUSE,
    contact_gap.CAUSE,
    stop_threshold.CAUSE,
]

FAMILIES = [
    restitution_housner_loss.CAUSE,
    restitution_drift.CAUSE,
    instability_amplitude.CAUSE,
    restitution_speed.CAUSE,
    flight_loss.CAUSE,
]


def in_order(columns: Iterable[str] = ()) -> list[Cause]:
    """The causes and the families in the order they act on the model.

    ``columns``: the test log's columns a drift may follow, each a family
    beside the drift along the test order (:func:`restitution_drift.along_log`).
    """
    families = list(FAMILIES)
    i = families.index(restitution_drift.CAUSE) + 1
    families[i:i] = restitution_drift.along_log(tuple(columns))
    # the causes estimated after selection act last, on the chosen model as it is (by their stage, not
    # by equality: a cause's comparison reads all its fields, and a fit names its laws thousands of times)
    later = [c for c in CAUSES if c.stage is not Stage.SELECTION]
    return [*(c for c in CAUSES if c.stage is Stage.SELECTION), *families, *later]


def by_name(name: str) -> Cause:
    """The cause of the catalogue called ``name`` (a drift along a column of the test log too).

    With :func:`log_columns_of`, the one reading of a cause's name: elsewhere a cause is its object.
    """
    column = restitution_drift.column_of(name)
    return next(c for c in in_order(() if column is None else (column,)) if c.name == name)


def log_columns_of(names: Iterable[str]) -> set[str]:
    """The columns of the test log that the causes called ``names`` follow (a drift along one), which a
    model of them needs whether or not its tests have them (:attr:`~rocklab.diagnosis.causes.Cause.log_column`)."""
    return {c for name in names if (c := restitution_drift.column_of(name)) is not None}


def laws(ext: Collection[str], values: Mapping[str, float] | None = None, columns: Iterable[str] = ()) -> list[Law]:
    """The laws of the causes named ``ext`` (:attr:`rocklab.diagnosis.causes.Cause.laws`) with their
    parameter ``values`` (null where missing), in the order they act on a wall (:func:`in_order`,
    with a drift along each of the test log's ``columns``)."""
    return [law for c in in_order(columns) if c.name in ext for law in c.laws(c.values(values or {}))]


def by_short(short: str) -> Cause:
    """The cause of the catalogue whose short name (:attr:`rocklab.diagnosis.causes.Cause.short`) is ``short``."""
    return next(c for c in in_order() if c.short == short)


def short_names() -> list[str]:
    """The short names of the causes the maps can carry, in catalogue order."""
    return [c.short for c in in_order() if c.short]


def null_values() -> dict[str, float]:
    """Every parameter of the catalogue at its null value (the base model)."""
    return {q.name: q.null for c in in_order() for q in c.params}


def for_boundary(
    boundary: str, stage: Stage = Stage.SELECTION, families: bool = False, columns: Iterable[str] = ()
) -> list[Cause]:
    """The causes of a stage that can occur in a boundary condition, in catalogue order (and the families,
    with a drift along each of the test log's ``columns``)."""
    return [
        c for c in in_order(columns) if c.stage == stage and boundary in c.boundaries and (families or not c.family)
    ]


def signatures(tests: Sequence[MeasuredTest]) -> dict[str, Signature]:
    """Evidence for each cause that needs no model fit, in catalogue order.

    Returns
    -------
    dict
        cause -> {"value": ..., "supports": bool, "text": str, ...} for the
        causes of the tests' boundary condition that have a signature.
    """
    ob = observe(tests)
    out = {}
    for cause in for_boundary(tests[0].boundary, families=True, columns=log_columns(tests)):
        s = cause.signature(ob)
        why = cause.not_identifiable(ob) if cause.family and cause.not_identifiable is not None else ""
        if why:
            # a family is named on the form it adds to its listed member, which a design that cannot identify
            # it cannot show: never named there (a listed cause may be, its model holding the design's bias)
            s = {**(s or {}), "supports": False, "not_identifiable": why, "text": (s or {}).get("text", why)}
        if s is not None:
            out[cause.name] = s
    return out


def starts(sigs: Mapping[str, Signature]) -> dict[str, float]:
    """Data-driven starting values of every parameter from the signatures (:func:`signatures`)."""
    out = {}
    for cause in in_order():
        out.update(cause.starts(sigs))
    return out
