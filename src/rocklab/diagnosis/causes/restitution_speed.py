"""The impact law as a flexible function of the impact speed (a family of the impact law, issue 12).

e / e_an = g(thetadot^- / thetadot_r), g piecewise linear between its values
at the knots x = 0, 1/3, 2/3, 1 (flat beyond): a form that no closed form
dictates, fitted where the scale and Eq. 17 leave the impact law's
structure.  The closed forms it holds as members (:func:`closed_form`
says which one the intervals of the fitted values hold): a constant
(:mod:`restitution_scale`), Eq. 17 (:mod:`restitution_amplitude`), a law
affine in the speed, a threshold below which the impact stops the wall
(the law of :mod:`stop_threshold`).  Its law
(:class:`rocklab.physics.law.SpeedFactor`) acts after the base law; the
exact simulator's reference integrator carries it, the maps' engines do not.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from rocklab._imports import lazy_module
from rocklab.diagnosis.causes import Cause, Signature, restitution_amplitude, restitution_scale
from rocklab.diagnosis.parameters import Param
from rocklab.physics.law import KNOTS, SpeedFactor

if TYPE_CHECKING:
    from rocklab.diagnosis.evidence import Observed

stats = lazy_module("scipy.stats")

G = tuple(Param(f"g{j}", 0.0, 2.5, 1.0, practical=0.01) for j in range(KNOTS.size))
NAMES = [q.name for q in G]


def laws(v: Mapping[str, float]) -> tuple[SpeedFactor]:
    return (SpeedFactor(tuple(v[n] for n in NAMES)),)


def _binned(ob: Observed) -> tuple[list[float], list[float], float] | None:
    """Medians of the measured e/e_an in thirds of the range of the impact speed, and their test."""
    e, x = ob.ratio[ob.ok], ob.vr[ob.ok]
    if e.size < 9:
        return None
    edges = np.percentile(x, [0, 100 / 3, 200 / 3, 100])
    groups = [e[(x >= lo) & (x <= hi)] for lo, hi in zip(edges[:-1], edges[1:])]
    if min(g.size for g in groups) < 3:
        return None
    centres = [float(np.median(x[(x >= lo) & (x <= hi)])) for lo, hi in zip(edges[:-1], edges[1:])]
    return centres, [float(np.median(g)) for g in groups], stats.kruskal(*groups).pvalue


def signature(ob: Observed) -> Signature | None:
    """The measured e/e_an in thirds of the impact speed: a law that changes with the speed."""
    b = _binned(ob)
    if b is None:
        return None
    centres, med, p = b
    spread = max(med) - min(med)
    assert G[0].practical is not None
    return {
        "value": med,
        "at": centres,
        "supports": bool(p < 0.01 and spread > G[0].practical),
        "text": "e/e_an by thirds of the impact speed: "
        + ", ".join(f"{m:.3f} at {c:.2f} thetadot_r" for m, c in zip(med, centres))
        + f" (Kruskal-Wallis p = {p:.2g})",
    }


def starts(sig: Mapping[str, Signature]) -> dict[str, float]:
    s = sig.get(CAUSE.name)
    if not s:
        return {}
    g = np.interp(KNOTS, s["at"], s["value"])
    return dict(zip(NAMES, map(float, g)))


def _holds(ci: Mapping[str, Sequence[float]], curve: Iterable[float]) -> bool:
    return all(CAUSE.holds(ci, n, float(c)) for n, c in zip(NAMES, curve) if n in ci)


def closed_form(values: Mapping[str, float], ci: Mapping[str, Sequence[float]]) -> str:
    """The first closed form whose curve at the knots every interval holds (weighted by the inverse widths)."""
    g = np.array([values[n] for n in NAMES])
    w = np.array([1.0 / max(ci[n][1] - ci[n][0], 1e-9) ** 2 if n in ci else 0.0 for n in NAMES])

    def fit(basis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        coef = np.linalg.lstsq(basis * np.sqrt(w)[:, None], g * np.sqrt(w), rcond=None)[0]
        return coef, basis @ coef

    one = np.ones_like(KNOTS)
    (c,), curve = fit(one[:, None])
    if _holds(ci, curve):
        return f"restitution_scale: e = c e_an, c = {c:.3f}"
    (a, mb), curve = fit(np.c_[one, KNOTS**2])
    if _holds(ci, curve):
        return f"restitution_amplitude: e/e_an = a - b (thetadot^-/thetadot_r)^2 (Eq. 17), a = {a:.3f}, b = {-mb:.3f}"
    (a, s), curve = fit(np.c_[one, KNOTS])
    if _holds(ci, curve):
        return f"affine in the speed: e/e_an = {a:.3f} {s:+.3f} thetadot^-/thetadot_r (no cause of the library)"
    for j in range(1, KNOTS.size):
        # a threshold: no rebound below a knot, a constant above (the law of stop_threshold)
        above = np.r_[np.zeros(j), np.ones(KNOTS.size - j)]
        (c,), curve = fit(above[:, None])
        if _holds(ci, curve):
            return f"stop_threshold-like: e = 0 below {KNOTS[j - 1]:.2f}-{KNOTS[j]:.2f} thetadot_r, {c:.3f} e_an above"
    return "no closed form of the library"


CAUSE = Cause(
    name="restitution_speed",
    law="e/e_an = g(thetadot^-/thetadot_r), piecewise linear at 0, 1/3, 2/3, 1 (a flexible law of the impact speed)",
    params=G,
    laws=laws,
    signature=signature,
    starts=starts,
    replaces=(restitution_scale.CAUSE.name, restitution_amplitude.CAUSE.name),
    family=restitution_amplitude.CAUSE.name,
    closed_form=closed_form,
    on_the_maps=(None, "a flexible impact law the calibrated walls do not carry (the engine could: issue 42)"),
)
