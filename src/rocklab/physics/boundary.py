"""The boundary conditions of a rocking wall (Sect. 2, Figs. 1 and 12): one name each.

A two-sided wall rocks about both edges of its base (Housner's block,
Eqs. 1-2); a one-sided wall is restrained on one face by the transverse
walls and rebounds off them (Eqs. 12-14).  The values are the names the
lab's test log, the result files and the pages use.
"""

from __future__ import annotations

import enum


class Boundary(enum.StrEnum):
    """A wall's boundary condition; equal to (and written as) its name, ``"two-sided"`` or ``"one-sided"``."""

    TWO_SIDED = "two-sided"
    ONE_SIDED = "one-sided"

    @property
    def key(self) -> str:
        """Its name as a key of the summaries and the pages' numbers: ``two_sided``, ``one_sided``."""
        return self.value.replace("-", "_")

    @property
    def short(self) -> str:
        """Its mark in the maps' model names (``2s-0.95``, ``1s-eq17``): ``2s``, ``1s``."""
        return "2s" if self is Boundary.TWO_SIDED else "1s"
