"""The noise model of a residual group and the likelihood of residuals under it.

Records are precise to a fixed rotation, so the log residuals of small
flights are noisier in proportion: each residual group has the variance
v = s0^2 + s1^2 x^2, x the observation's noise threshold over its amplitude
(:func:`noise_variance`), and a model is scored by the Gaussian -2 log L of
its residuals under those variances (:func:`deviance`); a residual it did not
see, of a test held out, by the Student-t its group's variance predicts from
the residuals it was estimated on (:func:`predictive_dof`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numba
import numpy as np

#: Floor of the variance of a residual group [log units^2] (noise-free data).
VAR_FLOOR = 1e-10


@numba.njit(cache=True)
def _profile(t: float, r2: np.ndarray, x2: np.ndarray) -> float:
    """-2 log L (constants dropped) of :func:`noise_variance`'s model at log rho = t, s0^2 profiled out.

    Compiled: the noise model is fitted at every reweighting pass of every
    fit, some ten thousand times in the diagnosis of the embedded campaign,
    and scipy's bounded search calls this some thirty times each.
    """
    n = r2.size
    mean, logs = 0.0, 0.0
    for i in range(n):
        d = 1.0 + math.exp(t) * x2[i]
        mean += r2[i] / d
        logs += math.log(d)
    return n * math.log(mean / n) + logs


_SQRT_EPS = math.sqrt(2.2e-16)
_GOLDEN = 0.5 * (3.0 - math.sqrt(5.0))


@numba.njit(cache=True)
def _profile_minimum(lo: float, hi: float, xatol: float, r2: np.ndarray, x2: np.ndarray) -> tuple[float, float]:
    """Minimum (log rho, -2 log L) of :func:`_profile` on [lo, hi]: Brent's bounded search, step for
    step that of :func:`scipy.optimize.minimize_scalar` (``method="bounded"``, 500 evaluations at most).

    Compiled whole: the search runs at every reweighting pass of every fit, and scipy's loop in
    Python cost as much as the likelihood it searched.
    """
    a, b = lo, hi
    fulc = a + _GOLDEN * (b - a)
    nfc, xf = fulc, fulc
    rat = e = 0.0
    x = xf
    fx = _profile(x, r2, x2)
    num = 1
    ffulc = fnfc = fx
    xm = 0.5 * (a + b)
    tol1 = _SQRT_EPS * abs(xf) + xatol / 3.0
    tol2 = 2.0 * tol1
    while abs(xf - xm) > (tol2 - 0.5 * (b - a)):
        golden = True
        if abs(e) > tol1:
            golden = False
            r = (xf - nfc) * (fx - ffulc)
            q = (xf - fulc) * (fx - fnfc)
            p = (xf - fulc) * q - (xf - nfc) * r
            q = 2.0 * (q - r)
            if q > 0.0:
                p = -p
            q = abs(q)
            r = e
            e = rat
            if (abs(p) < abs(0.5 * q * r)) and (p > q * (a - xf)) and (p < q * (b - xf)):
                rat = (p + 0.0) / q
                x = xf + rat
                if ((x - a) < tol2) or ((b - x) < tol2):
                    rat = tol1 * (np.sign(xm - xf) + (1.0 if (xm - xf) == 0 else 0.0))
            else:
                golden = True
        if golden:
            e = a - xf if xf >= xm else b - xf
            rat = _GOLDEN * e
        x = xf + (np.sign(rat) + (1.0 if rat == 0 else 0.0)) * max(abs(rat), tol1)
        fu = _profile(x, r2, x2)
        num += 1
        if fu <= fx:
            if x >= xf:
                a = xf
            else:
                b = xf
            fulc, ffulc = nfc, fnfc
            nfc, fnfc = xf, fx
            xf, fx = x, fu
        else:
            if x < xf:
                a = x
            else:
                b = x
            if (fu <= fnfc) or (nfc == xf):
                fulc, ffulc = nfc, fnfc
                nfc, fnfc = x, fu
            elif (fu <= ffulc) or (fulc == xf) or (fulc == nfc):
                fulc, ffulc = x, fu
        xm = 0.5 * (a + b)
        tol1 = _SQRT_EPS * abs(xf) + xatol / 3.0
        tol2 = 2.0 * tol1
        if num >= 500:
            break
    return xf, fx


def noise_variance(r: np.ndarray, x: np.ndarray) -> tuple[float, float]:
    """Maximum-likelihood noise model v = s0^2 + s1^2 x^2 of residuals r [log units^2].

    ``x`` is the observation's noise threshold over its amplitude: records
    are precise to a fixed rotation, so the log residuals of small flights
    are noisier in proportion.  For a ratio rho = s1^2 / s0^2 the best s0^2
    is mean(r^2 / (1 + rho x^2)); the profile likelihood is then minimised
    over log rho (Brent's bounded search of
    :func:`scipy.optimize.minimize_scalar` to 1e-3, compiled: :func:`_profile_minimum`), the ends rho = 0 and
    s0 = 0 included.
    Returns (s0^2, s1^2).
    """
    r2, x2 = r**2 + VAR_FLOOR, x**2
    n = r.size
    hom = (float(np.mean(r2)), 0.0)
    if n < 4 or np.ptp(x2) <= 1e-12 * max(float(np.max(x2)), 1e-300):
        return hom
    x2 = np.maximum(x2, 1e-300)
    lo, hi = -math.log(float(np.max(x2))) - 12.0, -math.log(float(np.min(x2))) + 12.0
    t, fun = _profile_minimum(lo, hi, 1e-3, np.ascontiguousarray(r2, float), np.ascontiguousarray(x2, float))
    ends = {"hom": n * math.log(hom[0]), "prop": n * math.log(float(np.mean(r2 / x2))) + float(np.sum(np.log(x2)))}
    best = min(ends, key=ends.get)  # type: ignore[arg-type]  # every key has its value
    if fun <= ends[best]:
        rho = math.exp(t)
        s0 = float(np.mean(r2 / (1.0 + rho * x2)))
        return (s0, rho * s0)
    return hom if best == "hom" else (1e-300, float(np.mean(r2 / x2)))


def finite_residuals(
    R: Mapping[str, np.ndarray], X: Mapping[str, np.ndarray]
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Finite residuals and their noise covariates, per group."""
    out: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for g, r in R.items():
        ok = np.isfinite(r) & np.isfinite(X[g])
        out[g] = (r[ok], X[g][ok])
    return out


def group_variances(R: Mapping[str, np.ndarray], X: Mapping[str, np.ndarray]) -> dict[str, tuple[float, float]]:
    """The noise model (s0^2, s1^2) of each residual group of R with two finite residuals or more."""
    return {g: noise_variance(r, x) for g, (r, x) in finite_residuals(R, X).items() if r.size >= 2}


def predictive_dof(
    R: Mapping[str, np.ndarray], X: Mapping[str, np.ndarray], var: Mapping[str, tuple[float, float]]
) -> dict[str, int]:
    """The degrees of freedom of each group's noise model ``var`` fitted on the residuals R.

    A variance estimated from n residuals predicts a new residual with
    Student's t on n degrees of freedom, not a normal law: the posterior
    predictive of a normal residual of known mean whose variance has the
    reference prior 1/sigma^2, s^2 the mean square (Gelman et al., Bayesian
    Data Analysis, 3rd ed., Sect. 3.2).  The shape of v (s1^2 / s0^2, where
    both are fitted) takes one more.  On the few residuals of a short series'
    training tests the normal law would count a held-out residual of ten
    times a near-noiseless training scatter as 100 units of deviance, the t (on
    three) some 15; on hundreds the two agree.
    """
    return {
        g: max(r.size - int(var[g][0] > 1e-300 and var[g][1] > 0.0), 1)
        for g, (r, _) in finite_residuals(R, X).items()
        if g in var
    }


def deviance(
    R: Mapping[str, np.ndarray],
    X: Mapping[str, np.ndarray],
    var: Mapping[str, tuple[float, float]],
    dof: Mapping[str, int] | None = None,
) -> float:
    """-2 log L (constants dropped) of residuals R under the group noise models ``var``.

    With ``dof`` (group -> degrees of freedom, :func:`predictive_dof`) each
    residual's law is Student's t of scale sqrt(v) instead of the normal law,
    its constants those of the normal law's deviance subtracted, so that the
    two agree as the degrees of freedom grow.
    """
    out = 0.0
    for g, (r, x) in finite_residuals(R, X).items():
        if g in var and r.size:
            v = var[g][0] + var[g][1] * x**2 + VAR_FLOOR
            if dof is None:
                out += float(np.sum(r**2 / v + np.log(v)))
                continue
            nu = float(dof[g])
            const = 2.0 * math.lgamma(nu / 2) - 2.0 * math.lgamma((nu + 1) / 2) + math.log(nu / 2)
            out += float(np.sum(np.log(v) + (nu + 1) * np.log1p(r**2 / (nu * v)))) + r.size * const
    return out
