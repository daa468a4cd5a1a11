"""The diagnosis' results as typed objects: results/diagnosis.json, diagnosis/<boundary>.json, limestone_diagnosis.json.

The JSON files are the diagnosis' interface with the rest of the workflow
(the calibrated walls of the maps, the campaign's covariates, the figures,
the docs): every writer and reader goes through the objects here, which
hold exactly the keys of the files, in their order, and are checked against
their JSON schemas on the way in and out (:data:`DIAGNOSIS_SCHEMA`,
:data:`LIMESTONE_SCHEMA`, whose descriptions say what each key means).

==========================  =========================================================
object                      file
==========================  =========================================================
:class:`CampaignDiagnosis`  results/diagnosis.json: the series, then the boundary
                            conditions; results/diagnosis/<boundary>.json holds the
                            series of one boundary condition (none where a series
                            has no test of two impacts)
:class:`SeriesDiagnosis`    an entry of one series (:func:`~rocklab.diagnosis.series.diagnose_series`)
:class:`BoundaryDiagnosis`  an entry of one boundary condition, its series summed up
                            (:func:`~rocklab.diagnosis.pooling.diagnose_boundary`)
:class:`Finding`            a cause a series (or a limestone block group) names
:class:`Structure`          structure a model leaves, where and in words
:class:`SeriesChange`       a parameter's change over the tests of a series, or none
:class:`PooledFinding`      a cause named in enough series of a boundary condition
:class:`LeftOut`            a series a pooled parameter leaves out, and why
:class:`ChangingSeries`     a series a pooled parameter counts though it changes
                            over the series' tests
:class:`LimestoneDiagnosis` results/limestone_diagnosis.json
                            (:func:`~rocklab.diagnosis.block_tests.diagnose_blocks`)
==========================  =========================================================

The diagnosis builds these objects where it computes them (the series in
:func:`~rocklab.diagnosis.series.diagnose_series`, the boundary conditions
in :func:`~rocklab.diagnosis.pooling.diagnose_boundary`, the blocks in
:func:`~rocklab.diagnosis.block_tests.diagnose_blocks`) and hands them on
to the writer, the figures and the pages; ``to_dict`` is the file's form and
``from_dict`` makes the object of one, refusing a key it does not know.  A key
that the diagnosis writes only in some cases is None here where the file lacks it.
Every field but the one that says what a record is (an entry's ``scope``,
a finding's ``effect``) has an empty default, so that a program may hold
part of a result (the maps need only the findings of a boundary
condition); the schema checks a whole file, on its way out and in.  The
numbers in the file are those of :func:`jsonable`: non-finite floats are
null.

Size: every object of the files and every shape nested in them, in one
place beside the schemas they are checked against key by key.
"""

from __future__ import annotations

import enum
import json
import math
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, fields
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, Protocol, Self, TypeAlias, TypedDict, cast

import numpy as np

from rocklab._imports import lazy_module
from rocklab.data import data_path
from rocklab.disk import write_text

jsonschema = lazy_module("jsonschema")
yaml = lazy_module("yaml")

#: JSON schema of results/diagnosis.json and results/diagnosis/<boundary>.json
#: (shipped with the package, linked from ``workflow/schemas/``).
DIAGNOSIS_SCHEMA = data_path("schemas", "diagnosis.schema.yaml")
#: JSON schema of results/limestone_diagnosis.json.
LIMESTONE_SCHEMA = data_path("schemas", "limestone_diagnosis.schema.yaml")


def jsonable(x: object) -> object:
    """``x`` with NumPy scalars as Python numbers and non-finite floats as None (JSON)."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return None if not np.isfinite(x) else float(x)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


@cache
def _validator(schema: Path) -> Any:
    """A validator of the schema at ``schema`` (read once per process)."""
    return jsonschema.Draft202012Validator(yaml.safe_load(Path(schema).read_text()))


def validate(document: object, schema: Path, what: str) -> None:
    """Check a JSON document against a schema.

    Raises
    ------
    ValueError
        Naming ``what`` (a file, an object), the key at fault and what the
        schema asks of it.
    """
    err = jsonschema.exceptions.best_match(_validator(schema).iter_errors(document))
    if err is not None:
        where = "/".join(str(x) for x in err.absolute_path) or "(top level)"
        raise ValueError(f"{what}: {where}: {err.message} (see {Path(schema).name})")


class _Record:
    """A JSON object as a dataclass: its fields are the keys, in the file's order.

    ``_optional`` names the fields written only where they are not None (the
    keys the diagnosis writes in some cases only); ``_nested`` the fields
    that hold records (a class) or lists of records (a one-element list).
    """

    _optional: ClassVar[frozenset[str]] = frozenset()
    _nested: ClassVar[dict[str, type[_Record] | list[type[_Record]]]] = {}
    # what makes the subclasses dataclasses, for the type checker
    __dataclass_fields__: ClassVar[dict]

    def to_dict(self) -> dict:
        """The JSON object, keys in the file's order."""
        out = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if value is None and f.name in self._optional:
                continue
            if isinstance(value, _Record):
                value = value.to_dict()
            elif isinstance(value, list) and f.name in self._nested:
                value = [v.to_dict() for v in value]
            out[f.name] = value
        return out

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Self:
        """The record of a JSON object (or of a dict the diagnosis computed).

        Raises
        ------
        ValueError
            For a key the record does not hold.
        """
        names = [f.name for f in fields(cls)]
        unknown = [k for k in d if k not in names]
        if unknown:
            raise ValueError(f"{cls.__name__}: unknown key(s) {', '.join(unknown)} (the keys: {', '.join(names)})")
        kwargs = {}
        for k, v in d.items():
            kind = cls._nested.get(k)
            if kind is None or v is None:
                kwargs[k] = v
            elif isinstance(kind, list):
                kwargs[k] = [x if isinstance(x, kind[0]) else kind[0].from_dict(x) for x in v]
            else:
                kwargs[k] = v if isinstance(v, kind) else kind.from_dict(v)
        return cls(**kwargs)


class _Document:
    """A whole JSON file: ``to_json``/``from_json`` through :meth:`to_dict`/``from_dict``, validated."""

    schema: ClassVar[Path]
    #: What the file holds, in words (for the errors).
    title: ClassVar[str]

    def to_dict(self) -> dict | list:
        """The JSON document (the record's, or a list of entries)."""
        raise NotImplementedError

    if TYPE_CHECKING:
        # made by the subclasses (a record's, or a list of entries)
        @classmethod
        def from_dict(cls, d: Any) -> Self: ...

    def to_json(self, path: str | os.PathLike[str]) -> None:
        """Write the file as the diagnosis always has: ``json.dumps(..., indent=1)``, no final newline.

        Raises
        ------
        ValueError
            Where the content does not follow :attr:`schema` (nothing is written).
        """
        document = jsonable(self.to_dict())
        validate(document, self.schema, f"{type(self).__name__} for {path}")
        write_text(path, json.dumps(document, indent=1))

    @classmethod
    def from_json(cls, path: str | os.PathLike[str]) -> Self:
        """The object of a file written by :meth:`to_json`.

        Raises
        ------
        ValueError
            For a file that is no JSON or does not follow :attr:`schema`.
        """
        path = Path(path)
        try:
            document = json.loads(path.read_text())
        except json.JSONDecodeError as err:
            raise ValueError(f"{path}: not a readable {cls.title} ({err})") from err
        validate(document, cls.schema, str(path))
        return cls.from_dict(document)


# The nested objects of the files that stay mappings in the objects (their keys are measures or
# parameters by name): their shapes, key by key, as the schemas give them.

#: A number of the files: a float, or None where it is not finite (:func:`jsonable`).
Number = float | None


class MeasuredAndModel(TypedDict):
    """A measure of the tests and of the model's free run (means over the tests)."""

    measured: Number
    model: Number


#: Engineering errors of a free run (:func:`rocklab.diagnosis.errors.engineering_errors`): a measure to
#: its measured and model values, or to an error.
Errors = dict[str, MeasuredAndModel | Number]


class HeldOut(TypedDict):
    """Held-out errors (measure -> mean over the tests) of the base model and of the chosen model."""

    base: dict[str, Number]
    model: dict[str, Number]


class ModelBias(TypedDict, total=False):
    """The bias of the model at the fit (:mod:`rocklab.diagnosis.estimation.bias`), by parameter, or why
    it was not measured."""

    b: dict[str, float]
    u_model: dict[str, float]
    not_measured: str


class SeriesExtended(TypedDict):
    """The base model with the causes found, and its engineering errors."""

    effects: list[str]
    params: dict[str, Number]
    errors: Errors
    statement: str


class BoundaryExtended(TypedDict):
    """The extended models of a boundary condition's series, summed up."""

    statement: str
    n_series: int


class PooledEvidence(TypedDict):
    """Why a cause is named for a boundary condition: its series, its pooling, its range over them."""

    series: str
    pooled: str
    range: dict[str, list[float]]


class CurveLine(TypedDict):
    """One line of a discovered form's figure: points and their label."""

    x: list[float]
    y: list[float]
    label: str


class Curve(TypedDict):
    """A discovered form's curve against the data: its lines and the axes' labels."""

    measured: CurveLine
    best_listed: CurveLine
    family: CurveLine
    x: str
    y: str


def floats(numbers: Mapping[str, Number]) -> dict[str, float]:
    """The numbers of a file's mapping as floats, a null (a number that was not finite) as NaN."""
    return {k: math.nan if v is None else float(v) for k, v in numbers.items()}


class BlockBase(TypedDict):
    """Housner's e_an (Eq. 2) against the measured ratios of a block group."""

    model: str
    e_an: Number
    measured_median_ratio: Number
    measured_geometric_mean_ratio: Number


class WeakEvidence(TypedDict):
    """A cause that would remove the structure left, short of the evidence: its parameters and why."""

    params: dict[str, Number]
    reason: str


class Slenderness(TypedDict):
    """The block groups' mean of the per-trial median r/e_an against (B/H)^2."""

    intercept: Number
    slope: Number
    slope_se: Number
    p: Number
    n_groups: int
    n_trials: int
    levels: dict[str, Number]


@dataclass(frozen=True)
class Structure(_Record):
    """Structure a model leaves in the data: ``where`` it is (a residual group such as ``impact``,
    or the cause whose form it questions) and the ``sentence`` that says it in numbers.

    The diagnosis of a boundary condition counts its series' structure by ``where``
    (:func:`rocklab.diagnosis.pooling.diagnose_boundary`); the pages print the sentence.
    """

    where: str
    sentence: str

    def __str__(self) -> str:
        return self.sentence


class ChangeKind(enum.StrEnum):
    """What a named parameter does over the tests of a series
    (:func:`rocklab.diagnosis.estimation.change.changes_over_tests`)."""

    NONE = "none"
    GRADUAL = "gradual"
    CHANGE_POINT = "change point"


@dataclass
class SeriesChange(_Record):
    """A named parameter tested for a change over the tests of its series, and what was found.

    ``kind`` is :attr:`ChangeKind.NONE` where neither a change point nor a
    gradual change clears the test (a permutation test over the test order,
    Bonferroni over the parameters and the two kinds, and the information
    criterion); otherwise ``where`` the change is (a change point: the index,
    in series order from 0, and the id of the first test after it; no interval
    is given for it), the value ``before`` and ``after`` it with their 95 %
    intervals over the tests of each side (a gradual change: at the first and
    the last test), and the ``size`` (after less before) with its interval.
    The tests are the unit: every interval rests on them.
    """

    _optional = frozenset(
        {"where_index", "where_test", "before", "after", "ci95_before", "ci95_after", "size", "ci95_size", "note"}
    )

    parameter: str
    effect: str = ""
    kind: ChangeKind = ChangeKind.NONE
    n_tests: int = 0
    where_index: int | None = None
    where_test: str | None = None
    before: float | None = None
    after: float | None = None
    ci95_before: list[Number] | None = None
    ci95_after: list[Number] | None = None
    size: float | None = None
    ci95_size: list[Number] | None = None
    p_change_point: Number = None
    p_gradual: Number = None
    dbic_change_point: Number = None
    dbic_gradual: Number = None
    level: float = 0.05
    n_permutations: int = 0
    note: str | None = None

    def __post_init__(self) -> None:
        # a file holds the kind's value: the object holds the enum, which decisions read
        self.kind = ChangeKind(self.kind)

    def __str__(self) -> str:
        """ "zeta changes from test T7 on, 0.0062 to 0.0081 (95 % interval of the change [...] on 10 tests)",
        as the pages say it; "zeta: no change over 10 tests" where none was found."""
        if self.kind is ChangeKind.NONE or self.before is None or self.after is None or self.ci95_size is None:
            return f"{self.parameter}: no change over {self.n_tests} tests"
        if self.kind is ChangeKind.CHANGE_POINT:
            how = f"changes from test {self.where_test or self.where_index} on"
        else:
            how = "changes gradually over the series"
        lo, hi = self.ci95_size
        return (
            f"{self.parameter} {how}, {self.before:.4g} to {self.after:.4g} "
            f"(95 % interval of the change [{lo:.3g}, {hi:.3g}] on {self.n_tests} tests)"
        )


@dataclass
class Finding(_Record):
    """A cause named by the data of one series (or of the limestone blocks).

    Parameters of the cause with their bootstrap 95 % intervals, the
    systematic standard uncertainty those hold (``u_systematic``), the
    intervals that hold all the verdict's parameters together at 95 %
    (``ci95_joint``), the tests
    they rest on, the evidence in words, the held-out errors of the model
    with the cause and their gain over the base model; a form discovered
    beyond the catalogue (a family) also says what it reduces to and its
    gain against the listed causes.  ``may_stand_in_for`` names the causes
    the series' design cannot identify whose effect this one may carry
    (:func:`rocklab.diagnosis.estimation.selection.stand_ins`), each with why
    it cannot be identified: the cause is then named with that caveat.
    ``changes_within`` names its parameters that change over the tests of
    the series (the entry's ``changes`` say where and by how much): their
    values are means over wall states, not one state's.
    """

    _optional = frozenset(
        {
            "ci_note",
            "u_systematic",
            "ci95_joint",
            "may_stand_in_for",
            "discovered",
            "family",
            "reduces_to",
            "best_listed",
            "heldout_gain",
            "curve",
            "changes_within",
        }
    )

    effect: str
    params: dict[str, float | None] = field(default_factory=dict)
    ci95: dict[str, list[Number]] = field(default_factory=dict)
    u_systematic: dict[str, float] | None = None
    ci95_joint: dict[str, list[Number]] | None = None
    n_tests: int | None = None
    ci_note: str | None = None
    evidence: dict[str, str] = field(default_factory=dict)
    error_heldout: dict[str, float | None] = field(default_factory=dict)
    gain: dict[str, float | None] = field(default_factory=dict)
    may_stand_in_for: dict[str, str] | None = None
    changes_within: list[str] | None = None
    discovered: bool | None = None
    family: str | None = None
    reduces_to: str | None = None
    best_listed: list[str] | None = None
    heldout_gain: dict[str, float | None] | None = None
    curve: Curve | None = None


class LeftOutBecause(enum.StrEnum):
    """Why a boundary condition's pooled parameter leaves a series out (:class:`LeftOut`)."""

    #: The series' design cannot carry the cause (its ``not_identifiable``): it says nothing of its size.
    NOT_IDENTIFIABLE = "not_identifiable"
    #: The series neither names the cause nor has an estimate of the parameter (its data carry no
    #: signature of it, or its fit put the parameter on a bound: the data did not fix it).
    NO_ESTIMATE = "no_estimate"
    #: The series is too small to name any cause (its ``too_small``).
    TOO_SMALL = "too_small"


@dataclass
class LeftOut(_Record):
    """A series a pooled parameter leaves out (never counted at the null value), the parameters it is
    left out of, why (``reason``, typed) and why in words (``why``: the series' own where it has one)."""

    series: str
    reason: LeftOutBecause
    params: list[str] = field(default_factory=list)
    why: str = ""

    def __post_init__(self) -> None:
        # a file holds the reason's value: the object holds the member
        self.reason = LeftOutBecause(self.reason)

    def __str__(self) -> str:
        """ "series 2b-1s (why)", as the pages say it."""
        return f"series {self.series} ({self.why})"


@dataclass
class ChangingSeries(_Record):
    """A series a pooled parameter counts though the parameter changes over the series' tests.

    The change (``kind``, where a change point is: ``where_test``, the
    values ``before`` and ``after`` it) is the series' own
    (:class:`SeriesChange`); ``u_states`` is the standard deviation of the
    series' states over its tests, added in quadrature to its standard
    error in the pool (:func:`rocklab.diagnosis.pooling.state_spread`).
    """

    _optional = frozenset({"where_test"})

    series: str
    parameter: str
    kind: ChangeKind = ChangeKind.NONE
    where_test: str | None = None
    before: Number = None
    after: Number = None
    u_states: Number = None

    def __post_init__(self) -> None:
        # a file holds the kind's value: the object holds the enum
        self.kind = ChangeKind(self.kind)

    def __str__(self) -> str:
        """ "series 2b-1s (zeta 0.0062 to 0.0081 from test T7 on; ...)", as the pages say it."""
        how = f"from test {self.where_test} on" if self.where_test else str(self.kind)
        return (
            f"series {self.series} ({self.parameter} {_g(self.before)} to {_g(self.after)} {how}; "
            f"counted with its standard error widened by the spread of its states, {_g(self.u_states)})"
        )


def _g(x: Number) -> str:
    """A number as the pages give a parameter, "n/a" for none."""
    return "n/a" if x is None else f"{x:.4g}"


@dataclass
class PooledFinding(_Record):
    """A cause named in at least half of the series of a boundary condition that can name one.

    The random-effects means of its parameters over every series that can
    estimate them, each at its own estimate under the extended model, named
    or not (walls where known), their t intervals widened by the systematic
    uncertainty the series share (``u_systematic``), the series left out and
    why (``left_out``: never at the null value), the series counted though
    the parameter changes over their tests (``changes_within``: their
    standard errors widened by the spread of their states), the range over
    the series that name it, and the test-weighted means of their held-out
    errors and gains (:func:`rocklab.diagnosis.pooling.diagnose_boundary`).
    """

    _optional = frozenset({"ci_note", "u_systematic", "left_out", "changes_within"})
    _nested = {"left_out": [LeftOut], "changes_within": [ChangingSeries]}

    effect: str
    params: dict[str, float | None] = field(default_factory=dict)
    ci95: dict[str, list[Number]] = field(default_factory=dict)
    u_systematic: dict[str, float] | None = None
    evidence: PooledEvidence = field(default_factory=lambda: PooledEvidence(series="", pooled="", range={}))
    error_heldout: dict[str, float | None] = field(default_factory=dict)
    gain: dict[str, float | None] = field(default_factory=dict)
    n_series: int | None = None
    n_tests: int | None = None
    ci_note: str | None = None
    left_out: list[LeftOut] | None = None
    changes_within: list[ChangingSeries] | None = None


@dataclass
class BaseRun(_Record):
    """The base (literature) model of an entry and its engineering errors
    (:func:`rocklab.diagnosis.errors.engineering_errors`); for one-sided walls
    also those of the literature alternatives."""

    _optional = frozenset({"alternatives"})

    model: str | None = None
    errors: Errors = field(default_factory=dict)
    alternatives: dict[str, Errors] | None = None


class _HasFindings(Protocol):
    """An entry's fields its methods read (declared by each subclass, in the file's order)."""

    findings: list
    verdict: list[str]


@dataclass
class _Entry(_Record):
    """What every entry of results/diagnosis.json has (see the subclasses)."""

    @property
    def named(self: _HasFindings) -> list:
        """The findings that name a cause (those of the verdict), in the entry's order."""
        return [f for f in self.findings if f.effect in self.verdict]

    def finding(self: _HasFindings, effect: str) -> Finding | PooledFinding | None:
        """The finding of a cause, None where the entry has none."""
        return next((f for f in self.findings if f.effect == effect), None)

    @property
    def discovered(self: _HasFindings) -> list:
        """The findings of a form discovered beyond the catalogue."""
        return [f for f in self.findings if getattr(f, "discovered", None)]


@dataclass
class SeriesDiagnosis(_Entry):
    """The diagnosis of one series (an entry of results/diagnosis/<boundary>.json and of diagnosis.json).

    A series too small to name a cause (``too_small`` says why) has no
    ``signatures``, ``heldout`` nor ``extended``; ``listed_verdict`` and
    ``listed_params`` are the causes of the catalogue alone where a form
    beyond it was tried; ``not_identifiable`` the causes its design cannot
    carry, and why (:func:`rocklab.diagnosis.series.not_identifiable`);
    ``model_bias`` the bias of the model measured where a cause is selected
    (:mod:`rocklab.diagnosis.estimation.bias`); ``unnamed_estimates`` the
    parameters of the candidates it does not name whose signature its data
    carry (:func:`rocklab.diagnosis.series.unnamed_estimates`), ``unnamed_se`` their statistical
    standard errors where known.  A series whose
    diagnosis could not finish (it raised) has ``not_finished``, the exception
    that stopped it, its tests and impacts, and no model (no ``base``,
    ``what_is_wrong`` nor ``sample_test``): the campaign's readers skip it
    (:attr:`CampaignDiagnosis.series`, :attr:`CampaignDiagnosis.not_finished`).
    A series longer than :data:`rocklab.diagnosis.splitting.SPLIT_CAP` tests was split
    (:mod:`rocklab.diagnosis.splitting`): ``n_tests_selection`` of its tests chose the causes (the
    evidence, the rejections, the signatures, the changes, the unnamed estimates rest on them), the
    ``n_tests_estimation`` others estimated the named causes' parameters and intervals (the findings'
    ``n_tests``); neither is written for a series not split.
    """

    _optional = frozenset(
        {
            "n_tests_selection",
            "n_tests_estimation",
            "base",
            "what_is_wrong",
            "sample_test",
            "not_finished",
            "too_small",
            "not_identifiable",
            "listed_verdict",
            "listed_params",
            "signatures",
            "unnamed_estimates",
            "unnamed_se",
            "heldout",
            "model_bias",
            "extended",
            "changes",
        }
    )
    _nested = {
        "base": BaseRun,
        "findings": [Finding],
        "residual_structure": [Structure],
        "changes": [SeriesChange],
    }

    scope: str
    key: str | None = None
    boundary: str | None = None
    n_tests: int | None = None
    n_impacts: int | None = None
    n_tests_selection: int | None = None
    n_tests_estimation: int | None = None
    base: BaseRun | None = None
    what_is_wrong: str | None = None
    not_finished: str | None = None
    too_small: str | None = None
    verdict: list[str] = field(default_factory=list)
    not_identifiable: dict[str, str] | None = None
    unexplained: bool = False
    residual_structure: list[Structure] = field(default_factory=list)
    findings: list[Finding] = field(default_factory=list)
    changes: list[SeriesChange] | None = None
    listed_verdict: list[str] | None = None
    listed_params: dict[str, float | None] | None = None
    weak_evidence: dict[str, str] = field(default_factory=dict)
    rejected: dict[str, str] = field(default_factory=dict)
    signatures: dict[str, str] | None = None
    unnamed_estimates: dict[str, dict[str, float]] | None = None
    unnamed_se: dict[str, dict[str, float]] | None = None
    heldout: HeldOut | None = None
    model_bias: ModelBias | None = None
    extended: SeriesExtended | None = None
    sample_test: str | None = None

    @property
    def changed(self) -> list[SeriesChange]:
        """The parameters tested that change over the series' tests (a kind other than none)."""
        return [c for c in self.changes or () if c.kind is not ChangeKind.NONE]


@dataclass
class BoundaryDiagnosis(_Entry):
    """The diagnosis of one boundary condition from those of its series.

    ``heldout`` is None (null) where no series is large enough to name a
    cause, and ``too_small`` then says so; ``extended`` sums up the
    extended models of the series that have one.
    """

    _optional = frozenset({"extended", "too_small", "wall_thickness_m"})
    _nested = {"base": BaseRun, "findings": [PooledFinding], "residual_structure": [Structure]}

    scope: str
    key: str | None = None
    boundary: str | None = None
    n_tests: int | None = None
    n_series: int | None = None
    n_series_diagnosed: int | None = None
    too_small_series: list[str] = field(default_factory=list)
    n_impacts: int | None = None
    base: BaseRun | None = None
    what_is_wrong: str | None = None
    verdict: list[str] = field(default_factory=list)
    unexplained: bool = False
    residual_structure: list[Structure] = field(default_factory=list)
    unexplained_series: list[str] = field(default_factory=list)
    findings: list[PooledFinding] = field(default_factory=list)
    heldout: HeldOut | None = None
    series_verdicts: dict[str, list[str]] = field(default_factory=dict)
    extended: BoundaryExtended | None = None
    too_small: str | None = None
    wall_thickness_m: float | None = None


#: An entry as a caller may hold it: its object, or the dict of its JSON object.
_EntryLike: TypeAlias = "SeriesDiagnosis | BoundaryDiagnosis | Mapping[str, Any]"


def entry_of(d: _EntryLike) -> SeriesDiagnosis | BoundaryDiagnosis:
    """The :class:`SeriesDiagnosis` or :class:`BoundaryDiagnosis` of an entry (by its ``scope``)."""
    if isinstance(d, _Entry):
        return d
    return (BoundaryDiagnosis if d.get("scope") == "boundary" else SeriesDiagnosis).from_dict(d)


@dataclass
class CampaignDiagnosis(_Document):
    """The entries of a diagnosis: results/diagnosis.json, or the series of results/diagnosis/<boundary>.json.

    ``entries`` are the series then the boundary conditions, as
    :func:`~rocklab.diagnosis.pooling.diagnose_campaign` gives them.
    """

    schema: ClassVar[Path] = DIAGNOSIS_SCHEMA
    title: ClassVar[str] = "diagnosis"

    entries: list = field(default_factory=list)

    def to_dict(self) -> list:
        """The JSON document: a list of entries."""
        return [e.to_dict() for e in self.entries]

    @classmethod
    def from_dict(cls, entries: Iterable[_EntryLike]) -> Self:
        """The diagnosis of a list of entries (dicts or entry objects)."""
        if isinstance(entries, dict):
            raise ValueError("a diagnosis is a list of entries, not an object")
        return cls([entry_of(e) for e in entries])

    @classmethod
    def of(cls, diagnosis: CampaignDiagnosis | str | Path | Iterable[_EntryLike]) -> Self:
        """A diagnosis from what a caller may hold: the object, its entries or the path of its JSON file.

        Raises
        ------
        ValueError
            For a path that is not a readable diagnosis.
        """
        if isinstance(diagnosis, cls):
            return diagnosis
        if isinstance(diagnosis, (str, Path)):
            try:
                return cls.from_json(diagnosis)
            except OSError as err:
                raise ValueError(f"{diagnosis}: not a readable {cls.title} ({err})") from err
        # neither the object nor a path: its entries
        return cls.from_dict(list(cast("Iterable[_EntryLike]", diagnosis)))

    @classmethod
    def joined(cls, parts: Iterable[CampaignDiagnosis]) -> Self:
        """One diagnosis of the entries of several, in their order."""
        return cls([e for part in parts for e in part.entries])

    @classmethod
    def of_series_files(cls, paths: Iterable[str | os.PathLike[str]]) -> Self:
        """The series of a campaign from its diagnosis jobs' files (results/diagnosis/<job>.json),
        ordered by series as diagnosis.json lists them (the files interleave them)."""
        joined = cls.joined(cls.from_json(path) for path in paths)
        return cls(sorted(joined.entries, key=lambda e: e.key))

    @property
    def series(self) -> list[SeriesDiagnosis]:
        """The entries of the series diagnosed, in the file's order (not those whose diagnosis did not
        finish: :attr:`not_finished`)."""
        return [e for e in self.entries if isinstance(e, SeriesDiagnosis) and e.not_finished is None]

    @property
    def not_finished(self) -> list[SeriesDiagnosis]:
        """The entries of the series whose diagnosis did not finish, in the file's order."""
        return [e for e in self.entries if isinstance(e, SeriesDiagnosis) and e.not_finished is not None]

    @property
    def boundaries(self) -> list[BoundaryDiagnosis]:
        """The entries of the boundary conditions, in the file's order."""
        return [e for e in self.entries if isinstance(e, BoundaryDiagnosis)]

    def boundary(self, boundary: str | None) -> BoundaryDiagnosis | None:
        """The entry of a boundary condition ("two-sided", "one-sided"), None where there is none."""
        return next((e for e in self.boundaries if e.boundary == boundary), None)

    def series_of(self, boundary: str | None) -> list[SeriesDiagnosis]:
        """The series entries of one boundary condition."""
        return [e for e in self.series if e.boundary == boundary]

    @property
    def sample_tests(self) -> set[str]:
        """The sample test of every series (the test its figure draws)."""
        return {e.sample_test for e in self.series if e.sample_test is not None}

    @property
    def unexplained(self) -> list[SeriesDiagnosis]:
        """The series that leave structure no candidate explains."""
        return [e for e in self.series if e.unexplained]

    def minority(self, boundary: str | None) -> list[tuple[SeriesDiagnosis, Finding]]:
        """The findings of the series of a boundary condition that its verdict lacks (named in too few series).

        Returns
        -------
        list of (SeriesDiagnosis, Finding)
            In the order of the series and of their findings; every finding
            of its series where the boundary condition has no entry.
        """
        entry = self.boundary(boundary)
        verdict = entry.verdict if entry is not None else []
        return [(e, f) for e in self.series_of(boundary) for f in e.findings if f.effect not in verdict]


@dataclass
class FamilyComparison(_Record):
    """A family of the impact law fitted on the limestone trials, named or not,
    against the base model and the best listed cause
    (:func:`rocklab.diagnosis.discovery.family_against_listed`)."""

    effect: str
    form: str | None = None
    params: dict[str, float | None] = field(default_factory=dict)
    ci95: dict[str, list[Number]] = field(default_factory=dict)
    reduces_to: str | None = None
    discovered: bool | None = None
    best_listed: str | None = None
    best_listed_params: dict[str, float | None] = field(default_factory=dict)
    dbic_vs_base: float | None = None
    dbic_vs_best_listed: float | None = None
    heldout_gain: dict[str, float | None] = field(default_factory=dict)


@dataclass
class BlockDiagnosis(_Entry):
    """The diagnosis of one group of limestone trials (one H/B) or of all of them."""

    _optional = frozenset({"listed_verdict"})
    _nested = {"findings": [Finding], "families": [FamilyComparison], "residual_structure": [Structure]}

    scope: str
    key: str | None = None
    h_over_b: float | None = None
    n_tests: int | None = None
    n_impacts: int | None = None
    base: BlockBase = field(
        default_factory=lambda: BlockBase(
            model="", e_an=None, measured_median_ratio=None, measured_geometric_mean_ratio=None
        )
    )
    what_is_wrong: str | None = None
    verdict: list[str] = field(default_factory=list)
    listed_verdict: list[str] | None = None
    unexplained: bool = False
    residual_structure: list[Structure] = field(default_factory=list)
    findings: list[Finding] = field(default_factory=list)
    weak_evidence: dict[str, WeakEvidence] = field(default_factory=dict)
    rejected: dict[str, str] = field(default_factory=dict)
    signatures: dict[str, str] = field(default_factory=dict)
    heldout: HeldOut = field(default_factory=lambda: HeldOut(base={}, model={}))
    families: list[FamilyComparison] = field(default_factory=list)


@dataclass
class LimestoneDiagnosis(_Record, _Document):
    """results/limestone_diagnosis.json: all trials, each block group, the trend with slenderness."""

    schema: ClassVar[Path] = LIMESTONE_SCHEMA
    title: ClassVar[str] = "limestone diagnosis"
    _nested = {"all": BlockDiagnosis, "groups": [BlockDiagnosis]}

    all: BlockDiagnosis
    groups: list[BlockDiagnosis]
    slenderness: Slenderness = field(
        default_factory=lambda: Slenderness(
            intercept=None, slope=None, slope_se=None, p=None, n_groups=0, n_trials=0, levels={}
        )
    )
    source: str | None = None
