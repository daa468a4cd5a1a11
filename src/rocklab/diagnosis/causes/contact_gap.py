"""A gap behind a one-sided wall: it swings inwards through g = gamma alpha (Fig. 12).

Two-sided rocking on the inner hinge, Eq. 2 at the base, Eqs. 12-13 on the
transverse walls (:func:`rocklab.diagnosis.wall_model.impact_speeds`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from rocklab.diagnosis.causes import Cause, Signature
from rocklab.diagnosis.parameters import Param
from rocklab.physics.boundary import Boundary
from rocklab.physics.law import Gap

if TYPE_CHECKING:
    from rocklab.diagnosis.evidence import Observed

GAMMA = Param("gap_over_alpha", 0.0, 0.3, 0.0, practical=0.002)


def laws(v: Mapping[str, float]) -> tuple[Gap]:
    return (Gap(v["gap_over_alpha"]),)


def signature(ob: Observed) -> Signature:
    """The negative rotations: excursions past theta = 0 above the noise threshold."""
    S = ob.S
    d = S.depth[np.isfinite(S.depth)]
    f = np.broadcast_to(S.floor[:, None], S.depth.shape)[np.isfinite(S.depth)]
    seen = d > f
    med = float(np.median((S.depth / ob.alpha)[np.isfinite(S.depth)][seen])) if seen.any() else 0.0
    return {
        "value": med,
        "supports": bool(seen.size and seen.mean() >= 0.25),
        "text": f"{int(seen.sum())} of {d.size} impacts with negative rotations (median depth {med:.4f} alpha)",
    }


def starts(sig: Mapping[str, Signature]) -> dict[str, float]:
    return {"gap_over_alpha": max(sig.get(CAUSE.name, {}).get("value", 0.0), 1e-3)}


CAUSE = Cause(
    name="contact_gap",
    law="one-sided: the wall swings inwards through a gap g = gamma alpha",
    params=(GAMMA,),
    laws=laws,
    boundaries=(Boundary.ONE_SIDED,),
    signature=signature,
    starts=starts,
    short="gap",
)
