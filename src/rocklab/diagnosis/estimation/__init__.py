"""Estimation engine: fits, held-out deviance, bootstrap intervals, selection.

Independent of what is fitted: a :class:`~rocklab.diagnosis.estimation.problem.Problem`
hands the engine its tests, its residual groups (log ratios, model over
measured), the noise covariate of each residual and its candidate causes.
The engine fits a combination of causes by maximum likelihood with a noise
model per group, scores it on tests left out, resamples tests for parameter
intervals and adds their systematic part (the pulls of the residual groups,
and the model's bias measured on tests simulated at the fit),
selects causes greedily and tests what the chosen model leaves.
The method is described in docs/diagnosis-method.md.

================  ==================================================================
module            holds
================  ==================================================================
``problem``       :class:`Problem`, what a problem hands the engine
``noise``         the noise model of a residual group, the deviance under it
``fitting``       :func:`fit` (iteratively reweighted least squares), its linearisation
``resampling``    :func:`heldout` (K-fold), :func:`parameter_intervals` (bootstrap or sandwich)
``systematic``    the systematic part of the intervals: the pulls of the residual groups
``bias``          the model's bias, measured on tests simulated at a fit
``structure``     :func:`structure`, the residual structure a model leaves
``selection``     :func:`select_effects`, :func:`beyond_the_catalogue`, :func:`stand_ins`,
                  :func:`rivals`
================  ==================================================================

Progress goes to the modules' loggers: each candidate with its BIC, held-out
gain and the reason it is taken or turned down, each full fit (passes,
convergence), each bootstrap (resamples, time); the fits of the folds and
resamples only at DEBUG level.
"""

from rocklab.diagnosis.estimation.fitting import Fit, fit
from rocklab.diagnosis.estimation.noise import noise_variance
from rocklab.diagnosis.estimation.problem import Problem
from rocklab.diagnosis.estimation.resampling import finite_mean, heldout, paired_gain, parameter_intervals
from rocklab.diagnosis.estimation.selection import beyond_the_catalogue, rivals, select_effects, stand_ins
from rocklab.diagnosis.estimation.structure import structure, within_slope

__all__ = [
    "Fit",
    "Problem",
    "beyond_the_catalogue",
    "finite_mean",
    "fit",
    "heldout",
    "noise_variance",
    "paired_gain",
    "parameter_intervals",
    "select_effects",
    "rivals",
    "stand_ins",
    "structure",
    "within_slope",
]
