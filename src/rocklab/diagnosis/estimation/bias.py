"""The bias of a fit's model, measured on data simulated at the fit.

A problem's residuals read its tests through a model of the measurement
(for a wall, closed forms of its flights and of the derivative filter's
bias, :mod:`rocklab.diagnosis.evidence`), whose approximations every test
shares and every residual group may see alike: neither the resampling of
tests (:mod:`~rocklab.diagnosis.estimation.resampling`) nor the pulls of the
groups (:mod:`~rocklab.diagnosis.estimation.systematic`) see such an error.
Its size at a fit is measured where the truth is known: the problem's
tests simulated under the fitted model by a simulator independent of the
residuals' closed forms, through the measurement chain, with the measured
noise (the caller makes ``simulated``: for a wall,
:func:`rocklab.diagnosis.extended.simulated_tests`), and fitted again with
the same causes from the fit.  The difference b = x* - x_hat is the model's
bias at x_hat plus the error of one noise realisation, of variance se^2
(the cluster-robust sandwich of the refit,
:func:`~rocklab.diagnosis.estimation.resampling.sandwich_errors`), so
E[b^2] = bias^2 + se^2.  One draw leaves b^2 - se^2 a single degree of
freedom: where the bias is one standard error, it is below zero about half
the time (issue 41).  The tests are therefore simulated in R draws
(:data:`BIAS_DRAWS`), each with its own noise, and

    u_model = sqrt(max(mean over draws of b_r^2 - mean of se_r^2, 0))

estimates the bias without the noise (the statistical part is not counted
twice), a standard uncertainty on R degrees of freedom (the mean of R
squares: where the bias is nothing it is a chi-square on R) added to the
interval with the pulls by Welch-Satterthwaite
(:func:`~rocklab.diagnosis.estimation.systematic.widened`): a parametric
bootstrap of R draws, for the bias, not the spread (Efron & Tibshirani
1993, Sect. 10.6).  The bias quoted is the mean of the b_r.  No constant is
set on a benchmark: the simulator is the reference.  What it cannot see:
an error the simulator and the residuals' model share (the rigid-body wall
both assume), the chain before the measured rotation (the transducers'
kinematics), noise that is not white; R = 3 degrees of freedom still give
t = 3.18 at 95 % where the model's part dominates.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from rocklab.diagnosis.estimation.fitting import Fit, fit, linearised
from rocklab.diagnosis.estimation.problem import Problem
from rocklab.diagnosis.estimation.resampling import sandwich_errors

log = logging.getLogger(__name__)


#: Draws of simulated tests the bias is measured on.  Three give u_model three degrees of freedom (t = 3.18
#: at 95 %, against 12.7 for one) at the cost of three refits; the caller splits its simulated tests between
#: the draws (rocklab.diagnosis.series.MAX_BIAS_TESTS), so the simulation costs what one draw did.
BIAS_DRAWS = 3


def net_of_noise(b: npt.ArrayLike, se: npt.ArrayLike) -> np.ndarray:
    """The bias differences ``b`` of R draws of standard errors ``se`` carry, (R, ...) each:
    sqrt(max(mean b^2 - mean se^2, 0)) over the draws (E[b^2] = bias^2 + se^2); none where an ``se`` is
    infinite (a direction the tests do not fix)."""
    b, se = np.atleast_1d(np.asarray(b, float)), np.atleast_1d(np.asarray(se, float))
    se = np.where(np.isfinite(se), se, np.abs(b))
    return np.sqrt(np.maximum(np.mean(b**2, axis=0) - np.mean(se**2, axis=0), 0.0))


def model_bias(simulated: Sequence[Problem[Any]], fitted: Fit) -> tuple[dict[str, float], dict[str, float]]:
    """The bias of ``fitted``'s parameters measured on ``simulated``, draws of tests simulated at the fit.

    Parameters
    ----------
    simulated : list of Problem
        The problem's tests simulated under ``fitted``, one problem a draw (module docstring).
    fitted : Fit
        The fit on the measured tests.

    Returns
    -------
    u_model : dict
        Parameter -> the bias net of the noise, sqrt(max(mean b_r^2 - mean se_r^2, 0)) [its unit], on
        ``len(simulated)`` degrees of freedom.
    b : dict
        Parameter -> the mean over the draws of the refit less the fit, x*_r - x_hat.
    """
    if not fitted.values or not simulated:
        return {}, {}
    bs, ses = [], []
    for problem in simulated:
        every = np.arange(problem.n_tests)
        refit = fit(problem, every, fitted.ext, x0=fitted.values)
        names, x0, *_, A, y = linearised(problem, problem.subset(every), refit)
        ses.append(sandwich_errors(A, y))
        bs.append(x0 - np.array([fitted.values[k] for k in names], float))
    b, se = np.array(bs), np.array(ses)
    u = net_of_noise(b, se)
    log.info(
        "bias of %s on %d draws of %s simulated tests: %s",
        "+".join(fitted.ext),
        len(simulated),
        "+".join(str(p.n_tests) for p in simulated),
        ", ".join(
            f"{k} {bk:+.3g} (rms se {s:.2g}, u_model {uk:.2g})"
            for k, bk, s, uk in zip(names, b.mean(axis=0), np.sqrt(np.mean(se**2, axis=0)), u)
        ),
    )
    return dict(zip(names, map(float, u))), dict(zip(names, map(float, b.mean(axis=0))))
