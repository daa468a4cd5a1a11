"""Energy dissipation of free-rocking tests (Sects. 3-4 of the paper).

Per test (:func:`motion_tables` of its motion, :mod:`rocklab.lab.motion`):
e_exp after n impacts by Eq. 10 and Eq. 11 for every n (Fig. 11), the
analytic e (Eq. 2 two-sided, Eq. 14 one-sided, nominal alpha), e_exp /
e_an, the windows of Table 3, the per-impact e_k, the impact velocity over
the overturning velocity (Eq. 16), theta0/alpha (Figs. 10, 16), p T_1/4
against Housner's closed form (Fig. 17, :func:`quarter_period_linear`),
cycles (Fig. 18), p D (Fig. 19) and, from the stored motion of a test
(:func:`analyse_stored_motion`), the channel-5 amplification (Fig. 20).  Per
table: the amplitude laws of Eqs. 15 and 17 (:func:`amplitude_law_fit`) and
the no-sliding check of Eq. 9.

Conventions
-----------
* e_exp (Eqs. 10-11) is the positive 2n-th root; e_an keeps its sign
  (negative for one-sided rocking, Eq. 14) and every ratio is
  e_exp / |e_an|, as in Figs. 11, 13 and Table 3.
* Eqs. 10-11 use alpha_ind = theta0 (Sect. 3); e_an, the normalisations
  theta/alpha and Eq. 16 use the nominal alpha = arctan(b/h).
* A half cycle is the motion from one peak to the next through one impact,
  so n_cycles = n_impacts / 2 for both boundary conditions.
* Only peaks above the noise threshold of :mod:`rocklab.lab.motion` are used;
  "whole history" means from theta0 to the last reliable peak.
* T_1/4 runs from the instant the wall leaves the screw to the first
  impact (:mod:`rocklab.lab.motion`, "Release and first quarter period"); the
  closed forms it is compared with use the instability angle of the fall
  (alpha_fall), not the nominal alpha: with theta0 / alpha = 0.9 Housner's
  p T_1/4 would be 2.9, while the wall was released a few 1e-4 rad from
  its own instability point.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr
from numpy.typing import ArrayLike

from rocklab.disk import write_text
from rocklab.dissipation.regression import ols
from rocklab.lab.motion import Motion, extract_motion, motion_from_dataset, stored_motion
from rocklab.physics import restitution
from rocklab.physics.flight import quarter_period_linear
from rocklab.physics.wall import no_sliding_friction, overturning_velocity

#: Keys of the per-test summary required by results/tests.csv (the lead
#: adds test_id, series, specimen, boundary, contact_depth_mm).
TEST_COLUMNS = [
    "direction",
    "h_over_b",
    "alpha",
    "theta0",
    "theta0_over_alpha",
    "n_impacts",
    "e_an",
    "e_exp_eq10",
    "e_exp_eq11",
    "e_ratio",
    "T_quarter_p",
    "duration_p",
]
#: Columns of the per-impact table (results/impacts.csv, less test_id).
IMPACT_COLUMNS = ["k", "t_s", "peak_before_over_alpha", "thetadot_before", "thetadot_after", "v_over_vr", "e_exp_k"]
#: Columns of the e_exp-versus-n table (Fig. 11).
E_BY_N_COLUMNS = ["n", "peak_over_alpha", "e_exp_eq10", "e_exp_eq11", "e_ratio_eq10", "e_ratio_eq11"]


#: What :func:`motion_tables` gives: the test's summary, its impacts and its e_exp after n impacts.
MotionTables = tuple[dict[str, Any], pd.DataFrame, pd.DataFrame]


def e_by_n(peaks: ArrayLike, theta0: float, alpha_ind: float, alpha: float, e_an: float) -> pd.DataFrame:
    """e_exp after n = 1..N impacts by Eqs. 10 and 11 (Fig. 11).

    Parameters
    ----------
    peaks : array_like
        |theta| of the reliable peaks after impacts 1..N [rad].
    theta0 : float
        Initial rotation [rad].
    alpha_ind : float
        Angle of Eqs. 10-11 (theta0 in the paper) [rad].
    alpha : float
        Nominal alpha for peak_over_alpha [rad].
    e_an : float
        Analytic coefficient (signed) for the ratios.
    """
    peaks = np.asarray(peaks, float)
    n = np.arange(1, peaks.size + 1)
    e10 = restitution.experimental_housner(peaks, theta0, alpha_ind, n)
    e11 = restitution.experimental_pena(peaks, theta0, alpha_ind, n)
    return pd.DataFrame(
        {
            "n": n,
            "peak_over_alpha": peaks / alpha,
            "e_exp_eq10": e10,
            "e_exp_eq11": e11,
            "e_ratio_eq10": e10 / abs(e_an),
            "e_ratio_eq11": e11 / abs(e_an),
        }
    )


def per_impact_e(peaks: ArrayLike, theta0: float, alpha_ind: float) -> np.ndarray:
    """e_k by Eq. 11 with n = 1 from peak k-1 to peak k (peak 0 = theta0)."""
    peaks = np.asarray(peaks, float)
    before = np.r_[theta0, peaks[:-1]]
    return restitution.experimental_pena(peaks, before, alpha_ind, 1)


def table3_windows(peaks: ArrayLike, theta0: float, alpha_ind: float, e_an: float) -> dict[str, float]:
    """e_exp / |e_an| by Eq. 11 over the windows of Table 3.

    complete: theta0 to peak N (n = N); without the first half cycle: peak 1
    to peak N (n = N - 1); first half cycle only: theta0 to peak 1 (n = 1).
    NaN where the window is empty.
    """
    peaks = np.asarray(peaks, float)
    N = peaks.size
    nan = np.nan
    eq11 = restitution.experimental_pena
    complete = eq11(peaks[-1], theta0, alpha_ind, N) if N else nan
    without = eq11(peaks[-1], peaks[0], alpha_ind, N - 1) if N > 1 else nan
    first = eq11(peaks[0], theta0, alpha_ind, 1) if N else nan
    return {
        "e_ratio_complete": float(complete) / abs(e_an),
        "e_ratio_without_first_half_cycle": float(without) / abs(e_an),
        "e_ratio_first_half_cycle": float(first) / abs(e_an),
    }


def analyse_motion(
    t: ArrayLike,
    theta: ArrayLike,
    fs: float,
    boundary: str,
    alpha: float,
    p: float,
    direction: str,
    *,
    alpha_ind: float | None = None,
    **motion_kw: Any,
) -> MotionTables:
    """:func:`motion_tables` of a free-rocking record (Sects. 3-4).

    Parameters
    ----------
    t, theta : ndarray
        Time [s] and rotation [rad] (Eq. 8 or the four-dof solution).
    fs : float
        Sampling rate [Hz].
    boundary, alpha, p, direction, alpha_ind
        As :func:`motion_tables`.
    **motion_kw
        Passed to :func:`rocklab.lab.motion.extract_motion`.
    """
    m = extract_motion(t, theta, fs, boundary, p, **motion_kw)
    return motion_tables(m, boundary, alpha, p, direction, alpha_ind=alpha_ind)


def motion_tables(
    m: Motion, boundary: str, alpha: float, p: float, direction: str, *, alpha_ind: float | None = None
) -> MotionTables:
    """Energy dissipation of one free-rocking motion (Sects. 3-4).

    Parameters
    ----------
    m : rocklab.lab.motion.Motion
        The motion of the record (:func:`rocklab.lab.motion.extract_motion`).
    boundary : {"two-sided", "one-sided"}
    alpha : float
        Nominal slenderness angle arctan(b/h) [rad].
    p : float
        Frequency parameter [rad/s].
    direction : {"push", "pull"}
        Copied to the summary.
    alpha_ind : float, optional
        Angle of Eqs. 10-11; defaults to the measured theta0 (Sect. 3).

    Returns
    -------
    summary : dict
        :data:`TEST_COLUMNS` first, then diagnostics: alpha_ind,
        e_ratio_complete / _without_first_half_cycle / _first_half_cycle,
        n_cycles, alpha_fall (instability angle of the fitted fall),
        theta0_over_alpha_fall, thetadot_release (speed leaving the screw),
        T_quarter_p_housner (Housner's closed form from rest at
        theta0/alpha_fall), T_quarter_p_linear (the same with the release
        speed, :func:`quarter_period_linear`), t_release, t_first_impact,
        t_end, noise_rad, n_negative_excursions, max_negative_over_alpha.
        T_quarter_p is p (t_first_impact - t_release), the release being
        where the wall leaves the screw (:mod:`rocklab.lab.motion`).
    impacts : pandas.DataFrame
        :data:`IMPACT_COLUMNS`, one row per impact followed by a reliable peak.
    e_n : pandas.DataFrame
        :data:`E_BY_N_COLUMNS`.
    """
    a_ind = m.theta0 if alpha_ind is None else float(alpha_ind)
    e_an = float(restitution.analytic(boundary, alpha))
    N = m.peaks.size
    e_n = e_by_n(m.peaks, m.theta0, a_ind, alpha, e_an)
    e10 = float(e_n.e_exp_eq10.iloc[-1]) if N else np.nan
    e11 = float(e_n.e_exp_eq11.iloc[-1]) if N else np.nan
    imp = m.impacts
    vr = overturning_velocity(alpha, p)
    impacts = pd.DataFrame(
        {
            "k": imp.k.to_numpy(int),
            "t_s": imp.t_s.to_numpy(),
            "peak_before_over_alpha": imp.peak_before.to_numpy() / alpha,
            "thetadot_before": imp.thetadot_before.to_numpy(),
            "thetadot_after": imp.thetadot_after.to_numpy(),
            "v_over_vr": np.abs(imp.thetadot_before.to_numpy()) / vr,
            "e_exp_k": per_impact_e(m.peaks, m.theta0, a_ind),
        }
    )
    summary = {
        "direction": direction,
        "h_over_b": float(1.0 / np.tan(alpha)),
        "alpha": float(alpha),
        "theta0": m.theta0,
        "theta0_over_alpha": m.theta0 / alpha,
        "n_impacts": int(N),
        "e_an": e_an,
        "e_exp_eq10": e10,
        "e_exp_eq11": e11,
        "e_ratio": e11 / abs(e_an),
        "T_quarter_p": p * (m.t_first_impact - m.t_release),
        "duration_p": p * (m.t_end - m.t_release),
        "alpha_ind": a_ind,
        **table3_windows(m.peaks, m.theta0, a_ind, e_an),
        "n_cycles": N / 2.0,
        "alpha_fall": m.alpha_fall,
        "theta0_over_alpha_fall": m.theta0 / m.alpha_fall,
        "thetadot_release": m.thetadot_release,
        "T_quarter_p_housner": float(quarter_period_linear(m.theta0 / m.alpha_fall)),
        "T_quarter_p_linear": float(
            quarter_period_linear(m.theta0 / m.alpha_fall, m.thetadot_release / (p * m.alpha_fall))
        ),
        "t_release": m.t_release,
        "t_first_impact": m.t_first_impact,
        "t_end": m.t_end,
        "noise_rad": m.noise_rad,
        "n_negative_excursions": m.n_negative_excursions,
        "max_negative_over_alpha": float(imp.negative_excursion.max() / alpha) if N else 0.0,
    }
    return summary, impacts, e_n


def _amplitude_line(x: np.ndarray, y: np.ndarray) -> dict[str, float]:
    """y = a - b x by least squares (:func:`~rocklab.dissipation.regression.ols`): a, b, R^2, standard errors, n."""
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    n = x.size
    if n < 3 or np.ptp(x) == 0:
        return dict(a=np.nan, b=np.nan, r2=np.nan, a_se=np.nan, b_se=np.nan, n=n)
    X = np.column_stack([np.ones(n), -x])
    coef, cov, _ = ols(y, X)
    res = y - X @ coef
    ss_res, ss_tot = res @ res, ((y - y.mean()) ** 2).sum()
    return dict(
        a=coef[0],
        b=coef[1],
        r2=1 - ss_res / ss_tot if ss_tot > 0 else np.nan,
        a_se=np.sqrt(cov[0, 0]),
        b_se=np.sqrt(cov[1, 1]),
        n=n,
    )


def amplitude_law_fit(
    impacts_df: pd.DataFrame, tests_df: pd.DataFrame, by: Sequence[str] = ("series",), law: str = "peak"
) -> pd.DataFrame:
    """Fit the amplitude law of Eq. 15 or Eq. 17 by group, with R^2.

    e_exp_k / |e_an| = a - b x, x = peak_before_over_alpha (``law="peak"``,
    Eq. 15) or v_over_vr**2 (``law="velocity"``, Eq. 17).

    Parameters
    ----------
    impacts_df : pandas.DataFrame
        results/impacts.csv (test_id + :data:`IMPACT_COLUMNS`).
    tests_df : pandas.DataFrame
        results/tests.csv: test_id, e_an and the grouping columns.
    by : sequence of str
        Grouping columns of ``tests_df`` (e.g. ("series",), ("boundary",));
        empty for one pooled fit.

    Returns
    -------
    pandas.DataFrame
        by-columns, law, a, b, r2, a_se, b_se, n (impacts), n_tests and
        n_series (where ``tests_df`` has ``series``) they come from; the
        standard errors take the impacts as independent.
    """
    if law not in ("peak", "velocity"):
        raise ValueError("law must be 'peak' (Eq. 15) or 'velocity' (Eq. 17)")
    by = list(by)
    units = ["series"] if "series" in tests_df and "series" not in by else []
    d = impacts_df.merge(tests_df[["test_id", "e_an", *by, *units]], on="test_id", how="inner")
    d["ratio"] = d.e_exp_k / d.e_an.abs()
    d["x"] = d.peak_before_over_alpha if law == "peak" else d.v_over_vr**2
    groups = d.groupby(by, sort=True) if by else [((), d)]
    rows = []
    for key, g in groups:
        key = key if isinstance(key, tuple) else (key,)
        used = g[np.isfinite(g.x) & np.isfinite(g.ratio)]
        counts = {"n_tests": used.test_id.nunique()}
        if "series" in used:
            counts["n_series"] = used.series.nunique()
        rows.append(
            {
                **dict(zip(by, key)),
                "law": law,
                **_amplitude_line(g.x.to_numpy(float), g.ratio.to_numpy(float)),
                **counts,
            }
        )
    return pd.DataFrame(rows)


def no_sliding_check(h_over_b: ArrayLike, mu_s: float = 0.6) -> pd.DataFrame:
    """No-sliding condition of free rocking, Eq. 9 (Shenton 1996).

    Returns a DataFrame with h_over_b, mu_required = 3 zeta / (1 + 4 zeta^2),
    the sufficient bound b/h and ``no_sliding`` (mu_s >= mu_required);
    mu_s = 0.6 is the low end of masonry friction (Rankine 1863, Sect. 2.2).
    """
    z = np.atleast_1d(np.asarray(h_over_b, float))
    mu = no_sliding_friction(z)
    return pd.DataFrame({"h_over_b": z, "mu_required": mu, "b_over_h": 1.0 / z, "no_sliding": mu_s >= mu})


META_COLUMNS = ["test_id", "series", "specimen", "boundary", "contact_depth_mm"]


def analyse_stored_motion(ds: xr.Dataset) -> MotionTables:
    """:func:`motion_tables` of a stored motion (:func:`rocklab.lab.motion.stored_motion`).

    Returns the three tables of :func:`motion_tables`, each carrying the
    test's metadata columns first; the summary also holds
    ``centre_amplification`` (Fig. 20b) from the stored motion.

    Raises
    ------
    ValueError
        When no motion could be extracted from the test.
    """
    a = ds.attrs
    summary, impacts, e_n = motion_tables(
        motion_from_dataset(ds), a["boundary"], float(a["alpha"]), float(a["p"]), a["direction"]
    )
    summary["centre_amplification"] = float(a["centre_amplification"])
    meta = {k: a.get(k, np.nan) for k in META_COLUMNS}
    return (
        {**meta, **summary},
        impacts.assign(test_id=a["test_id"])[["test_id", *impacts.columns]],
        e_n.assign(test_id=a["test_id"], series=a["series"], boundary=a["boundary"]),
    )


def analyse_reduced_test(ds: xr.Dataset) -> MotionTables:
    """:func:`analyse_stored_motion` of a reduced test (``rocklab.lab.reduction``)."""
    return analyse_stored_motion(stored_motion(ds))


def _frame_json(frame: pd.DataFrame) -> dict[str, Any]:
    """A table as JSON: its columns, their dtypes and values (floats as Python writes them: exact)."""
    return {
        "columns": list(frame.columns),
        "dtypes": [str(t) for t in frame.dtypes],
        "data": {c: frame[c].tolist() for c in frame.columns},
    }


def _frame_of(js: Mapping[str, Any]) -> pd.DataFrame:
    return pd.DataFrame({c: pd.Series(js["data"][c], dtype=t) for c, t in zip(js["columns"], js["dtypes"])})


@dataclass
class AnalysedTests:
    """The per-test tables of Sects. 3-4 (:func:`analyse_stored_motion`) of some tests, in their order.

    The reduction job that extracts a test's motion analyses it while the
    motion is in memory (results/reduction/<job>.dissipation.json,
    :meth:`write`), so that the campaign's tables (:func:`rocklab.dissipation.statistics.campaign_tables`)
    need not open each test's file again: netCDF-C spends longer opening a
    reduced test than the analysis takes, and a job that opened every test
    of a campaign would grow with it.

    Attributes
    ----------
    tests : list of dict
        The summary of each test analysed (``results/tests.csv``'s row), with its ``unit``.
    impacts, e_by_n : pandas.DataFrame
        The impacts and e_exp after n impacts of those tests, one after the other.
    failed : list of (str, str)
        The tests whose motion could not be analysed, and why.
    """

    tests: list[dict[str, Any]] = field(default_factory=list)
    impacts: pd.DataFrame = field(default_factory=pd.DataFrame)
    e_by_n: pd.DataFrame = field(default_factory=pd.DataFrame)
    failed: list[tuple[str, str]] = field(default_factory=list)

    @classmethod
    def of(cls, motions: Iterable[xr.Dataset]) -> AnalysedTests:
        """:func:`analyse_stored_motion` of each stored motion; one that raises is listed in ``failed``."""
        tests, impacts, e_n, failed = [], [], [], []
        for ds in motions:
            try:
                s, i, e = analyse_stored_motion(ds)
            except ValueError as exc:
                failed.append((str(ds.attrs["test_id"]), str(exc)))
                continue
            tests.append({**s, "unit": ds.attrs.get("unit", "")})
            impacts.append(i)
            e_n.append(e)

        def stacked(frames: list[pd.DataFrame]) -> pd.DataFrame:
            return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()

        return cls(tests, stacked(impacts), stacked(e_n), failed)

    @classmethod
    def joined(cls, parts: Iterable[AnalysedTests], test_ids: Sequence[str]) -> AnalysedTests:
        """The tests ``test_ids`` of ``parts`` (those analysed or failed), in that order."""
        parts = list(parts)
        rank = {t: i for i, t in enumerate(test_ids)}
        tests = sorted((r for p in parts for r in p.tests if r["test_id"] in rank), key=lambda r: rank[r["test_id"]])

        def ordered(frames: list[pd.DataFrame]) -> pd.DataFrame:
            frames = [f for f in frames if len(f)]
            if not frames:
                return pd.DataFrame()
            frame = pd.concat(frames, ignore_index=True)
            frame = frame[frame.test_id.isin(rank)]
            order = np.argsort(frame.test_id.map(rank).to_numpy(), kind="stable")
            return frame.iloc[order].reset_index(drop=True)

        failed = sorted((f for p in parts for f in p.failed if f[0] in rank), key=lambda f: rank[f[0]])
        return cls(tests, ordered([p.impacts for p in parts]), ordered([p.e_by_n for p in parts]), failed)

    def write(self, path: str | Path) -> None:
        """Write to ``path`` (JSON; NaN as ``NaN``), as :meth:`read` reads it back, equal to the bit."""
        js = {
            "tests": self.tests,
            "impacts": _frame_json(self.impacts),
            "e_by_n": _frame_json(self.e_by_n),
            "failed": self.failed,
        }
        write_text(path, json.dumps(js, default=_plain) + "\n")

    @classmethod
    def read(cls, path: str | Path) -> AnalysedTests:
        """The tables :meth:`write` wrote to ``path``."""
        js = json.loads(Path(path).read_text())
        return cls(js["tests"], _frame_of(js["impacts"]), _frame_of(js["e_by_n"]), [tuple(f) for f in js["failed"]])


def _plain(x: Any) -> Any:
    # a summary's numbers can be NumPy scalars (attributes read from a file)
    if isinstance(x, np.generic):
        return x.item()
    raise TypeError(f"{type(x).__name__} is not JSON")
