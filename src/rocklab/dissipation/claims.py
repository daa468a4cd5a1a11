"""The campaign-wide statements and their verdicts: what a claim is, its margin, how it is judged.

The paper's statements (:data:`PAPER_CLAIMS`, data:
``rocklab/data/paper_claims.csv``) and the exploratory "no effect" checks of
:mod:`rocklab.dissipation.covariates` are judged here (:func:`verdict`),
with one rule for the margin of every "no effect" and "close to" statement
(:func:`margin_of`): the smallest effect worth naming of the catalogue
parameter the response is, the departure of the simulated wall's
parameter from its null below which the diagnosis names no cause
(issue 24, item 2).  With one margin
per quantity, two claims on one mean further apart than twice it (the
ratio "close to one" and "on average 0.93") cannot both be supported.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, fields
from pathlib import Path

from rocklab.data import data_path
from rocklab.diagnosis import catalogue
from rocklab.lab.hierarchy import COVARIATE_LEVEL

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
CLAIM_BOUNDARIES = ("two-sided", "one-sided", "both")


def read_claims(path=None):
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
        claims = []
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
            claims.append(Claim(**{**row, "value": value}))
    return tuple(claims)


#: The statements of the paper (Sects. 2-4, Figs. 10 and 13, Tables 2-3) that the campaign can test.
PAPER_CLAIMS = read_claims()


def verdict(kind, low, high, p, value=0.0, margin=0.0, alpha=0.05):
    """The verdict on a claim from an interval [low, high] and the p-value.

    Parameters
    ----------
    kind : {'zero', 'below', 'near'}
        No effect; the mean below ``value``; the mean within ``value`` +- ``margin``.
    margin : float
        Absolute margin: the effect (or distance from ``value``) that counts as
        negligible (:func:`margin_of`); NaN where none is known, and then
        nothing is *supported* within a margin.

    Returns
    -------
    str
        'supported', 'contradicted' or 'inconclusive'.
    """
    if kind == "zero":
        if p < alpha:
            return "contradicted"
        return "supported" if -margin <= low and high <= margin else "inconclusive"
    if kind == "below":
        return "supported" if high < value else "contradicted" if low >= value else "inconclusive"
    if kind == "near":
        if value - margin <= low and high <= value + margin:
            return "supported"
        return "contradicted" if high < value - margin or low > value + margin else "inconclusive"
    raise ValueError(f"unknown kind of claim {kind!r}")


def margin_of(response):
    """The equivalence margin of "no effect" and "close to" on ``response``, in its units.

    One rule for every statement: the smallest effect worth naming
    (``practical``) of the catalogue parameter the response is (e_exp/e_an is
    the restitution scale c, theta0/alpha the instability angle
    alpha_r/alpha, :data:`RESPONSE_PARAMETER`; a diagnosis response
    ``<cause>.<parameter>`` is that parameter): the departure of the
    simulated wall's parameter below which the diagnosis names no cause
    (docs/diagnosis-method.md, "Selection").  NaN for a
    parameter with none: no statement of no effect on it can be supported.
    """
    cause, _, name = RESPONSE_PARAMETER.get(response, response).partition(".")
    try:
        params = catalogue.by_name(cause).params
    except StopIteration:
        return math.nan
    q = next((q for q in params if q.name == name), None)
    return math.nan if q is None or q.practical is None else float(q.practical)


def claim_text(kind, value, margin):
    """The claim of a row in words: "no effect", "mean below 1", "mean within 0.005 of 1"."""
    words = {"zero": "no effect", "below": f"mean below {value:g}", "near": f"mean within {margin:g} of {value:g}"}
    return words[kind]
