"""Restitution of free-rocking blocks from measured impact-by-impact velocity ratios.

The restitution part of :mod:`rocklab.diagnosis` on data that hold only
the ratio r_k = thetadot^+_k / thetadot^-_k of every impact k of every trial
(the same causes of :mod:`rocklab.diagnosis.catalogue` and the same engine,
:mod:`rocklab.diagnosis.estimation`):
the UMinho limestone blocks (Colombo et al., DOI 10.60756/uminho-jh25, CC BY
4.0; shipped in ``rocklab/data/uminho-limestone-free-rocking``), 134 trials on 12
slendernesses H/B = 4-15.  Base model: Housner's e_an = 1 - 3/2 sin^2 alpha
(Eq. 2), alpha = arctan(B/H).  Candidate causes, per block group (the trials
of one H/B):

``restitution_scale``     e = c e_an
``restitution_amplitude`` e/e_an = a - b' (thetadot^-_k / thetadot^-_1)^2: Eq. 17
                          with the impact speed relative to the first impact's
                          (the release angle is not in the tables), so
                          b' = b (thetadot^-_1 / thetadot_r)^2
``hinge_asymmetry``       e exp(+-s_e/2) on odd and even impacts: the two base
                          edges in turn (every trial taken as released to the
                          same side)

and, where these leave structure and the trials span several slendernesses
(all groups pooled, the block group the unit of the folds and resamples,
:func:`by_group`), the generalised family
:mod:`rocklab.diagnosis.causes.restitution_housner_loss`: e = 1 - lambda
(1 - e_an) - delta, Housner's loss scaled plus a constant loss per impact
(issue 12).

The speed before impact k relative to the first is the product of the
measured ratios before it (a rigid block lands at the speed it took off
with).  Velocity ratios above 1 or below 0 and late impacts are artefacts of
the processing at small amplitudes (SOURCE.md): the diagnosis uses the first
:data:`N_IMPACTS` impacts with 0 < r < :data:`R_MAX`, and a noise that grows
as the impact speed falls (:func:`rocklab.diagnosis.estimation.noise.noise_variance`).
"""

from __future__ import annotations

import os
from collections.abc import Collection, Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, cast

import numpy as np
import pandas as pd

from rocklab.data import LIMESTONE
from rocklab.diagnosis import catalogue
from rocklab.diagnosis.causes import Cause, Signature, restitution_housner_loss
from rocklab.diagnosis.discovery import discovery, family_against_listed
from rocklab.diagnosis.estimation import Problem, beyond_the_catalogue, select_effects
from rocklab.diagnosis.estimation.resampling import heldout_gain, heldout_means
from rocklab.diagnosis.estimation.selection import sentence_of, sentences
from rocklab.diagnosis.estimation.systematic import verdict_intervals
from rocklab.diagnosis.result import BlockDiagnosis, Finding, LimestoneDiagnosis
from rocklab.physics import restitution
from rocklab.physics.boundary import Boundary
from rocklab.physics.impact import bounded_factor
from rocklab.physics.law import Amplitude, HousnerLoss, Restitution

if TYPE_CHECKING:
    from rocklab.diagnosis.estimation.fitting import Fits
    from rocklab.diagnosis.parameters import Param
    from rocklab.diagnosis.result import Number

#: Impacts per trial used (later ones are dominated by the processing noise).
N_IMPACTS = 10

#: Measured ratios at or above this are artefacts (SOURCE.md: up to 28.9).
R_MAX = 1.5

#: Folder of the tables, with their provenance (package data, :mod:`rocklab.data`).
TABLES = LIMESTONE

#: The laws the ratios of the impacts tell: the listed causes that act through them alone are the
#: candidates (:func:`candidates`); the rotations, which the tables lack, are not modelled.
IMPACT_LAWS = (HousnerLoss, Restitution, Amplitude)


def candidates() -> tuple[Cause, ...]:
    """The listed causes of two-sided walls whose laws change e (:data:`IMPACT_LAWS`), in catalogue
    order: each changes the ratios of the impacts; a law of the rotations they also have (an angle)
    is not fitted."""
    null = catalogue.null_values()
    return tuple(
        c
        for c in catalogue.for_boundary(Boundary.TWO_SIDED)
        if any(isinstance(law, IMPACT_LAWS) for law in c.laws(c.values(null)))
    )


def read_events(path: str | os.PathLike[str] = TABLES / "limestone-rocking-events.csv") -> pd.DataFrame:
    """Per-impact table of the non-duplicate trials (``limestone-rocking-events.csv``)."""
    ev = pd.read_csv(path)
    ev = ev[ev.duplicate_of.isna()].copy()
    ev["alpha"] = np.arctan2(ev.B_m, ev.H_m)
    return ev.sort_values(["group", "trial", "event"])


@dataclass
class _Trials:
    """Trials as padded (rows, impacts) arrays: a row is a trial, or a block group (:func:`by_group`)."""

    ids: list[str]
    alpha: np.ndarray
    r: np.ndarray  # measured ratio, NaN where unused
    u: np.ndarray  # (thetadot^-_k / thetadot^-_1)^2
    odd: np.ndarray  # impact leaves the release edge
    group: np.ndarray  # block group of each row

    @property
    def ratio(self) -> np.ndarray:
        """r / e_an of every impact, Housner's e_an of Eq. 2 [-]."""
        return self.r / restitution.two_sided(self.alpha)[:, None]

    def subset(self, idx: np.ndarray) -> _Trials:
        return replace(
            self,
            ids=[self.ids[i] for i in idx],
            alpha=self.alpha[idx],
            r=self.r[idx],
            u=self.u[idx],
            odd=self.odd[idx],
            group=self.group[idx],
        )


def pooled(groups: Mapping[int, _Trials]) -> _Trials:
    """All groups' trials as one :class:`_Trials` (a calibration common to every slenderness)."""
    gs = list(groups.values())
    return _Trials(
        ids=[i for g in gs for i in g.ids],
        alpha=np.concatenate([g.alpha for g in gs]),
        r=np.vstack([g.r for g in gs]),
        u=np.vstack([g.u for g in gs]),
        odd=np.vstack([g.odd for g in gs]),
        group=np.concatenate([g.group for g in gs]),
    )


def by_group(trials: _Trials) -> _Trials:
    """The trials with one row per block group: its trials' impacts side by side (:data:`N_IMPACTS` each).

    Slenderness is a property of the block group (:data:`rocklab.lab.hierarchy.BLOCK_COVARIATE_LEVEL`):
    where the trials span several, the engine's folds leave out, and its bootstrap draws, whole groups,
    and a law that varies with slenderness is judged on as many units as there are groups.
    """
    groups = np.unique(trials.group)
    rows = [np.flatnonzero(trials.group == g) for g in groups]
    width = max(len(i) for i in rows) * N_IMPACTS

    def side_by_side(x: np.ndarray, fill: float) -> np.ndarray:
        out = np.full((len(groups), width), fill, dtype=x.dtype)
        for j, i in enumerate(rows):
            out[j, : len(i) * N_IMPACTS] = x[i].ravel()
        return out

    return _Trials(
        ids=[str(g) for g in groups],
        alpha=np.array([trials.alpha[i[0]] for i in rows]),
        r=side_by_side(trials.r, np.nan),
        u=side_by_side(trials.u, 1.0),
        odd=side_by_side(trials.odd, False),
        group=groups,
    )


def group_trials(events: pd.DataFrame) -> dict[int, _Trials]:
    """One :class:`_Trials` per block group."""
    out = {}
    for g, ev in events.groupby("group"):
        trials = list(ev.groupby("trial"))
        r = np.full((len(trials), N_IMPACTS), np.nan)
        for i, (_, t) in enumerate(trials):
            x = t.measured_source_angular_ratio.to_numpy(float)[:N_IMPACTS]
            r[i, : x.size] = x
        bad = ~((r > 0) & (r < R_MAX))
        # speed before impact k over the first: the product of the ratios before it (artefacts as 1)
        step = np.where(bad, 1.0, np.nan_to_num(r, nan=1.0))
        u = np.c_[np.ones(len(trials)), np.cumprod(step, axis=1)[:, :-1]] ** 2
        out[int(g)] = _Trials(
            ids=[f"{g}-{k}" for k, _ in trials],
            alpha=np.full(len(trials), ev.alpha.iloc[0]),
            r=np.where(bad, np.nan, r),
            u=u,
            odd=np.tile(np.arange(1, N_IMPACTS + 1) % 2 == 1, (len(trials), 1)),
            group=np.full(len(trials), int(g)),
        )
    return out


class BlockProblem(Problem[_Trials]):
    """The trials of one block group as a :class:`rocklab.diagnosis.estimation.problem.Problem` (impact group only)."""

    def __init__(self, trials: _Trials) -> None:
        self.T = trials
        self.n_tests = len(trials.ids)
        self.causes = candidates()
        # the base e of Housner's loss acts at its null where it is no candidate
        self._acting = (restitution_housner_loss.CAUSE, *self.causes)
        if np.ptp(trials.alpha) > 0:
            # Housner's loss and a constant loss are told apart only across slendernesses
            self.causes += (restitution_housner_loss.CAUSE,)

    def subset(self, idx: np.ndarray) -> _Trials:
        return self.T.subset(np.asarray(idx))

    def model_e(self, sub: _Trials, values: Mapping[str, float]) -> np.ndarray:
        """e of every impact: the laws of the causes (at their null where not in ``values``) on
        Housner's e, the base e first, then the factors on the edge being left (odd impacts leave
        the release edge), then Eq. 17 in the speed relative to the first impact's."""
        v = catalogue.null_values()
        v.update(values)
        laws = [law for c in self._acting for law in c.laws(c.values(v))]
        e = restitution.two_sided(sub.alpha)[:, None]
        for law in laws:
            if isinstance(law, HousnerLoss):
                e = law.restitution(e)
        for law in laws:
            if isinstance(law, Restitution):
                e = e * bounded_factor(e, law.on_impacts(sub.odd))
        for law in laws:
            if isinstance(law, Amplitude):
                e = e * bounded_factor(e, law.a - law.b * sub.u)
        return e

    def residuals(self, sub: _Trials, ext: Collection[str], values: Mapping[str, float]) -> dict[str, np.ndarray]:
        with np.errstate(invalid="ignore", divide="ignore"):
            return {"impact": np.log(self.model_e(sub, values) / sub.r)}

    def noise(self, sub: _Trials) -> dict[str, np.ndarray]:
        return {"impact": 1.0 / np.sqrt(sub.u)}

    def resolution(self, x: np.ndarray) -> float:
        # the noise covariate is a relative speed, not a resolution: significance decides
        return 0.0

    def covariates(self, sub: _Trials) -> dict[str, dict[str, np.ndarray]]:
        k = np.tile(np.arange(1.0, N_IMPACTS + 1), (len(sub.ids), sub.r.shape[1] // N_IMPACTS))
        return {
            "impact": {
                "impact index": k,
                "amplitude": np.log(sub.u),
                "slenderness (B/H)^2": np.tan(sub.alpha)[:, None] ** 2,
            }
        }

    def params(self, ext: Collection[str]) -> list[Param]:
        # no rotations in the tables: the asymmetry is that of e only
        return [q for q in super().params(ext) if q.name != "s_alpha"]

    def starts(self, ext: Collection[str]) -> dict[str, float]:
        ratio = self.T.ratio
        med = float(np.nanmedian(ratio))
        return {"c": med, "a": med}

    def heldout_measures(
        self, sub: _Trials, ext: Collection[str], values: Mapping[str, float]
    ) -> dict[str, np.ndarray]:
        R = self.residuals(sub, ext, values)["impact"]
        # the impact speed after n impacts relative to the first: the product of the ratios, trial by trial
        trials = R.reshape(len(R), -1, N_IMPACTS)
        decay = np.nancumsum(trials, axis=2)
        # a group's padding is no trial
        decay[~np.isfinite(trials).any(axis=2)] = np.nan
        decay = decay.reshape(R.shape)
        with np.errstate(invalid="ignore"):
            return {"ratio_rms": np.sqrt(np.nanmean(R**2, axis=1)), "decay_rms": np.sqrt(np.nanmean(decay**2, axis=1))}


def signatures(trials: _Trials) -> dict[str, Signature]:
    """Evidence in the ratios that needs no fit: each cause's own (its ``on_ratios``), Housner's loss
    across slendernesses first."""
    out = {}
    for cause in (restitution_housner_loss.CAUSE, *candidates()):
        s = cause.on_ratios(trials) if cause.on_ratios is not None else None
        if s is not None:
            out[cause.name] = s
    return out


def diagnose_group(trials: _Trials, *, n_boot: int = 40, seed: int = 0) -> BlockDiagnosis:
    """Diagnosis of one block group (or of all, pooled): what Housner's e gets wrong, the causes, the gain."""
    several = np.ptp(trials.alpha) > 0
    problem = BlockProblem(by_group(trials) if several else trials)
    sig = signatures(trials)
    fits: Fits = {}
    sel = select_effects(problem, signature=sig, n_boot=n_boot, seed=seed, fits=fits)
    sel = beyond_the_catalogue(problem, sel, signature=sig, n_boot=n_boot, seed=seed, fits=fits)
    e_an = float(np.median(restitution.two_sided(trials.alpha)))
    measured = float(np.nanmedian(trials.r))
    base_ho, final_ho = sel["base"], sel["final"]
    n = np.isfinite(trials.r).sum(axis=1)
    decay_meas = float(np.median(np.exp(np.nansum(np.log(trials.r), axis=1) / np.maximum(n, 1))))
    findings = []
    for eff in sel["effects"]:
        own = [q.name for q in problem.params((eff,))]
        st = sel["steps"][eff]
        findings.append(
            Finding(
                effect=eff,
                params={k: sel["fit"].values[k] for k in own},
                ci95={k: cast("list[Number]", sel["ci"][k]) for k in own if k in sel["ci"]},
                u_systematic={k: sel["ci"].u_sys[k] for k in own if k in sel["ci"].u_sys},
                n_tests=len(trials.ids),
                evidence={
                    "signature": sig[eff]["text"],
                    "fit": f"held-out deviance per impact lowered by {st['gain']:.3g} (standard error "
                    f"{st['se']:.2g}), dBIC = {st['dbic']:.1f}",
                },
                error_heldout=heldout_means(st["heldout"]),
                gain=heldout_gain(base_ho, st["heldout"], st["gain"]),
                **discovery(problem, eff, sel),
            )
        )
    params = {q.name: q for q in problem.params(tuple(sel["effects"]))}
    verdict_intervals(findings, params, dict.fromkeys(sel["effects"], problem.n_tests))
    hb = 1.0 / np.tan(trials.alpha)
    one = np.ptp(hb) == 0
    families = [c for c in problem.candidates(True) if c not in problem.candidates()]
    return BlockDiagnosis(
        scope="block group" if one else "all blocks",
        key=f"H/B = {hb[0]:.0f}" if one else f"H/B = {hb.min():.0f}-{hb.max():.0f}",
        h_over_b=float(hb[0]) if one else None,
        n_tests=len(trials.ids),
        n_impacts=int(np.isfinite(trials.r).sum()),
        base={
            "model": "Housner e_an = 1 - 3/2 sin^2 alpha (Eq. 2)",
            "e_an": e_an,
            "measured_median_ratio": measured,
            "measured_geometric_mean_ratio": decay_meas,
        },
        what_is_wrong=(
            f"Housner's e is {e_an:.3f} where the measured ratios have median {measured:.3f} and "
            f"geometric mean {decay_meas:.3f} over the first {N_IMPACTS} impacts: the impact speed "
            f"after {N_IMPACTS} impacts is {100 * e_an**N_IMPACTS:.0f}% of the first in the model, "
            f"{100 * decay_meas**N_IMPACTS:.0f}% measured"
        ),
        verdict=list(sel["effects"]),
        listed_verdict=sel["catalogue"]["effects"] if "catalogue" in sel else None,
        unexplained=bool(sel["structure"]) and not sel["weak"],
        residual_structure=sel["structure"],
        findings=findings,
        weak_evidence={
            k: {"params": cast("dict[str, Number]", v["params"]), "reason": sentence_of(v["reason"])}
            for k, v in sel["weak"].items()
        },
        rejected=sentences(sel["rejected"]),
        signatures={k: v["text"] for k, v in sig.items()},
        heldout={"base": heldout_means(base_ho), "model": heldout_means(final_ho)},
        # the families of the impact law, named or not: what a form outside the catalogue gives
        families=[family_against_listed(problem, f, sel, n_boot=n_boot, seed=seed, fits=fits) for f in families],
    )


def diagnose_blocks(events: pd.DataFrame | None = None, *, n_boot: int = 40, seed: int = 0) -> LimestoneDiagnosis:
    """Diagnose every block group of the limestone tables."""
    events = read_events() if events is None else events
    groups = group_trials(events)
    entries = [diagnose_group(t, n_boot=n_boot, seed=seed) for t in groups.values()]
    every = pooled(groups)
    return LimestoneDiagnosis(
        all=diagnose_group(every, n_boot=n_boot, seed=seed),
        groups=entries,
        slenderness=restitution_housner_loss.slenderness_trend(every),
        source="Colombo et al., UMinho free-rocking limestone blocks, DOI 10.60756/uminho-jh25 (CC BY 4.0)",
    )


def blocks_markdown(result: LimestoneDiagnosis) -> str:
    """Readable report of :func:`diagnose_blocks`."""
    a = result.all
    structure = "; ".join(map(str, a.residual_structure))
    out = [
        "# Restitution of the UMinho limestone blocks",
        "",
        f"Data: {result.source}.",
        "",
        f"All {a.n_tests} trials ({a.n_impacts} impacts), one calibration for every slenderness: "
        f"verdict **{', '.join(a.verdict) or 'none'}**"
        + "".join(
            f"; {f.effect}: "
            + ", ".join(
                f"{k} = {v:.4g} [{f.ci95[k][0]:.4g}, {f.ci95[k][1]:.4g}]" for k, v in f.params.items() if k in f.ci95
            )
            for f in a.findings
        )
        + f"; held-out ratio rms {a.heldout['base']['ratio_rms']:.4f} → {a.heldout['model']['ratio_rms']:.4f}"
        + (f"; **unexplained**: {structure}" if a.unexplained else "")
        + "".join(
            f"; structure remains ({structure}) that {k} "
            f"({', '.join(f'{n} = {x:.4g}' for n, x in w['params'].items())}) would remove, short of the "
            f"evidence to name it ({w['reason']})"
            for k, w in a.weak_evidence.items()
        )
        + ".",
        "",
        "| H/B | trials | e_an | measured r (median) | verdict | parameters [95% CI] "
        "| held-out ratio rms base → model | unexplained |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for e in result.groups:
        pars = "; ".join(
            f"{k} = {v:.4g} [{f.ci95[k][0]:.4g}, {f.ci95[k][1]:.4g}]"
            for f in e.findings
            for k, v in f.params.items()
            if k in f.ci95
        )
        h = e.heldout
        out.append(
            f"| {e.h_over_b:.0f} | {e.n_tests} | {e.base['e_an']:.3f} | "
            f"{e.base['measured_median_ratio']:.3f} | {', '.join(e.verdict) or 'none'} | {pars} | "
            f"{h['base']['ratio_rms']:.4f} → {h['model']['ratio_rms']:.4f} | "
            f"{'; '.join(map(str, e.residual_structure)) if e.unexplained else 'no'}"
            f"{' (weak: ' + ', '.join(e.weak_evidence) + ')' if e.weak_evidence else ''} |"
        )
    for fam in a.families:
        g, ci = fam.heldout_gain, fam.ci95
        out += [
            "",
            f"Beyond the catalogue, {fam.effect} ({fam.form}): "
            + ", ".join(f"{k} = {v:.4g} [{ci[k][0]:.4g}, {ci[k][1]:.4g}]" for k, v in fam.params.items())
            + f"; {fam.reduces_to}; dBIC {fam.dbic_vs_base:+.1f} against Housner's e, "
            f"{fam.dbic_vs_best_listed:+.1f} against the best listed cause ({fam.best_listed}); held-out "
            f"deviance gain per impact {g['vs_base']:.3g} (standard error {g['vs_base_se']:.2g}) against Housner's e, "
            f"{g['vs_best_listed']:.3g} ({g['vs_best_listed_se']:.2g}) against {fam.best_listed}: "
            + ("**discovered**." if fam.discovered else "not named (weak evidence at most)."),
        ]
    st = result.slenderness
    out += [
        "",
        f"Mean over the trials of each block group of their median r/e_an against (B/H)^2 (the variable of "
        f"Eq. 2), the {st['n_groups']} groups the units: {st['intercept']:.4f} {st['slope']:+.2f} "
        f"(+-{st['slope_se']:.2f}) (B/H)^2, p = {st['p']:.2g}; level by H/B: "
        + ", ".join(f"{k}: {v:.3f}" for k, v in st["levels"].items())
        + ".",
    ]
    out += [""] + [f"- H/B = {e.h_over_b:.0f}: {e.what_is_wrong}." for e in result.groups]
    return "\n".join(out) + "\n"
