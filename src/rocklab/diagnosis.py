"""Model diagnosis: what the literature model gets wrong, and why (Sect. 3, Figs. 14-15).

Free rocking is a sequence of peaks.  Between two impacts the rigid wall
conserves energy, so the peak after an impact follows from the peak before
it in closed form (the energy balance behind Eq. 11)::

    thetadot^-^2 = 2 p^2 [cos(a_s - |theta_k|) - cos a_s]          (impact velocity)
    thetadot^+   = |e| thetadot^-                                     (impact law)
    cos(a_s' - |theta_k+1|) = cos a_s' + thetadot^+^2 / (2 p^2)       (next peak)

with a_s the rocking angle of the hinge in use.  :func:`peak_step` is this
map, extended by the candidate causes of a mismatch, each a physical
extension of the base model with its own parameters (:data:`EFFECTS`):

``restitution_scale``     e = c e_an                       (null c = 1)
``restitution_amplitude`` e/e_an = a - b (thetadot^-/thetadot_r)^2, Eq. 17 (null b = 0)
``instability_angle``     hinges at alpha_r = r alpha        (null r = 1)
``flight_damping``        -2 zeta p thetadot between impacts  (null zeta = 0);
                          energy lost in a flight 2 zeta p * int |thetadot| dtheta
``hinge_asymmetry``       e x exp(+-s/2) on the two hinges (two-sided) or for
                          push / pull tests (one-sided)       (null s = 0)
``contact_gap``           one-sided wall swinging inwards through a gap
                          g = gamma alpha: base impact (Eq. 2), two-sided
                          rocking on the inner hinge, transverse impact
                          (Eqs. 12-13), base impact (Fig. 12) (null gamma = 0)

Statistics.  Parameters are fitted to the one-step residuals
log((theta_k+1^model + f) / (theta_k+1 + f)) of all tests of a series,
the model started from each measured peak (``f`` the test's peak
threshold, so noise-level peaks weigh little); these are nearly independent,
which the information criterion needs.  Extensions are chosen by greedy
forward selection: a candidate enters when its held-out error (K-fold over
tests) beats the current model by more than twice the standard error of the
paired per-test differences, BIC decreases, its bootstrap (over tests) 95 %
interval excludes the null value and its data signature (independent of the
fit) does not contradict it.  ``unexplained`` flags residual structure that
survives the chosen model: a per-test bias or trend with impact index or
amplitude, significant across tests.

The engineering measures (peak decay per impact, number of impacts,
duration, period-amplitude relation, phase drift) come from the same map with
the closed-form flight times; the RMS of theta/alpha over the motion comes
from :func:`rocklab.rocking.simulate_free` on a few tests per series.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize, stats

from rocklab import impact as _impact
from rocklab import restitution
from rocklab.motion import extract_motion
from rocklab.rocking import RockingModel, simulate_free
from rocklab.wall import overturning_velocity

#: Candidate causes, in the order they are reported when tied.
EFFECTS = ("restitution_scale", "restitution_amplitude", "instability_angle", "flight_damping",
           "hinge_asymmetry", "contact_gap")

#: Parameters of each extension: (name, start, lower, upper, null value).
PARAMS = {
    "restitution_scale": [("c", 1.0, 0.2, 2.0, 1.0)],
    "restitution_amplitude": [("a", 1.0, 0.2, 2.5, None), ("b", 0.0, -2.0, 3.0, 0.0)],
    "instability_angle": [("alpha_r_over_alpha", 1.0, 0.3, 1.2, 1.0)],
    "flight_damping": [("zeta", 0.0, 0.0, 0.2, 0.0)],
    "hinge_asymmetry": [("s", 0.0, -1.5, 1.5, 0.0)],
    "contact_gap": [("gap_over_alpha", 0.0, 0.0, 0.5, 0.0)],
}

_GL_X, _GL_W = np.polynomial.legendre.leggauss(12)
_GL_S = 0.5 * (_GL_X + 1.0)
_GL_W = 0.5 * _GL_W


# ---------------------------------------------------------------------------
# measured peak sequences


@dataclass
class PeakSeries:
    """Peak sequence of one free-rocking test (rocklab.motion.Motion reduced).

    ``peaks[0]`` is |theta0| and ``peaks[k]`` |theta_k| after impact k [rad];
    ``t_impacts[k-1]`` the time of impact k [s]; ``side0`` the sign of theta0.
    """

    test_id: str
    alpha: float
    p: float
    boundary: str
    direction: str
    side0: int
    peaks: np.ndarray
    t_release: float
    t_impacts: np.ndarray
    t_end: float
    floor: float
    thetadot_after: np.ndarray = field(default_factory=lambda: np.zeros(0))
    negative_excursion: np.ndarray = field(default_factory=lambda: np.zeros(0))
    t: np.ndarray | None = None
    theta: np.ndarray | None = None
    t_record_end: float = np.inf

    @property
    def n_impacts(self) -> int:
        return self.peaks.size - 1


def peak_series(record) -> PeakSeries:
    """Peak sequence of a measured test record.

    Parameters
    ----------
    record : dict
        ``test_id, t, theta, fs, alpha, p, boundary, direction`` (theta in rad,
        t in s); optionally ``motion`` (a :class:`rocklab.motion.Motion`
        already extracted) or ``motion_kw`` for :func:`extract_motion`.
    """
    t = np.asarray(record["t"], float)
    theta = np.asarray(record["theta"], float)
    m = record.get("motion")
    if m is None:
        m = extract_motion(t, theta, record["fs"], record["boundary"], record["p"],
                           **record.get("motion_kw", {}))
    imp = m.impacts
    n = m.peaks.size
    return PeakSeries(
        test_id=str(record.get("test_id", "")), alpha=float(record["alpha"]), p=float(record["p"]),
        boundary=record["boundary"], direction=str(record.get("direction", "push")), side0=int(m.sign),
        peaks=np.r_[m.theta0, m.peaks], t_release=float(m.t_release),
        t_impacts=imp.t_s.to_numpy(float)[:n], t_end=float(m.t_end), floor=float(m.peak_threshold),
        thetadot_after=np.abs(imp.thetadot_after.to_numpy(float)[:n]),
        negative_excursion=imp.negative_excursion.to_numpy(float)[:n], t=t, theta=theta,
        t_record_end=float(t[-1]),
    )


# ---------------------------------------------------------------------------
# the peak map


@dataclass
class MapParams:
    """Per-test arrays (broadcast over tests) of the extended peak map."""

    alpha: np.ndarray
    p: np.ndarray
    one_sided: np.ndarray
    e0: np.ndarray          # signed base e on hinge +, nominal alpha (Eq. 2 or Eq. 14)
    c_pos: np.ndarray       # multiplier of e on hinge + (scale x asymmetry)
    c_neg: np.ndarray
    amp_a: np.ndarray
    amp_b: np.ndarray
    a_pos: np.ndarray       # rocking angles [rad]
    a_neg: np.ndarray
    zeta: np.ndarray
    gap: np.ndarray         # [rad]


def _flight_integral(A, a, p):
    """int_0^A |thetadot| dtheta of the undamped flight with peak A on hinge a."""
    A = A[..., None]
    a = a[..., None]
    th = A * (1.0 - _GL_S**2)
    f = np.sqrt(np.maximum(2.0 * p[..., None] ** 2 * (np.cos(a - A) - np.cos(a - th)), 0.0))
    return np.sum(_GL_W * f * 2.0 * A * _GL_S, axis=-1)


def quarter_period(A, a, p):
    """Flight time from a peak A [rad] to theta = 0 on hinge a, exact rigid block [s].

    int_0^A dtheta / |thetadot|; the Housner closed form (rocklab.wall) is its
    small-alpha limit.
    """
    A, a, p = np.broadcast_arrays(np.asarray(A, float), np.asarray(a, float), np.asarray(p, float))
    Ac = np.minimum(A, a * (1 - 1e-9))[..., None]
    ac = a[..., None]
    s = _GL_S
    th = Ac * (1.0 - s**2)
    # thetadot^2 = 2 p^2 [cos(a - A) - cos(a - th)] vanishes like s^2: the ratio stays finite
    num = 2.0 * p[..., None] ** 2 * (np.cos(ac - Ac) - np.cos(ac - th))
    g = np.sqrt(np.maximum(num, 1e-300)) / np.maximum(s, 1e-300)
    return np.sum(_GL_W * 2.0 * Ac / g, axis=-1)


def _energy(A, a, p):
    return p**2 * (np.cos(a - A) - np.cos(a))


def _peak_from_energy(E, a, p):
    c = np.cos(a) + np.maximum(E, 0.0) / p**2
    return np.where(c >= 1.0, a, a - np.arccos(np.minimum(c, 1.0)))


def _factor(e0, mp, v):
    vr = overturning_velocity(mp.alpha, mp.p)
    hi = 1.0 / np.maximum(np.abs(e0), 1e-12)
    return np.clip(mp.amp_a - mp.amp_b * (v / vr) ** 2, 0.0, hi)


def peak_step(A, side, mp: MapParams):
    """One flight + impact: next peak |theta_k+1| and its hinge side.

    Parameters
    ----------
    A : ndarray
        Current peak |theta_k| [rad] (one value per test).
    side : ndarray
        Hinge of the current peak, +1 / -1.
    mp : MapParams

    Returns
    -------
    A_next, side_next : ndarray
    """
    a_s = np.where(side > 0, mp.a_pos, mp.a_neg)
    A = np.minimum(A, a_s * (1 - 1e-9))
    E = _energy(A, a_s, mp.p) - 2.0 * mp.zeta * mp.p * _flight_integral(A, a_s, mp.p)
    v = np.sqrt(2.0 * np.maximum(E, 0.0))
    c_s = np.where(side > 0, mp.c_pos, mp.c_neg)
    # two-sided, and one-sided without gap: one impact of law e0 (x scale, Eq. 17 factor)
    e = mp.e0 * c_s
    v_out = np.abs(e * _factor(e, mp, v)) * v
    new_side = np.where(mp.one_sided, side, -side)
    # one-sided with gap (Fig. 12): base impact, inner two-sided flight, transverse impact, base impact
    gapped = mp.one_sided & (mp.gap > 0)
    if np.any(gapped):
        e_b = restitution.two_sided(mp.alpha) * c_s
        e_tr = restitution.transverse(mp.alpha)
        v1 = np.abs(e_b * _factor(e_b, mp, v)) * v
        U = _energy(np.minimum(mp.gap, mp.a_neg), mp.a_neg, mp.p)
        reach = 0.5 * v1**2 > U
        v2 = np.sqrt(np.where(reach, e_tr**2 * np.maximum(v1**2 - 2 * U, 0.0) + 2 * U, v1**2))
        v3 = np.abs(e_b * _factor(e_b, mp, v2)) * v2
        v_out = np.where(gapped, v3, v_out)
    new_a = np.where(new_side > 0, mp.a_pos, mp.a_neg)
    E1 = 0.5 * v_out**2
    A1 = _peak_from_energy(E1, new_a, mp.p)
    if np.any(mp.zeta > 0):
        A1 = _peak_from_energy(E1 - 2.0 * mp.zeta * mp.p * _flight_integral(A1, new_a, mp.p), new_a, mp.p)
    return A1, new_side


def free_peaks(theta0, side0, mp: MapParams, n):
    """Peaks after impacts 1..n of free rocking from rest at theta0 (peak map), (tests, n)."""
    A = np.asarray(theta0, float).copy()
    side = np.asarray(side0, float).copy()
    out = np.empty(A.shape + (n,))
    for k in range(n):
        A, side = peak_step(A, side, mp)
        out[..., k] = A
    return out


def model_params(tests, ext=(), values=None):
    """MapParams of the base model extended by ``ext`` with parameter ``values``."""
    values = dict(values or {})
    alpha = np.array([ts.alpha for ts in tests])
    p = np.array([ts.p for ts in tests])
    one = np.array([ts.boundary == "one-sided" for ts in tests])
    e0 = np.where(one, restitution.one_sided(alpha), restitution.two_sided(alpha))
    ones = np.ones_like(alpha)
    c = values.get("c", 1.0) * ones
    s = values.get("s", 0.0)
    push = np.array([ts.direction == "push" for ts in tests])
    # two-sided: side +/- of the hinge; one-sided: push / pull tests
    c_pos = c * np.where(one, np.where(push, math.exp(s / 2), math.exp(-s / 2)), math.exp(s / 2))
    c_neg = c * np.where(one, c_pos / c, math.exp(-s / 2))
    r = values.get("alpha_r_over_alpha", 1.0)
    return MapParams(
        alpha=alpha, p=p, one_sided=one, e0=e0, c_pos=c_pos, c_neg=c_neg,
        amp_a=values.get("a", 1.0) * ones, amp_b=values.get("b", 0.0) * ones,
        a_pos=r * alpha, a_neg=r * alpha, zeta=values.get("zeta", 0.0) * ones,
        gap=values.get("gap_over_alpha", 0.0) * alpha,
    )


def rocking_model(ts: PeakSeries, ext=(), values=None, base="analytic") -> RockingModel:
    """The RockingModel (rocklab.rocking) equivalent to a peak-map model.

    ``base``: "analytic" (Eq. 2 / Eq. 14), "two-sided-e" (|e_an,2s| used for a
    one-sided wall, Hogan 1992) or "zero" (e = 0, Liberatore & Spera 2003).
    """
    values = dict(values or {})
    one = ts.boundary == "one-sided"
    gap = values.get("gap_over_alpha", 0.0) * ts.alpha
    if base == "zero":
        law = _impact.Zero()
    elif base == "two-sided-e" and one:
        law = _impact.Constant(-restitution.two_sided(ts.alpha))
    elif one and gap == 0:
        law = _impact.OneSided()
    else:
        law = _impact.HousnerTwoSided()
    c, s = values.get("c", 1.0), values.get("s", 0.0)
    if one:
        cs = c * math.exp((s if ts.direction == "push" else -s) / 2)
        law = _impact.Scaled(law, cs) if cs != 1.0 else law
    elif s != 0.0:
        law = _impact.Sided(_impact.Scaled(law, c * math.exp(s / 2)), _impact.Scaled(law, c * math.exp(-s / 2)))
    elif c != 1.0:
        law = _impact.Scaled(law, c)
    if "b" in values:
        law = _impact.AmplitudeLaw(law, values.get("a", 1.0), values["b"])
    ar = values.get("alpha_r_over_alpha", 1.0) * ts.alpha
    return RockingModel(alpha=ts.alpha, p=ts.p, boundary=ts.boundary, impact=law, alpha_rock=ar,
                        flight_damping=values.get("zeta", 0.0), gap=gap)


# ---------------------------------------------------------------------------
# residuals, fit, held-out error


def _stack(tests):
    n = max(ts.n_impacts for ts in tests)
    P = np.full((len(tests), n + 1), np.nan)
    for i, ts in enumerate(tests):
        P[i, : ts.peaks.size] = ts.peaks
    floor = np.array([ts.floor for ts in tests])[:, None]
    side0 = np.array([ts.side0 for ts in tests], float)
    return P, floor, side0


def one_step_residuals(tests, ext=(), values=None, mp=None):
    """log((theta_k^model + f) / (theta_k + f)), model started from the measured peak k-1; (tests, n)."""
    P, floor, side0 = _stack(tests)
    mp = model_params(tests, ext, values) if mp is None else mp
    n = P.shape[1] - 1
    R = np.full((len(tests), n), np.nan)
    one = mp.one_sided
    for k in range(n):
        side = np.where(one, side0, side0 * (-1.0) ** k)
        A = np.nan_to_num(P[:, k], nan=0.0)
        A1, _ = peak_step(A, side, mp)
        R[:, k] = np.log((A1 + floor[:, 0]) / (P[:, k + 1] + floor[:, 0]))
    return R


def free_residuals(tests, ext=(), values=None, mp=None):
    """log((theta_k^model + f) / (theta_k + f)) of the free run from the measured release; (tests, n)."""
    P, floor, side0 = _stack(tests)
    mp = model_params(tests, ext, values) if mp is None else mp
    M = free_peaks(P[:, 0], side0, mp, P.shape[1] - 1)
    return np.log((M + floor) / (P[:, 1:] + floor))


def _param_list(ext):
    return [q for e in EFFECTS if e in ext for q in PARAMS[e]]


def _lower_alpha_r(tests):
    return max(ts.peaks[0] / ts.alpha for ts in tests) + 1e-4


def fit(tests, ext):
    """Least-squares fit of the extensions ``ext`` on the pooled one-step residuals.

    Returns
    -------
    values : dict
        Parameter name -> value.
    sse : float
    n_obs : int
    """
    plist = _param_list(ext)
    if not plist:
        R = one_step_residuals(tests)
        r = R[np.isfinite(R)]
        return {}, float(r @ r), r.size
    lo = np.array([q[2] for q in plist], float)
    hi = np.array([q[3] for q in plist], float)
    x0 = np.array([q[1] for q in plist], float)
    for i, q in enumerate(plist):
        if q[0] == "alpha_r_over_alpha":
            lo[i] = min(max(lo[i], _lower_alpha_r(tests)), hi[i] - 1e-3)
            x0[i] = min(max(x0[i], lo[i] + 1e-3), hi[i])
    names = [q[0] for q in plist]

    def res(x):
        R = one_step_residuals(tests, ext, dict(zip(names, x)))
        return np.nan_to_num(R[np.isfinite(_stack(tests)[0][:, 1:])], nan=10.0)

    x0 = np.clip(x0, lo + 1e-9, hi - 1e-9)
    sol = optimize.least_squares(res, x0, bounds=(lo, hi), x_scale="jac", diff_step=1e-4)
    # a second start away from the null avoids the flat spot of bounded nulls (zeta, gap)
    if any(n_ in ("zeta", "gap_over_alpha", "b") for n_ in names):
        x1 = np.clip(x0 + 0.1 * (hi - lo) * np.array([n_ in ("zeta", "gap_over_alpha", "b") for n_ in names]),
                     lo + 1e-9, hi - 1e-9)
        sol2 = optimize.least_squares(res, x1, bounds=(lo, hi), x_scale="jac", diff_step=1e-4)
        if sol2.cost < sol.cost:
            sol = sol2
    r = sol.fun
    return dict(zip(names, map(float, sol.x))), float(r @ r), r.size


def _folds(n, k_max=5):
    k = n if n <= 8 else k_max
    idx = np.arange(n)
    return [idx[idx % k == j] for j in range(k)]


def heldout_errors(tests, ext):
    """Per-test held-out errors of ``ext`` fitted on the other tests (K-fold).

    Returns
    -------
    dict
        ``one_step_mse`` (per test, array), ``free_rms`` (per test, array).
    """
    n = len(tests)
    one = np.full(n, np.nan)
    free = np.full(n, np.nan)
    folds = _folds(n) if n > 1 else [np.arange(n)]
    for held in folds:
        train = [tests[i] for i in range(n) if i not in held] or tests
        values, _, _ = fit(train, ext)
        sub = [tests[i] for i in held]
        R = one_step_residuals(sub, ext, values)
        F = free_residuals(sub, ext, values)
        for j, i in enumerate(held):
            one[i] = np.nanmean(R[j] ** 2)
            free[i] = math.sqrt(np.nanmean(F[j] ** 2))
    return {"one_step_mse": one, "free_rms": free}


def bootstrap_ci(tests, ext, values, n_boot=40, seed=0):
    """Percentile 95 % intervals of the parameters, resampling whole tests."""
    rng = np.random.default_rng(seed)
    draws = []
    for _ in range(n_boot):
        pick = rng.integers(0, len(tests), len(tests))
        v, _, _ = fit([tests[i] for i in pick], ext)
        draws.append([v[k] for k in values])
    d = np.array(draws)
    return {k: [float(np.percentile(d[:, i], 2.5)), float(np.percentile(d[:, i], 97.5))]
            for i, k in enumerate(values)}


def _bic(sse, n, k):
    return n * math.log(max(sse, 1e-300) / n) + k * math.log(n)


# ---------------------------------------------------------------------------
# signatures in the data, independent of the fits


def _per_impact_e(ts):
    """Per-impact |e| from consecutive peaks (energy balance, nominal alpha) and impact velocity."""
    a = ts.alpha
    E = _energy(np.minimum(ts.peaks, a * (1 - 1e-9)), a, ts.p)
    e = np.sqrt(np.maximum(E[1:], 0) / np.maximum(E[:-1], 1e-300))
    v = np.sqrt(2 * np.maximum(E[:-1], 0))
    ok = ts.peaks[1:] > ts.floor
    return e[ok], v[ok] / overturning_velocity(a, ts.p), np.arange(1, ts.peaks.size)[ok]


def signatures(tests):
    """Evidence for each cause that does not come from a model fit.

    Returns
    -------
    dict
        effect -> {"value": ..., "supports": bool, "text": str}.
    """
    one = tests[0].boundary == "one-sided"
    e_an = abs(restitution.one_sided(tests[0].alpha) if one else restitution.two_sided(tests[0].alpha))
    es, vs, sides, dirs = [], [], [], []
    for ts in tests:
        e, v, k = _per_impact_e(ts)
        e_an_t = abs(restitution.one_sided(ts.alpha) if one else restitution.two_sided(ts.alpha))
        es.append(e / e_an_t)
        vs.append(v)
        sides.append(ts.side0 * (np.ones(k.size) if one else (-1.0) ** (k - 1)))
        dirs.append(np.full(e.size, ts.direction == "push"))
    e, v, side, push = (np.concatenate(x) if x else np.zeros(0) for x in (es, vs, sides, dirs))
    out = {}
    if e.size >= 3:
        med = float(np.median(e))
        lo, hi = np.percentile(e, [25, 75])
        out["restitution_scale"] = {"value": med, "supports": bool(abs(med - 1) > 0.01),
                                    "text": f"median per-impact e/e_an = {med:.3f} (IQR {lo:.3f}-{hi:.3f}, "
                                            f"{e.size} impacts)"}
        sl = stats.linregress(v**2, e) if np.ptp(v) > 0 else None
        if sl is not None:
            out["restitution_amplitude"] = {
                "value": float(sl.slope), "supports": bool(sl.slope < 0 and sl.pvalue < 0.01),
                "text": f"e/e_an vs (thetadot^-/thetadot_r)^2: slope {sl.slope:.3f} (p = {sl.pvalue:.2g})"}
        if one:
            a_, b_ = e[push], e[~push]
        else:
            a_, b_ = e[side > 0], e[side < 0]
        if a_.size >= 3 and b_.size >= 3:
            u = stats.mannwhitneyu(a_, b_)
            lab = "push/pull tests" if one else "hinge +/-"
            out["hinge_asymmetry"] = {
                "value": float(np.median(a_) / np.median(b_)), "supports": bool(u.pvalue < 0.01),
                "text": f"median e/e_an on {lab}: {np.median(a_):.3f} / {np.median(b_):.3f} "
                        f"(Mann-Whitney p = {u.pvalue:.2g})"}
    r0 = np.array([ts.peaks[0] / ts.alpha for ts in tests])
    # period-amplitude: measured first quarter period against the exact one at the nominal alpha
    tq = np.array([(ts.t_impacts[0] - ts.t_release) / quarter_period(ts.peaks[0], ts.alpha, ts.p)
                   for ts in tests if ts.t_impacts.size])
    out["instability_angle"] = {
        "value": float(np.median(r0)), "supports": bool(np.median(r0) < 0.98),
        "text": f"theta0/alpha = {np.median(r0):.3f} (median of {r0.size} releases, max {r0.max():.3f}); "
                f"first quarter period / rigid-block value at nominal alpha = "
                f"{np.median(tq) if tq.size else float('nan'):.3f}"}
    drift = []
    for ts in tests:
        n = min(ts.thetadot_after.size, ts.peaks.size - 1)
        ok = (ts.peaks[1:n + 1] > ts.floor) & (ts.thetadot_after[:n] > 0)
        if ok.any():
            E_peak = _energy(np.minimum(ts.peaks[1:n + 1][ok], ts.alpha * (1 - 1e-9)), ts.alpha, ts.p)
            drift.append(E_peak / (0.5 * ts.thetadot_after[:n][ok] ** 2))
    dr = np.concatenate(drift) if drift else np.zeros(0)
    if dr.size:
        out["flight_damping"] = {
            "value": float(np.median(dr)), "supports": bool(np.median(dr) < 0.97),
            "text": f"energy at the next peak / kinetic energy after the impact = {np.median(dr):.3f} "
                    f"(median of {dr.size} flights; 1 = no loss in flight)"}
    if one:
        neg = np.concatenate([ts.negative_excursion for ts in tests]) if tests else np.zeros(0)
        n_neg = int(np.sum(neg > 0))
        mx = float(max((ts.negative_excursion.max(initial=0) / ts.alpha for ts in tests), default=0))
        out["contact_gap"] = {"value": mx, "supports": bool(n_neg > 0),
                              "text": f"{n_neg} impacts with negative rotations (max |theta|/alpha = {mx:.3f})"}
    else:
        out["contact_gap"] = {"value": 0.0, "supports": False, "text": "two-sided wall: no transverse walls"}
    return out


#: Smallest held-out gain, relative to the current one-step MSE, that can name a cause.
MIN_RELATIVE_GAIN = 0.1

#: Causes that cannot be named against their signature (the fit alone does not carry them).
_NEEDS_SIGNATURE = ("contact_gap", "flight_damping")


# ---------------------------------------------------------------------------
# engineering measures


def engineering_errors(tests, ext=(), values=None, base="analytic", n_history=2, cap=300):
    """Measured vs model: decay per impact, impacts, duration, period-amplitude, phase drift, RMS.

    Returns
    -------
    dict
        Series means of each measure, measured and model, and the error measures
        ``log_peak_rms`` (free run) and ``one_step_rms``.
    """
    mp = model_params(tests, ext, values)
    if base == "zero":
        mp.e0 = mp.e0 * 0.0
    elif base == "two-sided-e":
        mp.e0 = np.where(mp.one_sided, -restitution.two_sided(mp.alpha), mp.e0)
    P, floor, side0 = _stack(tests)
    M = free_peaks(P[:, 0], side0, mp, cap)
    rows = []
    for i, ts in enumerate(tests):
        def times(x, a):
            # flight times: release to impact 1 is a quarter period, then two quarters per peak
            q = quarter_period(x, a, ts.p)
            return ts.t_release + np.cumsum(np.r_[q[0], 2 * q[1:]])

        meas = ts.peaks
        ar = mp.a_pos[i]
        mod = np.r_[meas[0], M[i]]
        # the model is observed like the wall: peaks above the noise threshold, within the record
        alive = (mod[1:] > ts.floor) & (times(mod[:-1], ar) <= ts.t_record_end)
        n_mod = int(np.argmax(~alive)) if np.any(~alive) else cap
        mod = mod[: n_mod + 1]

        def decay(x):
            if x.size < 2:
                return 1.0
            return 1.0 - math.exp(np.polyfit(np.arange(x.size), np.log(x), 1)[0])

        t_mod = times(mod[:-1], ar) if mod.size > 1 else np.zeros(0)
        n_c = min(t_mod.size, ts.t_impacts.size)
        half = np.diff(np.r_[ts.t_release, ts.t_impacts])
        drift = (180.0 * (t_mod[n_c - 1] - ts.t_impacts[n_c - 1]) / max(np.mean(half[1:n_c]) if n_c > 1
                 else 2 * half[0], 1e-9)) if n_c else 0.0
        # period-amplitude: measured flight times against the model's at the measured peaks
        q_meas = np.r_[half[0], half[1:] / 2] if half.size else np.zeros(0)
        q_mod = quarter_period(meas[: half.size], ar, ts.p)
        pa = float(np.sqrt(np.mean(np.log(q_meas / q_mod) ** 2))) if half.size else np.nan
        rows.append({
            "decay_measured": decay(meas), "decay_model": decay(mod),
            "n_measured": ts.n_impacts, "n_model": n_mod,
            "duration_measured": ts.t_end - ts.t_release,
            "duration_model": (t_mod[-1] - ts.t_release) if t_mod.size else 0.0,
            "phase_drift_deg": drift, "period_amplitude_rms": pa,
        })
    F = np.log((M[:, : P.shape[1] - 1] + floor) / (P[:, 1:] + floor))
    R = one_step_residuals(tests, mp=mp)
    agg = {k: float(np.nanmean([r[k] for r in rows])) for k in rows[0]}
    out = {
        "peak_decay_pct_per_impact": {"measured": 100 * agg["decay_measured"], "model": 100 * agg["decay_model"]},
        "n_impacts": {"measured": agg["n_measured"], "model": agg["n_model"]},
        "duration_s": {"measured": agg["duration_measured"], "model": agg["duration_model"]},
        "phase_drift_deg": agg["phase_drift_deg"],
        "period_amplitude_rms_log": agg["period_amplitude_rms"],
        "log_peak_rms": float(np.sqrt(np.nanmean(F**2))),
        "one_step_rms": float(np.sqrt(np.nanmean(R**2))),
    }
    rms = []
    for ts in tests[:n_history]:
        if ts.t is None:
            continue
        rms.append(_history_rms(ts, ext, values, base))
    out["rms_theta_over_alpha"] = float(np.mean(rms)) if rms else None
    return out


def _history_rms(ts, ext, values, base):
    fs = 1.0 / np.median(np.diff(ts.t))
    sel = (ts.t >= ts.t_release) & (ts.t <= ts.t_end)
    if sel.sum() < 2:
        return float("nan")
    h = simulate_free(rocking_model(ts, ext, values, base), ts.side0 * ts.peaks[0], 0.0,
                      t_end=ts.t_end - ts.t_release, fs=fs, rtol=1e-8, atol=1e-10)
    th = np.interp(ts.t[sel] - ts.t_release, h.t, np.nan_to_num(h.theta))
    return float(np.sqrt(np.mean((th - ts.theta[sel]) ** 2)) / ts.alpha)


# ---------------------------------------------------------------------------
# selection and report


def _candidates(boundary):
    return [e for e in EFFECTS if boundary == "one-sided" or e != "contact_gap"]


def _with(current, eff):
    new = set(current) | {eff}
    if eff == "restitution_amplitude":
        new.discard("restitution_scale")    # a of Eq. 17 is the scale
    if eff == "restitution_scale" and "restitution_amplitude" in current:
        return None
    return tuple(e for e in EFFECTS if e in new)


def _null_excluded(ext, ci):
    for e in ext:
        for name, _, _, _, null in PARAMS[e]:
            if null is not None and ci[name][0] <= null <= ci[name][1]:
                return False
            if null is not None and name in ("zeta", "gap_over_alpha") and ci[name][0] <= 1e-4:
                return False
    return True


def _structure(tests, ext, values, alpha_level=0.01):
    """Residual structure left by a model: per-test bias and trends, tested across tests."""
    R = one_step_residuals(tests, ext, values)
    P = _stack(tests)[0]
    means, slopes_k, slopes_a = [], [], []
    for i, ts in enumerate(tests):
        r = R[i, : ts.n_impacts]
        ok = np.isfinite(r) & (P[i, 1: ts.n_impacts + 1] > ts.floor)
        if ok.sum() >= 3:
            means.append(r[ok].mean())
            k = np.arange(r.size)[ok]
            slopes_k.append(np.polyfit(k / max(k.max(), 1), r[ok], 1)[0])
            amp = P[i, : ts.n_impacts][ok] / ts.alpha
            slopes_a.append(np.polyfit(amp, r[ok], 1)[0] if np.ptp(amp) > 0 else 0.0)
    found = []
    for name, x, size in (("bias", means, 0.01), ("trend with impact index", slopes_k, 0.02),
                          ("trend with amplitude", slopes_a, 0.05)):
        x = np.asarray(x)
        if x.size >= 3 and np.std(x) > 0:
            t = stats.ttest_1samp(x, 0.0)
            if t.pvalue < alpha_level and abs(x.mean()) > size:
                found.append(f"{name} {x.mean():+.3f} (p = {t.pvalue:.1g})")
    return found


def diagnose_series(tests, *, key="", scope="series", n_boot=40, n_history=2, max_effects=3, seed=0):
    """Diagnosis of one series (or one boundary condition): base model, causes, gain.

    Parameters
    ----------
    tests : list of PeakSeries or of record dicts (see :func:`peak_series`)
        All of one boundary condition.
    key, scope : str
        Identify the entry ("series" | "boundary").
    n_boot : int
        Bootstrap resamples (of tests) for the 95 % intervals.
    n_history : int
        Tests simulated in time (simulate_free) for the RMS of theta/alpha.

    Returns
    -------
    dict
        One entry of results/diagnosis.json (see module docstring).
    """
    tests = [t if isinstance(t, PeakSeries) else peak_series(t) for t in tests]
    tests = [t for t in tests if t.n_impacts >= 1]
    boundary = tests[0].boundary
    if any(t.boundary != boundary for t in tests):
        raise ValueError("a diagnosis needs tests of one boundary condition")
    sig = signatures(tests)
    base_name = "Housner e_an,2s (Eq. 2), nominal alpha" if boundary == "two-sided" else \
        "one-sided e_an,1s (Eq. 14), nominal alpha"
    base = {"model": base_name, "errors": engineering_errors(tests, n_history=n_history)}
    if boundary == "one-sided":
        base["alternatives"] = {
            "two-sided e (Hogan 1992)": engineering_errors(tests, base="two-sided-e", n_history=0),
            "e = 0 (Liberatore & Spera 2003)": engineering_errors(tests, base="zero", n_history=0),
        }
    n_obs_all = int(np.sum([t.n_impacts for t in tests]))
    current = ()
    cur_vals, cur_sse, _ = fit(tests, current)
    cur_err = heldout_errors(tests, current)
    base_err = cur_err
    findings, tried = [], {}
    for _ in range(max_effects):
        passed = []
        for eff in _candidates(boundary):
            if eff in current:
                continue
            ext = _with(current, eff)
            if ext is None or ext == current:
                continue
            vals, sse, n = fit(tests, ext)
            err = heldout_errors(tests, ext)
            d = cur_err["one_step_mse"] - err["one_step_mse"]
            se = np.std(d, ddof=1) / math.sqrt(d.size) if d.size > 1 else np.inf
            dbic = _bic(sse, n, len(_param_list(ext))) - _bic(cur_sse, n, len(_param_list(current)))
            cand = {"effect": eff, "ext": ext, "values": vals, "sse": sse, "err": err, "gain": float(d.mean()),
                    "margin": float(2 * se), "dbic": float(dbic)}
            tried[eff] = cand
            # the noise margin: twice the standard error of the paired differences, and a tenth
            # of the current error (a gain the noise of a few tests could fake is no evidence)
            if d.mean() > max(2 * se, MIN_RELATIVE_GAIN * cur_err["one_step_mse"].mean()) and dbic < 0:
                passed.append(cand)
        if not passed:
            break
        top = max(passed, key=lambda c: c["gain"])
        # parsimony: a simpler extension whose held-out error is not worse than the best's by
        # more than the noise wins (e = c e_an before Eq. 17)
        best = top
        for cand in sorted(passed, key=lambda c: (len(_param_list(c["ext"])), -c["gain"])):
            d = cand["err"]["one_step_mse"] - top["err"]["one_step_mse"]
            se = np.std(d, ddof=1) / math.sqrt(d.size) if d.size > 1 else 0.0
            if d.mean() <= max(2 * se, MIN_RELATIVE_GAIN * top["err"]["one_step_mse"].mean()):
                best = cand
                break
        eff = best["effect"]
        if eff in _NEEDS_SIGNATURE and not sig.get(eff, {}).get("supports", False):
            tried[eff]["rejected"] = "its signature in the data is absent"
            break
        ci = bootstrap_ci(tests, best["ext"], best["values"], n_boot=n_boot, seed=seed)
        own = {q[0] for q in PARAMS[eff]}
        if not _null_excluded((eff,), ci):
            tried[eff]["rejected"] = "its 95% interval contains the null value"
            break
        current, cur_vals, cur_sse, cur_err = best["ext"], best["values"], best["sse"], best["err"]
        findings = [f for f in findings if f["effect"] in current]
        findings.append({
            "effect": eff,
            "params": {k: v for k, v in best["values"].items() if k in own},
            "ci95": {k: v for k, v in ci.items() if k in own},
            "evidence": {"signature": sig.get(eff, {}).get("text", ""),
                         "fit": f"held-out one-step MSE lowered by {best['gain']:.2e} (margin {best['margin']:.2e}), "
                                f"dBIC = {best['dbic']:.1f}"},
            "error_heldout": {"one_step_rms": float(math.sqrt(np.mean(best["err"]["one_step_mse"]))),
                              "free_run_log_peak_rms": float(np.mean(best["err"]["free_rms"]))},
            "gain": {"one_step_rms": float(math.sqrt(np.mean(base_err["one_step_mse"]))
                                           - math.sqrt(np.mean(best["err"]["one_step_mse"]))),
                     "free_run_log_peak_rms": float(np.mean(base_err["free_rms"]) - np.mean(best["err"]["free_rms"]))},
        })
    # parameters of the final combination (refit together)
    for f in findings:
        own = {q[0] for q in PARAMS[f["effect"]]}
        f["params"] = {k: v for k, v in cur_vals.items() if k in own}
    structure = _structure(tests, current, cur_vals)
    findings.sort(key=lambda f: -f["gain"]["one_step_rms"])
    entry = {
        "scope": scope, "key": key, "boundary": boundary, "n_tests": len(tests), "n_impacts": n_obs_all,
        "base": base,
        "what_is_wrong": ("the base model explains the data within the noise: " if not current and not structure
                          else "") + what_is_wrong(base, tests, sig),
        "verdict": [f["effect"] for f in findings],
        "unexplained": bool(structure),
        "residual_structure": structure,
        "findings": findings,
        "rejected": {k: {"gain": v["gain"], "margin": v["margin"], "dbic": v["dbic"],
                         **({"reason": v["rejected"]} if "rejected" in v else {})}
                     for k, v in tried.items() if k not in current},
        "heldout": {"base_one_step_rms": float(math.sqrt(np.mean(base_err["one_step_mse"]))),
                    "base_free_run_log_peak_rms": float(np.mean(base_err["free_rms"])),
                    "model_one_step_rms": float(math.sqrt(np.mean(cur_err["one_step_mse"]))),
                    "model_free_run_log_peak_rms": float(np.mean(cur_err["free_rms"]))},
    }
    if current:
        entry["extended"] = {"effects": list(current), "params": cur_vals,
                             "errors": engineering_errors(tests, current, cur_vals, n_history=n_history)}
    return entry


def what_is_wrong(base, tests, sig):
    """Plain statement, in numbers, of where the base model departs from the tests."""
    e = base["errors"]
    n, d, T = e["n_impacts"], e["peak_decay_pct_per_impact"], e["duration_s"]
    parts = []
    if n["model"] > 1.2 * n["measured"] + 1:
        parts.append(f"the simulation keeps rocking for {n['model']:.0f} impacts where the wall stops after "
                     f"{n['measured']:.0f}")
    elif n["model"] < 0.8 * n["measured"] - 1:
        parts.append(f"the simulation stops after {n['model']:.0f} impacts where the wall rocks for "
                     f"{n['measured']:.0f}")
    parts.append(f"its peak decays {d['model']:.1f}% per impact against {d['measured']:.1f}% measured")
    parts.append(f"it lasts {T['model']:.2f} s against {T['measured']:.2f} s")
    if abs(e["phase_drift_deg"]) > 30:
        parts.append(f"it drifts {e['phase_drift_deg']:+.0f} deg in phase by the last common impact")
    if e["period_amplitude_rms_log"] > 0.05:
        parts.append(f"its flight times at the measured amplitudes are off by "
                     f"{100 * e['period_amplitude_rms_log']:.0f}% rms")
    return "; ".join(parts) + "."


def diagnose_campaign(series_records, *, n_boot=40, n_history=2, by_boundary=True):
    """Diagnose every series and every boundary condition of a campaign.

    Parameters
    ----------
    series_records : dict
        series id -> list of test records (dicts for :func:`peak_series`) or PeakSeries.
    by_boundary : bool
        Add one entry per boundary condition (all its series pooled).

    Returns
    -------
    list of dict
        The content of results/diagnosis.json.
    """
    pooled = {}
    entries = []
    for sid, recs in series_records.items():
        tests = [r if isinstance(r, PeakSeries) else peak_series(r) for r in recs]
        tests = [t for t in tests if t.n_impacts >= 1]
        if not tests:
            continue
        entries.append(diagnose_series(tests, key=str(sid), scope="series", n_boot=n_boot, n_history=n_history))
        pooled.setdefault(tests[0].boundary, []).extend(tests)
    if by_boundary:
        for b in ("two-sided", "one-sided"):
            if b in pooled:
                entries.append(diagnose_series(pooled[b], key=b, scope="boundary", n_boot=n_boot,
                                               n_history=n_history))
    return entries


def write_diagnosis(entries, json_path, md_path=None):
    """Write results/diagnosis.json (and diagnosis.md) from :func:`diagnose_campaign` entries."""
    from pathlib import Path
    Path(json_path).write_text(json.dumps(entries, indent=1, default=float))
    if md_path is not None:
        Path(md_path).write_text(diagnosis_markdown(entries))


def diagnosis_markdown(entries) -> str:
    """Readable report (results/diagnosis.md) of :func:`diagnose_campaign` entries."""
    out = ["# Model diagnosis", ""]
    for e in entries:
        out += [f"## {e['scope']} {e['key']} ({e.get('boundary', '')}, {e['n_tests']} tests)", "",
                f"Base model: {e['base']['model']}.", "", f"What it gets wrong: {e['what_is_wrong']}", ""]
        v = ", ".join(e["verdict"]) if e["verdict"] else "none"
        out.append(f"**Verdict: {v}**" + (" — **unexplained** structure remains: "
                                            + "; ".join(e.get("residual_structure", [])) if e["unexplained"] else ""))
        out.append("")
        if e["findings"]:
            out += ["| effect | parameters | 95% CI | held-out error (one-step / free run) | gain | evidence |",
                    "|---|---|---|---|---|---|"]
            for f in e["findings"]:
                pr = ", ".join(f"{k} = {x:.3g}" for k, x in f["params"].items())
                ci = ", ".join(f"[{a:.3g}, {b:.3g}]" for a, b in f["ci95"].values())
                er = f"{f['error_heldout']['one_step_rms']:.3f} / {f['error_heldout']['free_run_log_peak_rms']:.3f}"
                ga = f"{f['gain']['one_step_rms']:.3f} / {f['gain']['free_run_log_peak_rms']:.3f}"
                out.append(f"| {f['effect']} | {pr} | {ci} | {er} | {ga} | {f['evidence']['signature']} |")
            out.append("")
        h = e.get("heldout", {})
        if h:
            out += [f"Held-out log-peak error: base {h['base_one_step_rms']:.3f} (one-step), "
                    f"{h['base_free_run_log_peak_rms']:.3f} (free run); chosen model "
                    f"{h['model_one_step_rms']:.3f}, {h['model_free_run_log_peak_rms']:.3f}.", ""]
        alt = e["base"].get("alternatives")
        if alt:
            for name, er in alt.items():
                out.append(f"- literature alternative {name}: {er['n_impacts']['model']:.0f} impacts, "
                           f"decay {er['peak_decay_pct_per_impact']['model']:.1f}%/impact, "
                           f"free-run log-peak error {er['log_peak_rms']:.3f}")
            out.append("")
    return "\n".join(out)


def records_by_series(datasets):
    """Group reduced tests (``rocklab.reduction``) into the records of :func:`diagnose_campaign`."""
    out = {}
    for ds in datasets:
        a = ds.attrs
        out.setdefault(a["series"], []).append({
            "test_id": a["test_id"], "t": ds.time.values, "theta": ds.theta.values,
            "fs": float(a["sampling_rate_hz"]), "alpha": float(a["alpha"]), "p": float(a["p"]),
            "boundary": a["boundary"], "direction": a["direction"],
        })
    return dict(sorted(out.items()))
