"""The campaign-wide statements and their verdicts: what a claim is, its margin, how it is judged.

The paper's statements (:data:`PAPER_CLAIMS`, data:
``rocklab/data/paper_claims.csv``) and the exploratory "no effect" checks of
:mod:`rocklab.dissipation.covariates` are judged here (:func:`verdict`),
with one rule for the margin of every "no effect" and "close to" statement
(:func:`margin_of`, issue 24, item 2): the smallest change of the catalogue
parameter the response is that changes a simulated engineering outcome by
a stated tolerance (:func:`outcome_margin`).

The outcome is the free-rocking duration to rest, p D (the paper's Fig. 19),
of the reference wall: the maps' wall of Sect. 5 (alpha 0.1, R 3 m) with the
paper's calibrated restitution (0.95 e_an,2s two-sided, 1.05 e_an,1s
one-sided, :mod:`rocklab.physics.restitution`), released from rest at
:data:`REFERENCE_RELEASE` alpha, the instability displacement the paper's
two-sided walls reach on average (Sect. 3: 91 % of alpha), through the exact
simulator (:func:`rocklab.diagnosis.wall_model.simulator`,
:func:`rocklab.simulation.reference.simulate_free`).  The tolerance
(:data:`DURATION_TOLERANCE`, 5 %) is the change of duration an assessment
would act on, and of the order of the scatter of the durations of one
series' tests (Fig. 19): an effect below it is hard to tell from a
repetition of the test.  A wall that overturns or never comes to rest has changed its
outcome by more than any tolerance.  A statement on one boundary
condition takes the margin of its wall, one on the boundary condition as
a covariate the smaller of the two; each is the smaller over the two
directions from the parameter's reference value (its null; for the
restitution scale the calibrated ratio).  A parameter the simulator carries no law of
(a law of the impact speed), or whose whole range changes the duration less
than the tolerance (a drift, on a wall in the middle of its series), has no
margin: no statement of no effect on it is supported.  One whose smallest
departure from the null changes the outcome has a margin of zero (a contact
gap: inside it the wall rocks two-sided).

The margins are computed once for every parameter of the catalogue
(:func:`margin_table`, about a minute) and shipped as
``rocklab/data/claim_margins.csv``; ``python -m rocklab.dissipation.claims``
writes it again after a change of the catalogue, the simulator or the rule.
With one margin per quantity, two claims on one mean further apart than
twice it (the ratio "close to one" and "on average 0.93") cannot both be
supported.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from rocklab._imports import lazy_module
from rocklab.data import data_path
from rocklab.diagnosis import catalogue
from rocklab.inference.verdicts import ClaimVerdict
from rocklab.lab.hierarchy import COVARIATE_LEVEL
from rocklab.physics import restitution
from rocklab.physics import wall as _wall
from rocklab.physics.boundary import Boundary
from rocklab.physics.law import Restitution

if TYPE_CHECKING:
    from rocklab.simulation.rocking_model import RockingModel

optimize = lazy_module("scipy.optimize")

#: The catalogue parameter each per-test response of tests.csv is (its margin, :func:`margin_of`).
RESPONSE_PARAMETER = {"e_ratio": "restitution_scale.c", "theta0_over_alpha": "instability_angle.alpha_r_over_alpha"}


@dataclass(frozen=True)
class Claim:
    """A campaign-wide statement to test.

    Attributes
    ----------
    key : str
        Short name (a column of campaign_effects.csv).
    boundary : str
        'two-sided', 'one-sided' or 'both' (the boundary condition as a covariate).
    response : str
        A column of tests.csv or ``<cause>.<parameter>`` of the diagnosis.
    covariate : str
        A covariate of :data:`rocklab.lab.hierarchy.COVARIATE_LEVEL`, or
        'mean' (a claim on the response's value itself).
    kind : {'zero', 'below', 'near'}
        No effect; the mean below ``value``; the mean close to ``value``.
    value : float
    paper : str
        Where the paper says it, and how.
    """

    key: str
    boundary: str
    response: str
    covariate: str
    kind: str = "zero"
    value: float = 0.0
    paper: str = ""


#: The kinds of claim :func:`verdict` judges: no effect, the mean below a value, the mean close to it.
CLAIM_KINDS = ("zero", "below", "near")
#: The boundary conditions a claim can be on ('both': the boundary condition as a covariate).
CLAIM_BOUNDARIES = (Boundary.TWO_SIDED, Boundary.ONE_SIDED, "both")


def read_claims(path: str | Path | None = None) -> tuple[Claim, ...]:
    """The campaign-wide statements in a CSV file, checked, as :class:`Claim` objects.

    Parameters
    ----------
    path : str or Path, optional
        A CSV file with the columns of :class:`Claim`, one statement a row;
        default the paper's, ``rocklab/data/paper_claims.csv``.

    Returns
    -------
    tuple of Claim
        In the order of the file (the order of campaign_effects.csv).

    Raises
    ------
    ValueError
        A missing or unknown column, a repeated key, a boundary, covariate
        or kind that the tests do not know, or a value that is no finite number.
    """
    path = data_path("paper_claims.csv") if path is None else Path(path)
    columns = [f.name for f in fields(Claim)]
    covariates = (*COVARIATE_LEVEL, "mean")
    with open(path, newline="", encoding="utf-8") as fh:
        reader = csv.DictReader(fh)
        if reader.fieldnames != columns:
            raise ValueError(f"{path}: columns {reader.fieldnames}, expected {columns}")
        claims: list[Claim] = []
        for line, row in enumerate(reader, start=2):
            where = f"{path}, line {line}"
            for column, known in (("boundary", CLAIM_BOUNDARIES), ("covariate", covariates), ("kind", CLAIM_KINDS)):
                if row[column] not in known:
                    raise ValueError(f"{where}: {column} {row[column]!r}, expected one of {', '.join(known)}")
            try:
                value = float(row["value"])
            except ValueError:
                value = math.nan
            if not math.isfinite(value):
                raise ValueError(f"{where}: value {row['value']!r} is no finite number")
            if row["key"] in {c.key for c in claims}:
                raise ValueError(f"{where}: key {row['key']!r} repeated")
            given: dict[str, Any] = {**row, "value": value}
            claims.append(Claim(**given))
    return tuple(claims)


#: The statements of the paper (Sects. 2-4, Figs. 10 and 13, Tables 2-3) that the campaign can test.
PAPER_CLAIMS = read_claims()


def verdict(
    kind: str, low: float, high: float, p: float, value: float = 0.0, margin: float = 0.0, alpha: float = 0.05
) -> ClaimVerdict:
    """The verdict on a claim from an interval [low, high] and the p-value.

    Parameters
    ----------
    kind : {'zero', 'below', 'near'}
        No effect (none beyond ``margin``: supported where the interval lies within +- margin, even
        where ``p`` is below ``alpha``, contradicted where it lies beyond, or where no margin is
        known and ``p`` is below ``alpha``); the mean below ``value``; the mean within ``value`` +-
        ``margin``.
    margin : float
        Absolute margin: the effect (or distance from ``value``) that counts as
        negligible (:func:`margin_of`); NaN where none is known, and then
        nothing is *supported* within a margin.

    Returns
    -------
    ClaimVerdict
        Supported, contradicted or inconclusive.
    """
    V = ClaimVerdict
    if kind == "zero":
        # no effect that matters: an effect the test detects but the interval holds within the margin
        # is negligible, one the interval puts beyond it contradicts; between the two, only a claim
        # of no effect at all (no margin known) is contradicted by the test
        if -margin <= low and high <= margin:
            return V.SUPPORTED
        if low > margin or high < -margin or (p < alpha and not margin >= 0):
            return V.CONTRADICTED
        return V.INCONCLUSIVE
    if kind == "below":
        return V.SUPPORTED if high < value else V.CONTRADICTED if low >= value else V.INCONCLUSIVE
    if kind == "near":
        if value - margin <= low and high <= value + margin:
            return V.SUPPORTED
        return V.CONTRADICTED if high < value - margin or low > value + margin else V.INCONCLUSIVE
    raise ValueError(f"unknown kind of claim {kind!r}")


# --- the margins: the smallest effect that changes a simulated outcome ---------------------------

#: The change of the reference wall's free-rocking duration to rest, p D, that counts (relative).
DURATION_TOLERANCE = 0.05
#: Release of the reference wall from rest [alpha]: the two-sided walls' mean instability displacement (Sect. 3).
REFERENCE_RELEASE = 0.9
#: The reference wall's restitution, as a scale of e_an: the paper's calibrated walls (Sects. 3, 5).
REFERENCE_SCALE: dict[str, float] = {
    Boundary.TWO_SIDED: restitution.CALIBRATED_RATIO_TWO_SIDED,
    Boundary.ONE_SIDED: restitution.CALIBRATED_RATIO_ONE_SIDED,
}
#: Longest free rocking simulated [1/p]: a wall still rocking then is taken as never coming to rest.
MAX_DURATION_P = 2000.0
#: The margins of every parameter of the catalogue (:func:`margin_table`), shipped with the library.
MARGINS_FILE = "claim_margins.csv"
#: Columns of :data:`MARGINS_FILE`.
MARGIN_COLUMNS = ("cause", "parameter", "boundary", "reference", "duration_p", "margin")


def reference_value(cause: str, parameter: str, boundary: str) -> float:
    """Value of a parameter on the reference wall: its null, the calibrated ratio for the restitution scale."""
    if (cause, parameter) == ("restitution_scale", "c"):
        return REFERENCE_SCALE[boundary]
    return next(q.null for q in catalogue.by_name(cause).params if q.name == parameter)


def reference_wall(boundary: str, cause: str | None = None, values: Mapping[str, float] | None = None) -> RockingModel:
    """The reference wall's simulator, with ``cause`` of the catalogue at ``values`` (null where missing).

    The maps' wall (:mod:`rocklab.seismic.walls`) with the paper's calibrated
    restitution (:data:`REFERENCE_SCALE`; the restitution scale itself when
    ``cause`` is it), as the diagnosis models a wall
    (:func:`rocklab.diagnosis.wall_model.model_of`, :func:`rocklab.diagnosis.wall_model.simulator`).

    Returns
    -------
    rocklab.simulation.rocking_model.RockingModel
    """
    from rocklab.diagnosis.wall_model import model_of, simulator
    from rocklab.seismic.calibrated import MapWall
    from rocklab.seismic.walls import ALPHA, R

    laws = list(catalogue.laws((cause,), values)) if cause else []
    if cause != "restitution_scale":
        laws.insert(0, Restitution(REFERENCE_SCALE[boundary]))
    wall = MapWall(ALPHA, float(_wall.frequency_parameter(R)), boundary)
    return simulator(model_of([wall], laws).row(0))


def free_rocking_duration(model: RockingModel) -> float:
    """p D: the free-rocking duration to rest of ``model`` released from rest at :data:`REFERENCE_RELEASE` alpha.

    The exact simulator (:func:`rocklab.simulation.reference.simulate_free`);
    rest is its rest criterion (impacts slower than ``REST_TOL`` thetadot_r).

    Returns
    -------
    float
        [-]; inf where the wall overturns or is still rocking after
        :data:`MAX_DURATION_P`.
    """
    from rocklab.simulation.reference import simulate_free

    h = simulate_free(
        model, REFERENCE_RELEASE * model.alpha, 0.0, t_end=MAX_DURATION_P / model.p, fs=model.p, rtol=1e-9, atol=1e-12
    )
    return math.inf if h.overturned or h.t_rest is None else float(h.t_rest * model.p)


def outcome_margin(cause: str, parameter: str, boundary: str, tolerance: float = DURATION_TOLERANCE) -> float:
    """The smallest change of a parameter that changes the reference wall's free-rocking duration by ``tolerance``.

    From the parameter's reference value (:func:`reference_value`) towards
    each of its bounds, the first change of a geometric scan (1e-4 of the
    room to the bound up to the bound) at which |D / D_ref - 1| reaches the
    tolerance, refined by Brent's method; the smaller of the two directions.

    Parameters
    ----------
    cause, parameter : str
        A parameter of the catalogue (:mod:`rocklab.diagnosis.catalogue`).
    boundary : {"two-sided", "one-sided"}
    tolerance : float
        Relative change of p D (:func:`free_rocking_duration`).

    Returns
    -------
    float
        In the parameter's units; NaN where no change within its bounds
        reaches the tolerance (or the simulator carries no law of it).
    """
    q = next(q for q in catalogue.by_name(cause).params if q.name == parameter)
    v0 = reference_value(cause, parameter, boundary)
    d0 = free_rocking_duration(reference_wall(boundary, cause, {parameter: v0}))

    def excess(change: float, sign: float) -> float:
        d = free_rocking_duration(reference_wall(boundary, cause, {parameter: v0 + sign * change}))
        return (abs(d / d0 - 1.0) if math.isfinite(d) else 1.0) - tolerance

    best = math.nan
    for sign, room in ((1.0, q.upper - v0), (-1.0, v0 - q.lower)):
        if room <= 0:
            continue
        below = 0.0
        for change in room * np.logspace(-4, 0, 9):
            if excess(change, sign) >= 0:
                root = optimize.brentq(excess, below, change, args=(sign,), xtol=1e-4 * change, rtol=1e-6)
                best = root if math.isnan(best) else min(best, root)
                break
            below = change
    return best


def margin_table() -> pd.DataFrame:
    """:func:`outcome_margin` of every parameter of the catalogue in each boundary condition it occurs in.

    Returns
    -------
    pandas.DataFrame
        :data:`MARGIN_COLUMNS`: the parameter's reference value, the
        reference wall's p D and the margin (NaN: none).
    """
    rows: list[tuple[Any, ...]] = []
    for c in catalogue.in_order():
        for q in c.params:
            for b in c.boundaries:
                v0 = reference_value(c.name, q.name, b)
                d0 = free_rocking_duration(reference_wall(b, c.name, {q.name: v0}))
                rows.append((c.name, q.name, b, v0, d0, outcome_margin(c.name, q.name, b)))
    return pd.DataFrame(rows, columns=list(MARGIN_COLUMNS))


@cache
def margins() -> pd.DataFrame:
    """The shipped :func:`margin_table` (``rocklab/data/claim_margins.csv``)."""
    return pd.read_csv(data_path(MARGINS_FILE))


def margin_rule() -> dict[str, Any]:
    """The rule of the margins in numbers, for the docs: tolerance, reference wall, its durations.

    Returns
    -------
    dict
        ``tolerance`` (relative change of p D), ``release`` [alpha],
        ``alpha`` [rad], ``R`` [m], ``scale`` and ``duration_p`` by
        boundary condition (the reference wall's e / e_an and its p D);
        ``zero``, ``none``: the parameters (``<cause>.<parameter>``) whose
        margin is zero in a boundary condition, or that have none in either.
    """
    from rocklab.seismic.walls import ALPHA, R

    table = margins()
    base = table[(table.cause == "restitution_scale") & (table.parameter == "c")].set_index("boundary")
    return {
        "tolerance": DURATION_TOLERANCE,
        "release": REFERENCE_RELEASE,
        "alpha": ALPHA,
        "R": R,
        "scale": dict(REFERENCE_SCALE),
        "duration_p": base.duration_p.to_dict(),
        "zero": sorted({f"{r.cause}.{r.parameter}" for r in table.itertuples() if r.margin == 0}),
        "none": sorted(
            f"{c}.{q}" for (c, q), m in table.groupby(["cause", "parameter"], sort=False).margin if m.isna().all()
        ),
    }


def margin_of(response: str, boundary: str = "both") -> float:
    """The equivalence margin of "no effect" and "close to" on ``response``, in its units.

    One rule for every statement (:func:`outcome_margin`): the smallest
    change of the catalogue parameter the response is (e_exp/e_an is the
    restitution scale c, theta0/alpha the instability angle alpha_r/alpha,
    :data:`RESPONSE_PARAMETER`; a diagnosis response ``<cause>.<parameter>``
    is that parameter) that changes the free-rocking duration of the
    reference wall of ``boundary`` by :data:`DURATION_TOLERANCE`; for
    ``"both"`` (the boundary condition as a covariate) the smaller of the
    two walls'.  NaN for a parameter with none (or no parameter of the
    catalogue): no statement of no effect on it can be supported.
    """
    cause, _, name = RESPONSE_PARAMETER.get(response, response).partition(".")
    table = margins()
    rows = (table.cause == cause) & (table.parameter == name)
    if boundary != "both":
        rows &= table.boundary == boundary
    found = table.margin[rows].dropna()
    return float(found.min()) if len(found) else math.nan


def claim_text(kind: str, value: float, margin: float) -> str:
    """The claim of a row in words: "no effect", "mean below 1", "mean within 0.0031 of 1" (the margin to
    two digits: the table's ``margin`` column holds it whole)."""
    words = {"zero": "no effect", "below": f"mean below {value:g}", "near": f"mean within {margin:.2g} of {value:g}"}
    return words[kind]


if __name__ == "__main__":
    margin_table().to_csv(data_path(MARGINS_FILE), index=False, float_format="%.6g")
