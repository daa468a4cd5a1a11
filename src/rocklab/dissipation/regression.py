"""Ordinary least squares with Student's t inference: the library's one regression.

Used by the amplitude laws of the impacts (Eqs. 15 and 17,
:func:`rocklab.dissipation.analysis.amplitude_law_fit`) and by the campaign's
between-series models (:mod:`rocklab.dissipation.covariates`).
"""

from __future__ import annotations

import numpy as np


def ols(y: np.ndarray, X: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """Ordinary least squares with Student's t inference.

    Parameters
    ----------
    y : (n,) array
    X : (n, k) array, full column rank, k < n

    Returns
    -------
    coef : (k,) array
    cov : (k, k) array
        s^2 (X'X)^-1, s^2 the residual mean square on n - k degrees of freedom.
    df : int
        n - k.
    """
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    df = len(y) - X.shape[1]
    resid = y - X @ coef
    cov = (resid @ resid) / df * np.linalg.inv(X.T @ X)
    return coef, cov, df
