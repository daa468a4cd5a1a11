"""Free-rocking tests of one series as a :class:`rocklab.diagnosis.estimation.problem.Problem`."""

from __future__ import annotations

from collections.abc import Collection, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from rocklab.diagnosis import catalogue
from rocklab.diagnosis.causes import Signature, Stage
from rocklab.diagnosis.estimation import Problem
from rocklab.diagnosis.evidence import MeasuredTest, TestStack, covariates, log_ratio, noise_covariates, residuals
from rocklab.diagnosis.extended import model_params
from rocklab.diagnosis.result import Structure
from rocklab.diagnosis.wall_model import ModelParams, base_params, branches, free_run, log_columns, stacked

if TYPE_CHECKING:
    from rocklab.diagnosis.causes import Unexplained


class WallProblem(Problem[TestStack]):
    """The tests of one boundary condition (a series), the causes of the catalogue that can occur in it."""

    def __init__(self, tests: Iterable[MeasuredTest]) -> None:
        self.tests = list(tests)
        self.n_tests = len(self.tests)
        self.S = TestStack.of(self.tests)
        self.boundary = self.tests[0].boundary
        self.causes = tuple(catalogue.for_boundary(self.boundary, families=True, columns=log_columns(self.tests)))
        self.after_selection = tuple(catalogue.for_boundary(self.boundary, Stage.AFTER_SELECTION))
        self._sig: dict[str, Signature] | None = None
        # what a model of the whole series leaves for the causes estimated after selection, by model
        self._left: dict[tuple[tuple[str, ...], tuple[tuple[str, float], ...]], dict[str, list[Structure]]] = {}
        # what residuals() keeps between calls: the base model of a subset, and evidence.residuals' own
        self._cache: dict[str, Any] = {}

    def subset(self, idx: np.ndarray) -> TestStack:
        return self.S.subset(np.asarray(idx))

    def residuals(self, sub: TestStack, ext: Collection[str], values: Mapping[str, float]) -> dict[str, np.ndarray]:
        return residuals(sub, model_params(sub.tests, ext, values, self._base(sub)), self._cache)

    def _base(self, sub: TestStack) -> ModelParams:
        # a fit evaluates one subset many times: its base model is made once
        if self._cache.get("base_of") is not sub:
            self._cache.update(base_of=sub, base=base_params(sub.tests))
        return cast("ModelParams", self._cache["base"])

    def residuals_at(
        self, sub: TestStack, ext: Collection[str], values: Sequence[Mapping[str, float]]
    ) -> list[dict[str, np.ndarray]]:
        """:meth:`residuals` at each of ``values``, equal to them bit for bit: the models that take the
        same branches of the closed forms (:func:`branches`) evaluated as one, stacked on the tests
        repeated (:func:`rocklab.diagnosis.wall_model.stacked`), the fixed cost of an evaluation (some
        hundred small array operations) paid once a branch."""
        models = [model_params(sub.tests, ext, v, self._base(sub)) for v in values]
        together: dict[tuple[bool, ...], list[int]] = {}
        for i, mp in enumerate(models):
            together.setdefault(branches(mp), []).append(i)
        out: list[dict[str, np.ndarray]] = [{} for _ in models]
        n = len(sub.tests)
        for same in together.values():
            if len(same) == 1:
                out[same[0]] = residuals(sub, models[same[0]], self._cache)
                continue
            # the repeated tests and evidence.residuals' cache of them, kept while the subset lasts
            tiled = self._cache.setdefault("tiled", {})
            if tiled.get("of") is not sub:
                tiled.clear()
                tiled["of"] = sub
            if len(same) not in tiled:
                tiled[len(same)] = (sub.subset(np.tile(np.arange(n), len(same))), {})
            S, cache = tiled[len(same)]
            R = residuals(S, stacked([models[i] for i in same]), cache)
            for j, i in enumerate(same):
                out[i] = {g: r[j * n : (j + 1) * n] for g, r in R.items()}
        return out

    def covariates(self, sub: TestStack) -> dict[str, dict[str, np.ndarray]]:
        return covariates(sub)

    def noise(self, sub: TestStack) -> dict[str, np.ndarray]:
        return noise_covariates(sub)

    def extra_structure(self, sub: TestStack, ext: Collection[str], values: Mapping[str, float]) -> list[Structure]:
        """What the model leaves that the causes estimated after selection would explain."""
        if len(sub.tests) == self.n_tests and all(a is b for a, b in zip(sub.tests, self.tests)):
            return [st for left in self.left_for(ext, values).values() for st in left]
        mp = model_params(sub.tests, ext, values)
        # every cause estimated after selection says what it would explain (Cause.unexplained)
        return [st for cause in self.after_selection for st in cast("Unexplained", cause.unexplained)(sub, mp)]

    def left_for(self, ext: Collection[str], values: Mapping[str, float]) -> dict[str, list[Structure]]:
        """Cause estimated after selection -> what the model ``ext`` at ``values`` leaves in the whole series
        that it would explain (:attr:`~rocklab.diagnosis.causes.Cause.unexplained`).

        Made once a model: the selection's structure tests, the search beyond the catalogue and the
        estimation after selection (:func:`rocklab.diagnosis.series.diagnose_series`) all ask it of the
        chosen model, and the stop's reading of every test's end of motion is a costly part of it.
        """
        key = (tuple(ext), tuple(sorted(values.items())))
        if key not in self._left:
            mp = model_params(self.tests, ext, values)
            self._left[key] = {c.name: cast("Unexplained", c.unexplained)(self.S, mp) for c in self.after_selection}
        return self._left[key]

    def form_structure(self, ext: Collection[str]) -> list[Structure]:
        """What a family's signature says the model ``ext`` misses: its listed member of the wrong
        form (``against_member``), or no member at all (``unmodelled``); the flight-loss curve of
        :mod:`rocklab.diagnosis.causes.flight_loss`.  A named member whose form only its family's
        signature checks (:attr:`~rocklab.diagnosis.causes.Cause.checks_form`) and that signature
        unreadable: its form is untested."""
        out = []
        for c in self.causes:
            sig = self.signature.get(c.name) or {}
            if c.family in ext and sig.get("against_member"):
                out.append(Structure(c.name, sig["against_member"]))
            elif c.family in ext and c.checks_form and (not sig or sig.get("not_identifiable")):
                assert c.family is not None
                out.append(
                    Structure(
                        c.family,
                        f"{c.family}: its form is untested, the signature of {c.name} cannot be read in these tests",
                    )
                )
            elif c.family and not {c.name, c.family} & set(ext) and sig.get("unmodelled"):
                out.append(Structure(c.name, sig["unmodelled"]))
        return out

    @property
    def signature(self) -> dict[str, Signature]:
        """The causes' signatures in these tests (:func:`rocklab.diagnosis.catalogue.signatures`)."""
        if self._sig is None:
            self._sig = catalogue.signatures(self.tests)
        return self._sig

    def starts(self, ext: Collection[str]) -> dict[str, float]:
        return catalogue.starts(self.signature)

    def heldout_measures(
        self, sub: TestStack, ext: Collection[str], values: Mapping[str, float]
    ) -> dict[str, np.ndarray]:
        mp = model_params(sub.tests, ext, values)
        run = free_run(sub, mp, n_max=sub.A.shape[1])
        R = residuals(sub, mp)
        M = run["peaks"][:, : sub.A.shape[1]]
        F = log_ratio(M, sub.A[:, : M.shape[1]], sub.floor[:, None])
        rms = lambda x: np.sqrt(np.nanmean(x**2, axis=1))  # noqa: E731
        with np.errstate(invalid="ignore"):
            return {
                "free_run_log_peak_rms": rms(F),
                "impact_rms": rms(R["impact"]),
                "time_rms": rms(R["time"]) if np.isfinite(R["time"]).any() else np.full(len(sub.tests), np.nan),
                "peak_rms": rms(R["peak"]),
            }
