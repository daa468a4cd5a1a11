"""Candidate causes of the diagnosis, one module each (the list is :mod:`rocklab.diagnosis.catalogue`).

A cause is a physical extension of the base rocking model: a module that
declares one :class:`Cause` named ``CAUSE``, whose physics is written once,
as laws of :mod:`rocklab.physics.law` (:attr:`Cause.laws`) that every model
reads: the diagnosis, the exact simulator, the maps, the shake-table and
limestone blocks.  docs/diagnosis-method.md shows how to add one.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, TypeAlias

from rocklab.diagnosis.parameters import Param
from rocklab.physics.boundary import Boundary

if TYPE_CHECKING:
    import numpy as np

    from rocklab.diagnosis.evidence import Observed, TestStack
    from rocklab.diagnosis.result import Structure
    from rocklab.diagnosis.wall_model import ModelParams
    from rocklab.physics.law import Amplitude, FlightLoss, Gap, Hinge, HousnerLoss, Restitution, SpeedFactor, Stop

BOTH = tuple(Boundary)

#: A law of :mod:`rocklab.physics.law`: what a cause does to a wall (:attr:`Cause.laws`).
Law: TypeAlias = "Restitution | HousnerLoss | Amplitude | SpeedFactor | Hinge | FlightLoss | Gap | Stop"

#: A cause's signature in the data (:attr:`Cause.signature`): ``value``, ``supports``, ``text`` and what
#: else the cause reads from it (its starting values, a statement), their kinds by key.
Signature: TypeAlias = dict[str, Any]

#: :attr:`Cause.unexplained`: what a model of a stack of tests leaves that the cause would explain.
Unexplained: TypeAlias = "Callable[[TestStack, ModelParams], list[Structure]]"


class Trials(Protocol):
    """What :attr:`Cause.on_ratios` reads of trials without rotations (the limestone blocks of
    :mod:`rocklab.diagnosis.block_tests`): (trials, impacts) arrays and a row per trial."""

    ids: list[str]
    alpha: np.ndarray
    u: np.ndarray
    odd: np.ndarray
    group: np.ndarray

    @property
    def ratio(self) -> np.ndarray: ...


class Stage(enum.StrEnum):
    """When the diagnosis estimates a cause (its value is the word the catalogue's tables give)."""

    #: A residual of the flights, selected by the engine with the other causes.
    SELECTION = "selection"
    #: Estimated once the chosen model is known, from what it leaves (the end of a free run: the
    #: stop); it acts on no law a flight or an impact of the chosen model is drawn with.
    AFTER_SELECTION = "after selection"


def _no_signature(observed: Observed) -> None:
    return None


def _no_starts(signatures: Mapping[str, Signature]) -> dict[str, float]:
    return {}


@dataclass(frozen=True)
class Cause:
    """What the diagnosis needs to know of one candidate cause.

    Attributes
    ----------
    name : str
        As reported (the module's name).
    law : str
        The extension in one line (docs and tables).
    params : tuple of Param
        Bounds, null value (the base model) and smallest effect worth naming.
    laws : callable
        ``laws(values) -> tuple``: what the cause does to a wall, as laws of
        :mod:`rocklab.physics.law` (restitution, Eq. 17, hinge angles, flight
        loss, gap, stop, ...), ``values`` its parameters by name.
    boundaries : tuple of str
        Boundary conditions it can occur in.
    signature : callable
        ``signature(observed) -> dict or None``: the evidence in the data
        that needs no fit (:class:`rocklab.diagnosis.evidence.Observed`),
        ``{"value", "supports", "text", ...}``; a cause whose signature does
        not support it is never named.
    starts : callable
        ``starts(signatures) -> dict``: data-driven starting values of its
        parameters from the signatures of all causes.
    replaces : tuple of str
        Causes it contains (Eq. 17's a is the plain scale): never fitted
        together.
    stage : Stage
        :attr:`Stage.SELECTION` (a residual of the flights, selected by the engine)
        or :attr:`Stage.AFTER_SELECTION` (estimated once the chosen model is known,
        from what that model leaves: :attr:`unexplained` and :attr:`estimate`).
    unexplained : callable, optional
        After-selection causes: ``unexplained(stack, mp) -> list of Structure``,
        what the model ``mp`` leaves that this cause would explain.
    estimate : callable, optional
        After-selection causes: ``estimate(tests, mp, seed) -> dict or None``,
        ``mp`` the chosen model of ``tests``
        (:class:`rocklab.diagnosis.wall_model.ModelParams`), with ``named`` (bool),
        ``values`` (its parameters) and ``finding`` (the entry of the diagnosis).
    family : str, optional
        A generalised family (issue 12) rather than a listed cause: the
        listed cause it holds as one member (its null values).  Families
        are searched only where the listed causes leave structure, and a
        family named is reported as discovered.
    closed_form : callable, optional
        Families: ``closed_form(values, ci) -> str``, the closed form of
        the library the fitted member reduces to (its intervals hold the
        values of that form), or "no closed form of the library".
    curve : callable, optional
        Families: ``curve(tests, values, listed) -> dict``, the discovered
        curve against the data and the best member of the catalogue
        (``values``, ``listed``: the parameters of the chosen and of the
        listed model), for the figure of
        :func:`rocklab.plots.diagnosis.family_curve_figure`.
    on_ratios : callable, optional
        ``on_ratios(trials) -> dict or None``: its signature in the ratios of
        the impacts alone, r = thetadot^+/thetadot^- of every impact of
        trials without rotations (the limestone blocks of
        :mod:`rocklab.diagnosis.block_tests`: ``trials.ratio`` r/e_an,
        ``u`` (thetadot^-_k/thetadot^-_1)^2, ``odd`` the impacts leaving the
        release edge, ``alpha``), as :attr:`signature`.
    short : str, optional
        Its name in the calibrated walls' model names, ``<2s|1s>-calibrated-no-<short>``
        (:mod:`rocklab.seismic.calibrated`); None for a cause the maps do not carry as found.
    on_the_maps : tuple, optional
        A cause the maps' wall cannot carry as found: ``(member, why)``, the
        cause of the catalogue that carries it instead (None: none, it is
        left off) and why.
    checks_form : bool
        Families: the signature is the only check of the form of the listed
        member (:attr:`family`), read on part of the flights; where the
        member is named and the signature cannot be read, the member's form
        is untested, and the diagnosis says so as structure left
        (:meth:`rocklab.diagnosis.series_problem.WallProblem.form_structure`).
    drifts : bool
        The cause changes from test to test of a series, along the test's
        place in it or along :attr:`log_column` (its figure draws it so).
    log_column : str, optional
        The column of the test log a drifting cause follows (None: the
        test's place in its series); a model of the cause needs that column
        even on a wall whose tests lack it (the maps' wall stands for the
        middle of the series).
    not_identifiable : callable, optional
        ``not_identifiable(observed) -> str``: why the tests of a series
        (:class:`rocklab.diagnosis.evidence.Observed`) cannot tell the cause
        from the noise or from another cause by their design, whatever its
        size ("" where they can); its absence from a verdict is then no
        evidence against it (:func:`rocklab.diagnosis.series.not_identifiable`).
    """

    name: str
    law: str
    params: tuple[Param, ...]
    laws: Callable
    boundaries: tuple[str, ...] = BOTH
    signature: Callable = _no_signature
    starts: Callable = _no_starts
    replaces: tuple[str, ...] = ()
    stage: Stage = Stage.SELECTION
    unexplained: Callable | None = None
    estimate: Callable | None = None
    family: str | None = None
    closed_form: Callable | None = None
    curve: Callable | None = None
    on_ratios: Callable | None = None
    short: str | None = None
    on_the_maps: tuple[str | None, str] | None = None
    checks_form: bool = False
    drifts: bool = False
    log_column: str | None = None
    not_identifiable: Callable | None = None

    def holds(self, ci: Mapping[str, Sequence[float]], name: str, value: float) -> bool:
        """Whether the 95 % interval ``ci`` of parameter ``name`` holds ``value`` (to its practical margin)."""
        q = next(q for q in self.params if q.name == name)
        lo, hi = ci[name]
        margin = q.practical or 0.0
        return lo - margin <= value <= hi + margin

    def values(self, values: Mapping[str, float]) -> dict[str, float]:
        """This cause's parameters from ``values``, the null value where missing."""
        return {q.name: values.get(q.name, q.null) for q in self.params}
