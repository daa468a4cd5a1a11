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

    u_model = sqrt(max(b^2 - se^2, 0))

estimates the bias without the noise (E[b^2] = bias^2 + se^2: the
statistical part is not counted twice), a standard uncertainty added in
quadrature to the interval like the pulls
(:func:`~rocklab.diagnosis.estimation.systematic.widened`): a parametric
bootstrap of one draw, for its bias, not its spread (Efron & Tibshirani
1993, Sect. 10.6).  No constant is set on a benchmark: the simulator is the
reference.  What it cannot see: an error the simulator and the residuals'
model share (the rigid-body wall both assume), the chain before the
measured rotation (the transducers' kinematics), noise that is not white.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
import numpy.typing as npt

from rocklab.diagnosis.estimation.fitting import Fit, fit, linearised
from rocklab.diagnosis.estimation.problem import Problem
from rocklab.diagnosis.estimation.resampling import sandwich_errors

log = logging.getLogger(__name__)


def net_of_noise(b: npt.ArrayLike, se: npt.ArrayLike) -> np.ndarray:
    """The bias a difference ``b`` of one noise draw of standard error ``se`` carries: sqrt(max(b^2 - se^2, 0))
    (E[b^2] = bias^2 + se^2); none where ``se`` is infinite (a direction the tests do not fix)."""
    b, se = np.asarray(b, float), np.asarray(se, float)
    return np.sqrt(np.maximum(b**2 - np.where(np.isfinite(se), se, np.abs(b)) ** 2, 0.0))


def model_bias(simulated: Problem[Any], fitted: Fit) -> tuple[dict[str, float], dict[str, float]]:
    """The bias of ``fitted``'s parameters measured on ``simulated``, its tests simulated at the fit.

    Parameters
    ----------
    simulated : Problem
        The problem's tests simulated under ``fitted`` (module docstring).
    fitted : Fit
        The fit on the measured tests.

    Returns
    -------
    u_model : dict
        Parameter -> the bias net of the noise, sqrt(max(b^2 - se^2, 0)) [its unit].
    b : dict
        Parameter -> the refit less the fit, x* - x_hat.
    """
    if not fitted.values:
        return {}, {}
    every = np.arange(simulated.n_tests)
    refit = fit(simulated, every, fitted.ext, x0=fitted.values)
    names, x0, *_, A, y = linearised(simulated, simulated.subset(every), refit)
    se = sandwich_errors(A, y)
    b = x0 - np.array([fitted.values[k] for k in names], float)
    u = net_of_noise(b, se)
    log.info(
        "bias of %s on %d simulated tests: %s",
        "+".join(fitted.ext),
        simulated.n_tests,
        ", ".join(f"{k} {bk:+.3g} (se {s:.2g}, u_model {uk:.2g})" for k, bk, s, uk in zip(names, b, se, u)),
    )
    return dict(zip(names, map(float, u))), dict(zip(names, map(float, b)))
