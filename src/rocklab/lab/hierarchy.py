"""The levels at which the lab's data vary, and how many units a verdict needs (issue 24, item 1).

Impacts sit in tests, tests in series (one set-up: specimen, boundary
condition, contact depth), series in specimens, specimens in walls (a
specimen is a wall fractured at a bed joint to a lower height, Table 2;
Sect. 2), walls in the campaign.  For the limestone blocks, impacts sit in
trials and trials in block groups (one H/B each).

A covariate is a property of one level: the unit material of the wall, h/b
of the specimen, the contact depth and the boundary condition of the series,
the direction and the place of the test.  Its effect has as many degrees
of freedom as there are units of that level, never more: two series of one
wall are one wall's evidence about its material.  Every consumer that takes
an interval, a test, a fold or a resample imports the level from here
(:data:`COVARIATE_LEVEL`, :data:`BLOCK_COVARIATE_LEVEL`) and the rule of
:func:`too_few_units`.
"""

from __future__ import annotations

from rocklab.lab.campaign import UNREADABLE, Campaign

#: The levels of the lab's campaign, finest first.
LEVELS = ("impact", "test", "series", "specimen", "wall", "campaign")
#: The levels of the limestone blocks (rocklab/data/uminho-limestone-free-rocking), finest first.
BLOCK_LEVELS = ("impact", "trial", "block group", "campaign")
#: The column of tests.csv naming the unit of each level ('campaign': one unit, no column).
UNIT_COLUMN = {"test": "test_id", "series": "series", "specimen": "specimen", "wall": "wall"}
#: The level each covariate of the campaign is a property of (it is constant within a unit of it).
COVARIATE_LEVEL = {
    "unit": "wall",
    "h_over_b": "specimen",
    "contact_depth_mm": "series",
    "boundary": "series",
    "direction": "test",
    "order": "test",
}
#: The level the slenderness of a limestone block is a property of.
BLOCK_COVARIATE_LEVEL = {"h_over_b": "block group"}
#: Fewest units at each level of a categorical covariate: with one, the level's effect is
#: that unit's own departure (one tuff wall says what that wall does, not what tuff does).
MIN_UNITS_PER_LEVEL = 2
#: Fewest residual degrees of freedom of a verdict: with one, the 95 % t quantile is 12.7 and the
#: scatter between units rests on a single difference; no margin of the catalogue can be met.
MIN_DF = 2


def parent(level: str, levels: tuple[str, ...] = LEVELS) -> str:
    """The level above ``level`` (the one its units sit in)."""
    return levels[levels.index(level) + 1]


def plural(level: str, n: int) -> str:
    """``n`` units of ``level`` in words: "1 wall", "3 walls", "2 series", "12 block groups"."""
    return f"{n} {level}{'' if n == 1 or level.endswith('s') else 's'}"


def too_few_units(level: str, n_units: int, df: float, per_level: dict[str, int] | None = None) -> str:
    """Why a verdict on units of ``level`` cannot be given; "" when it can.

    Parameters
    ----------
    level : str
        The level the covariate varies at (:data:`COVARIATE_LEVEL`).
    n_units : int
        Units of that level the estimate rests on.
    df : int
        Residual degrees of freedom of its t interval.
    per_level : dict, optional
        Units at each value of a categorical covariate.

    Returns
    -------
    str
        Why, naming the units counted ("2 walls, 1 residual df (2 needed)"), or "".
    """
    if per_level is not None:
        short = {k: n for k, n in per_level.items() if n < MIN_UNITS_PER_LEVEL}
        if short:
            counts = ", ".join(f"{plural(level, n)} of {k}" for k, n in per_level.items())
            return f"{counts} ({MIN_UNITS_PER_LEVEL} {level}s a level needed)"
    if df < MIN_DF:
        return f"{plural(level, n_units)}, {df} residual df ({MIN_DF} needed)"
    return ""


def walls_of_specimens(campaign: Campaign) -> dict[str, str]:
    """Specimen -> wall of a :class:`rocklab.lab.campaign.Campaign` (its specimens.csv)."""
    return campaign.specimens.set_index("specimen").wall.astype(str).to_dict()


def walls_of_series(campaign: Campaign) -> dict[str, str]:
    """Series -> wall of a :class:`rocklab.lab.campaign.Campaign`: the wall of the specimen of its tests."""
    walls = walls_of_specimens(campaign)
    return {
        series: walls[campaign.test_row(ids[0]).specimen]
        for series, ids in campaign.reduction_groups().items()
        if series != UNREADABLE
    }


def thickness_of_walls(campaign: Campaign) -> dict[str, float]:
    """Wall -> its thickness [m] of a :class:`rocklab.lab.campaign.Campaign` (the mean over its specimens)."""
    spec = campaign.specimens.assign(wall=campaign.specimens.wall.astype(str))
    return (spec.groupby("wall").thickness_mm.mean() / 1000.0).to_dict()
