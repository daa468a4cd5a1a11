"""The verdicts a claim on the data can get (:func:`rocklab.dissipation.claims.verdict`): one word each."""

from __future__ import annotations

import enum


class ClaimVerdict(enum.StrEnum):
    """The verdict on a claim (written as its word in ``campaign_effects.csv``)."""

    #: The simultaneous interval lies within the claim.
    SUPPORTED = "supported"
    #: The effect differs from the claim (Holm-adjusted p, or the interval outside it).
    CONTRADICTED = "contradicted"
    #: Neither.
    INCONCLUSIVE = "inconclusive"
    #: Too few units, one level, no variation where the effect varies: no verdict (the row says why).
    NOT_TESTABLE = "not testable"
