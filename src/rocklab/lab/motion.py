"""Free-rocking motion of one test: release, impacts, peaks, end of motion.

From a uniformly sampled rotation history theta(t) [rad] (Sect. 2.2, Eq. 8)
this module finds the quantities that Sects. 3-4 of the paper build on: the
release instant and the initial rotation theta0 (``alpha_ind = theta0``), the
impacts (base impacts at theta = 0; in one-sided rocking the rebound, which
includes the impact on the transverse walls), the peak |theta| between
impacts, the angular velocity just before and just after each impact and the
end of the motion.

Velocities come from the linearised flight fitted on each side of an
impact, the transducer ringing excluded (:mod:`rocklab.lab.flight_fit`, the
derivative filter); a peak is the extremum of the same model fitted over
+-0.6/p clipped to the flight between its two impacts (a "local parabola"
that stays exact away from the apex).  The release (the instant the wall
leaves the screw, theta0, the instability angle of the fall and the speed
at the release) is :func:`rocklab.lab.release.screw_departure`.

End of the motion
-----------------
The motion ends at the first extremum that is not the apex of a flight
above the noise: its refined value must exceed ``k_noise`` times the noise,
the raw record must reach that level in the flight (the smoother overshoots
where a wall stops dead at theta = 0, typically back from the gap of a
one-sided wall, and makes a bump that is not in the data), and the fitted
curvature must be that of a wall turning back under gravity, |theta''| >=
p^2 (theta0 - |theta|) / 2 (theta'' = -p^2 (alpha - |theta|) in flight),
which the slow residual drift of a settled wall is not.  The last flight's
fit stops where the wall is back at theta ~ 0, crossing or not: a wall that
lands and stops does not cross, and the rest beyond is no flight.  Without
these rules 234 of the 298 one-sided tests of the embedded campaign ended
on a spurious "impact" with e_k ~ 0.2, which hid the amplitude dependence
of Eq. 15, and 24 of the 154 two-sided tests on a mis-fitted last peak;
with them, none.  Take-off velocities are not used for this: those of the
short last flights are too uncertain and would cut real ones.

Stored motion
-------------
The workflow extracts the motion of each test once, in the reduction job of
its series, and stores it inside the reduced test's file
``results/tests/<job>/<test_id>.nc``, as its netCDF-4 group :data:`MOTION_GROUP`
(:func:`write_test_with_motion`; one file per test, not two: a third of the
reduction's time was the writing of a second file): the :class:`Motion`
(:func:`motion_to_dataset`), who the test is and the constants of its wall
(:data:`TEST_ATTRS`), and the channel-5 amplification of Fig. 20b
(:func:`stored_motion`).  The dissipation tables, the diagnosis and its
figures read it back (:func:`read_stored_motion`, :func:`read_motion`,
:func:`rocklab.diagnosis.evidence.stored_records`, with the rotation in one open,
:func:`valid_stored_motions`) instead of extracting the motion again.

All angles are returned as magnitudes of the rotation measured on the side
of release (``sign`` gives that side); velocities keep the sign of the input.

Size: one topic read top to bottom, a test's motion from its extraction to
its stored form, every function with its types (just past the limit).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import pandas as pd
import xarray as xr
from numpy.typing import ArrayLike

from rocklab.io import cf_attrs, read_dataset, valid_tests, write_netcdf
from rocklab.lab import kinematics
from rocklab.lab.channels import LOST_STATUSES
from rocklab.lab.flight_fit import local_fit, model_value, model_velocity, odd_samples, root_tau, stationary_tau
from rocklab.lab.inertial import impacts_from_rate
from rocklab.lab.release import screw_departure
from rocklab.lab.rotation import FlightFits, flight_fits, unseen_impacts
from rocklab.physics.boundary import Boundary
from rocklab.physics.flight import quarter_period_linear

#: Group of a reduced test's netCDF file that holds its stored motion.
MOTION_GROUP = "motion"
#: Columns of :attr:`Motion.impacts`, in order.
IMPACT_FIELDS = (
    "k",
    "t_s",
    "t_after_s",
    "thetadot_before",
    "thetadot_after",
    "negative_excursion",
    "e_velocity",
    "peak_before",
    "peak_after",
)
#: Scalar fields of :class:`Motion` and their types.
SCALAR_FIELDS = {
    "sign": int,
    "t_release": float,
    "theta0": float,
    "noise_rad": float,
    "peak_threshold": float,
    "t_first_impact": float,
    "t_end": float,
    "n_negative_excursions": int,
    "alpha_fall": float,
    "thetadot_release": float,
}
#: CF ``long_name`` and ``units`` of the variables of a stored motion.
VARIABLE_ATTRS = {
    "k": ("number of the impact, 1 the first after the release", "1"),
    "t_s": ("arrival at theta = 0 before the impact, time since the start of the record", "s"),
    "t_after_s": ("departure from theta = 0 after the impact, time since the start of the record", "s"),
    "thetadot_before": ("angular velocity just before the impact", "rad/s"),
    "thetadot_after": ("angular velocity just after the impact", "rad/s"),
    "negative_excursion": ("excursion past theta = 0 of a one-sided wall, magnitude", "rad"),
    "e_velocity": ("coefficient of restitution, thetadot_after / thetadot_before", "1"),
    "peak_before": ("peak |theta| before the impact", "rad"),
    "peak_after": ("peak |theta| after the impact", "rad"),
    "peaks": ("reliable peaks |theta| after impacts 1..n", "rad"),
}
#: CF ``source`` of a stored motion.
SOURCE = "laboratory free-rocking test, motion extracted from the reduced rotation"
#: Attributes of a reduced test that its stored motion carries: who the test
#: is, its verdict and the constants of its wall.
TEST_ATTRS = (
    "test_id",
    "series",
    "specimen",
    "boundary",
    "contact_depth_mm",
    "direction",
    "unit",
    "alpha",
    "p",
    "sampling_rate_hz",
    "valid",
    "reject_reason",
)


@dataclass(frozen=True)
class Motion:
    """Kinematic landmarks of one free-rocking test.

    Attributes
    ----------
    sign : int
        +1 if the wall was released at theta > 0, -1 otherwise.
    t_release : float
        Release instant [s] (zero velocity of the fitted fall).
    theta0 : float
        Initial rotation |theta0| [rad].
    noise_rad : float
        Robust rms of transducer noise plus hum [rad].
    peak_threshold : float
        Peaks below this [rad] are not used (``k_noise * noise_rad``).
    impacts : pandas.DataFrame
        One row per impact followed by a reliable peak: ``k``, ``t_s``
        (arrival at theta = 0), ``t_after_s`` (departure from theta = 0;
        later than ``t_s`` when a one-sided wall swings into the gap),
        ``thetadot_before``, ``thetadot_after`` [rad/s], ``e_velocity``
        (signed thetadot^+ / thetadot^-), ``peak_before``, ``peak_after``
        [rad, magnitudes], ``negative_excursion`` [rad, magnitude of the
        excursion past theta = 0 of a one-sided wall; 0 if none].
    peaks : numpy.ndarray
        |theta| of the reliable peaks after impacts 1..n [rad].
    t_first_impact : float
        First impact [s] (end of the first quarter period).
    t_end : float
        End of the motion [s]: the impact that follows the last reliable
        peak, or that peak when the record stops before the impact.
    n_negative_excursions : int
        One-sided only: impacts with an excursion past theta = 0 larger than
        the detection hysteresis (wall swinging into the gap).
    alpha_fall : float
        Instability angle of the fall [rad]: the asymptote of
        theta'' = p^2 (alpha_fall - theta) fitted from the release to half of
        theta0 (NaN when the fall could not be fitted).
    thetadot_release : float
        Speed towards the vertical with which the wall left its hold [rad/s]
        (the screw's creep; 0 from a plateau).
    """

    sign: int
    t_release: float
    theta0: float
    noise_rad: float
    peak_threshold: float
    impacts: pd.DataFrame
    peaks: np.ndarray
    t_first_impact: float
    t_end: float
    n_negative_excursions: int
    alpha_fall: float
    thetadot_release: float


def noise_level(theta: ArrayLike, fs: float) -> float:
    """Robust rms of the noise plus mains hum of a rotation record [rad].

    1.4826 MAD of the residual of a 0.1 s cubic Savitzky-Golay smoother: the
    rocking motion (a few Hz) passes the smoother, white noise and 50 Hz hum
    do not, and the median ignores the few samples around impacts.
    """
    # imported here and in extract_motion: the jobs that read stored motion
    # only (the figures of the dissipation) would pay 1 s of scipy at start-up
    from scipy.signal import savgol_filter

    theta = np.asarray(theta, float)
    win = odd_samples(0.1 * fs, 7)
    if theta.size <= win:
        return float(1.4826 * np.median(np.abs(np.diff(theta)))) / np.sqrt(2.0)
    r = theta - savgol_filter(theta, win, 3)
    return float(1.4826 * np.median(np.abs(r - np.median(r))))


def _crossings(u: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """Indices i where u passes from >= 0 at i to < 0 at i+1 (or vice versa)."""
    s = np.signbit(u[lo:hi])
    return lo + np.flatnonzero(s[1:] != s[:-1])


def _arrival(us: np.ndarray, i: int, level: float) -> int | None:
    """First index after i where the smoothed |rotation| us is back within
    ``level`` of zero (None if the record ends first)."""
    back = np.flatnonzero(us[i:] <= level)
    return i + int(back[0]) if back.size else None


#: Samples a flight needs for the local fit of its apex (apex, its instant and the curvature: three
#: parameters, two degrees of freedom left); a shorter one is read as a few samples near a corner.
MIN_APEX_SAMPLES = 5


def apex_resolved(A: ArrayLike, alpha: float, p: float, fs: float) -> np.ndarray | np.bool_:
    """Whether the flight of apex A [rad] on a wall (alpha [rad], p [rad/s]) spans :data:`MIN_APEX_SAMPLES`
    samples at ``fs`` [Hz]: its duration twice Housner's quarter period from the apex
    (:func:`rocklab.physics.flight.quarter_period_linear`).  The end of a motion is set on the noise; with
    quiet instruments it keeps apexes of flights of two or three samples (0.0006 alpha on a stocky wall at
    200 Hz), read some 25 % off."""
    with np.errstate(invalid="ignore"):
        return 2.0 * quarter_period_linear(np.asarray(A) / alpha) / p * fs >= MIN_APEX_SAMPLES


#: Time [s] of one flight (float) or of many (ndarray).
Times = TypeVar("Times", float, np.ndarray)


def landing_window(
    t_takeoff: Times, t_landing: Times, fs: float, width: float, ring_guard_s: float
) -> tuple[Times, Times]:
    """The window the derivative filter fits for the speed with which a flight lands [s].

    The last ``width`` seconds of the flight (``window_p`` / p), less the
    ``ring_guard_s`` that the ringing of the take-off spoils (at most 40 % of
    the flight: late flights are short) and the 2.5 samples before the
    landing, where the impact has begun.  Works on arrays.

    Returns
    -------
    lo, hi : float or ndarray
    """
    lo = np.maximum(t_takeoff + np.minimum(ring_guard_s, 0.4 * (t_landing - t_takeoff)), t_landing - width)
    return lo, t_landing - 2.5 / fs


def takeoff_window(t_takeoff: Times, t_apex: Times, width: float, ring_guard_s: float) -> tuple[Times, Times]:
    """The window the derivative filter fits for the speed with which a flight takes off [s].

    From the end of the ringing (``ring_guard_s``, at most 80 % of the rise)
    over ``width`` seconds, at most 80 % of the rise past the apex.  Works on
    arrays.

    Returns
    -------
    lo, hi : float or ndarray
    """
    rise = t_apex - t_takeoff
    lo = t_takeoff + np.minimum(ring_guard_s, 0.8 * rise)
    return lo, np.minimum(lo + width, t_apex + 0.8 * rise)


def extract_motion(
    t: ArrayLike,
    theta: ArrayLike,
    fs: float,
    boundary: str,
    p: float,
    *,
    k_noise: float = 10.0,
    ring_guard_s: float = 0.06,
    window_p: float = 0.6,
    hum_hz: Sequence[float] = (50.0,),
) -> Motion:
    """Release, impacts, peaks and end of a free-rocking record.

    Parameters
    ----------
    t : ndarray
        Time [s], uniform sampling.
    theta : ndarray
        Rotation [rad], zero at the vertical.
    fs : float
        Sampling rate [Hz] (100 or 400 in the campaign).
    boundary : {"two-sided", "one-sided"}
        Two-sided: impacts are sign changes of theta.  One-sided: theta
        stays on the release side; an impact is a return to theta ~ 0 and a
        rebound, and excursions past zero (the gap towards the transverse
        walls) belong to that impact and are reported, not counted.
    p : float
        Frequency parameter [rad/s] (rocklab.physics.wall.frequency_parameter).
    k_noise : float
        Reliable peaks exceed ``k_noise`` times the noise rms; the motion
        ends at the first extremum that is not such a peak of a flight
        (module docstring, "End of the motion").
    ring_guard_s : float
        Samples this close after an impact are excluded from the fits.
    window_p : float
        Half-width of the fit windows in units of 1/p.
    hum_hz : sequence of float
        Mains frequencies fitted as nuisance terms.

    Returns
    -------
    Motion
    """
    from scipy.signal import find_peaks, savgol_filter  # imported here: see noise_level

    if boundary not in set(Boundary):
        raise ValueError(f"boundary must be one of {tuple(b.value for b in Boundary)}, got {boundary!r}")
    t = np.asarray(t, float)
    theta = np.asarray(theta, float)
    noise = noise_level(theta, fs)
    smooth_win = odd_samples(0.025 * fs)
    sm = savgol_filter(theta, smooth_win, 2)
    sign = 1 if sm[np.argmax(np.abs(sm))] >= 0 else -1
    u = sign * theta
    us = sign * sm  # the smoothing of u itself, bit for bit: the filter is linear and odd
    t_rel, theta0, i_half, alpha_fall, v_rel = screw_departure(t, u, us, p, fs, noise)
    threshold = k_noise * noise
    hyst = 5.0 * noise
    W = window_p / p
    g_pre = 2.5 / fs

    # Flight extrema after the release: alternating signs in two-sided
    # rocking, positive only in one-sided rocking.
    pos = find_peaks(us[i_half:], prominence=hyst)[0] + i_half
    if boundary == Boundary.TWO_SIDED:
        neg = find_peaks(-us[i_half:], prominence=hyst)[0] + i_half
        ext = np.r_[pos, neg]
        ext.sort(kind="stable")
        # Keep one extremum per lobe: consecutive same-sign extrema are
        # noise-split lobes, the larger one is the peak.
        keep: list[int] = []
        for i in ext:
            if keep and np.sign(us[i]) == np.sign(us[keep[-1]]):
                if abs(us[i]) > abs(us[keep[-1]]):
                    keep[-1] = i
            else:
                keep.append(i)
        ext = np.array([i for i in keep if abs(us[i]) > hyst], int)
        # The first lobe must be on the far side of the release.
        if ext.size and us[ext[0]] > 0:
            ext = ext[1:]
    else:
        ext = pos[us[pos] > hyst]

    # Impacts: between the fall (or previous peak) and the next peak.
    starts = np.r_[i_half, ext[:-1]] if ext.size else np.array([], int)
    rows = []
    prev_after = t_rel
    for k, (a, b) in enumerate(zip(starts, ext), start=1):
        seg = u[a : b + 1]
        if boundary == Boundary.TWO_SIDED:
            cr = _crossings(seg, 0, seg.size)
            if cr.size == 0:
                break
            ib = a + int(cr[0])
            ia = a + int(cr[-1])
            tb = t[ib] + (t[ib + 1] - t[ib]) * u[ib] / (u[ib] - u[ib + 1])
            ta = t[ia] + (t[ia + 1] - t[ia]) * u[ia] / (u[ia] - u[ia + 1])
            neg_exc = 0.0
        else:
            cr = _crossings(seg, 0, seg.size)
            if cr.size:
                ib, ia = a + int(cr[0]), a + int(cr[-1])
                tb = t[ib] + (t[ib + 1] - t[ib]) * u[ib] / (u[ib] - u[ib + 1])
                ta = t[ia] + (t[ia + 1] - t[ia]) * u[ia] / (u[ia] - u[ia + 1])
            else:
                tb = ta = t[a + int(np.argmin(seg))]
            neg_exc = float(max(0.0, -u[a : b + 1].min()))
        # Velocity before: flight since the previous impact, ringing excluded
        c_b = local_fit(t, u, tb, *landing_window(prev_after, tb, fs, W, ring_guard_s), p, fs, hum_hz)
        vb = np.nan
        if c_b is not None:
            r = root_tau(c_b, p)
            tau = r if np.isfinite(r) and abs(r) < 4 * g_pre else 0.0
            tb = tb + tau
            vb = model_velocity(c_b, tau, p)
        # Velocity after: the next flight, from the end of the ringing.
        c_a = local_fit(t, u, ta, *takeoff_window(ta, t[b], W, ring_guard_s), p, fs, hum_hz)
        va = np.nan
        if c_a is not None:
            r = root_tau(c_a, p)
            tau = r if np.isfinite(r) and abs(r) < ring_guard_s else 0.0
            ta = ta + tau
            va = model_velocity(c_a, tau, p)
        rows.append((k, tb, ta, vb, va, neg_exc))
        prev_after = ta

    # Peaks: extremum of the local model within the flight after each impact,
    # and whether it is the apex of a flight (module docstring).
    peak_values: list[float] = []
    flights: list[bool] = []
    for j, i in enumerate(ext[: len(rows)]):
        lo = rows[j][2] + min(ring_guard_s, 0.8 * (t[i] - rows[j][2]))
        if j + 1 < len(rows):
            hi = rows[j + 1][1] - g_pre
        else:
            # The last flight ends where the wall comes back to theta ~ 0,
            # crossing or not (a wall that lands and stops does not cross):
            # beyond it lies the rest, which a flight model cannot fit.
            i_back = _arrival(us, i, hyst)
            hi = t[i_back] - g_pre if i_back is not None else t[-1]
        lo, hi = max(lo, t[i] - W), min(hi, t[i] + W)
        c = local_fit(t, u, t[i], lo, hi, p, fs, hum_hz)
        val = abs(us[i])
        side = np.sign(us[i])
        flight = True
        if c is not None:
            tau = stationary_tau(c, p)
            if np.isfinite(tau) and lo - t[i] <= tau <= hi - t[i]:
                val = abs(float(model_value(c, tau, p)))
            flight = -side * c[2] >= 0.5 * p**2 * (theta0 - val)
        i0, i1 = np.searchsorted(t, [lo, hi])
        raw = side * u[i0 : i1 + 1]
        peak_values.append(val)
        flights.append(flight and raw.size > 0 and raw.max() >= threshold)
    peaks = np.asarray(peak_values)

    reliable = (peaks >= threshold) & np.asarray(flights, bool)
    n_ok = int(np.argmin(reliable)) if not reliable.all() else peaks.size
    rows = rows[:n_ok] if n_ok < len(rows) else rows
    peaks = peaks[:n_ok]
    # typed even when empty, so that a stored motion reads back the same; made at once of its
    # columns (a frame retyped and filled column by column took a third of the extraction's time)
    cols = np.array([r[1:] for r in rows], float).reshape(len(rows), 5).T
    before, after = cols[2] * sign, cols[3] * sign
    with np.errstate(invalid="ignore", divide="ignore"):
        e_velocity = after / before
    imp = pd.DataFrame(
        dict(
            zip(
                IMPACT_FIELDS,
                (
                    np.array([r[0] for r in rows], int),
                    cols[0],
                    cols[1],
                    before,
                    after,
                    cols[4],
                    e_velocity,
                    np.r_[theta0, peaks[:-1]] if n_ok else np.array([]),
                    np.asarray(peaks, float),
                ),
            )
        )
    )
    n_neg = int((cols[4] > hyst).sum())
    if n_ok:
        # End: the impact after the last reliable peak, if the record has it.
        i_last = ext[n_ok - 1]
        i_back = _arrival(us, i_last, hyst)
        t_end = float(t[i_back]) if i_back is not None else float(t[i_last])
        t_first = float(imp.t_s.iloc[0])
    else:
        t_end = t_first = np.nan
    return Motion(
        sign, float(t_rel), float(theta0), noise, threshold, imp, peaks, t_first, t_end, n_neg, alpha_fall, float(v_rel)
    )


def centre_amplification(disp_centre: ArrayLike, disp_side_from_theta: ArrayLike, i_first_impact: int) -> float:
    """Channel-5 amplification of one-sided tests (Fig. 20b) [-].

    Ratio of the maximum |displacement| after the first impact measured at
    the centre of the facade (channel 5) to the one predicted at the same
    height by the rigid rotation (Eq. 8).  Both series in the same unit.
    """
    c = np.abs(np.asarray(disp_centre, float)[i_first_impact:])
    s = np.abs(np.asarray(disp_side_from_theta, float)[i_first_impact:])
    return float(np.nanmax(c) / np.nanmax(s))


def monitor_readings(ds: xr.Dataset) -> tuple[int, np.ndarray, np.ndarray] | None:
    """Monitor transducer (channel 5 at the centre of the facade, Fig. 20a).

    Its reading against the one the rigid-body motion of the reduced test
    (theta, phi, v, w of Eqs. 3-7, forward model of
    :func:`rocklab.lab.kinematics.transducer_elongation`) gives at the same
    point.  The monitor is kept out of the kinematic fit, so any excess is
    deformation of the facade (Sect. 4).  The rigid reading uses all four
    degrees of freedom rather than theta alone so that twist and sliding are
    not read as deformation.

    Parameters
    ----------
    ds : xarray.Dataset
        A reduced test (``rocklab.lab.reduction``).

    Returns
    -------
    (int, ndarray, ndarray) or None
        Channel number, measured and rigid-body elongation [mm] on ``time``;
        None when the setup has no working monitor channel.
    """
    if "channel_role" not in ds:  # a test no transducer recorded
        return None
    role = ds.channel_role.values.astype(str)
    status = ds.channel_status.values.astype(str)
    k = np.flatnonzero((role == "monitor") & ~np.isin(status, LOST_STATUSES))
    if k.size == 0:
        return None
    k = k[:1]
    X = np.column_stack([ds[f"wall_{c}"].values[k] for c in "xyz"])
    F = np.column_stack([ds[f"frame_{c}"].values[k] for c in "xyz"])
    rigid = kinematics.transducer_elongation(
        ds.theta.values, ds.phi.values, ds.v.values, ds.w.values, X, F, float(ds.attrs["thickness_mm"])
    )
    return int(ds.channel.values[k[0]]), ds.elongation.values[:, k[0]], rigid[:, 0]


def _cf_attrs(attrs: Mapping[str, Any]) -> dict[str, str]:
    return cf_attrs(f"rocklab free-rocking motion of test {attrs.get('test_id', '')}".rstrip(), SOURCE)


def motion_to_dataset(m: Motion, attrs: Mapping[str, Any] | None = None) -> xr.Dataset:
    """A :class:`Motion` as a dataset: impacts on ``impact``, peaks on ``peak``,
    the scalars as attributes (after ``attrs``); :func:`motion_from_dataset`
    reads it back."""
    data: dict[str, tuple[Any, ...]] = {name: ("impact", m.impacts[name].to_numpy()) for name in IMPACT_FIELDS}
    data["peaks"] = ("peak", np.asarray(m.peaks, float))
    for name, (long_name, units) in VARIABLE_ATTRS.items():
        data[name] += ({"long_name": long_name, "units": units},)
    attrs = attrs or {}
    return xr.Dataset(
        data,
        attrs={**_cf_attrs(attrs), **attrs, **{name: getattr(m, name) for name in SCALAR_FIELDS}},
    )


def motion_from_dataset(ds: xr.Dataset) -> Motion:
    """The :class:`Motion` of a dataset of :func:`motion_to_dataset` or :func:`stored_motion`.

    Raises
    ------
    ValueError
        When no motion could be extracted from the test (the reason).
    """
    a = ds.attrs
    if "sign" not in a:
        raise ValueError(a.get("motion_error", "no motion stored"))
    return Motion(
        impacts=pd.DataFrame({name: ds[name].values for name in IMPACT_FIELDS}),
        peaks=ds.peaks.values,
        **{name: kind(a[name]) for name, kind in SCALAR_FIELDS.items()},
    )


def read_stored_motion(path: str | Path) -> xr.Dataset:
    """The stored motion (:func:`stored_motion`) of the reduced test at ``path``
    (``results/tests/<job>/<test_id>.nc``, written by :func:`write_test_with_motion`)."""
    return read_dataset(path, group=MOTION_GROUP)


def read_motion(path: str | Path) -> Motion:
    """The :class:`Motion` stored in the reduced test at ``path`` (:func:`read_stored_motion`)."""
    return motion_from_dataset(read_stored_motion(path))


def valid_stored_motions(paths: Iterable[str | Path], qc_path: str | Path | None = None) -> Iterator[xr.Dataset]:
    """Yield the stored motions of the valid tests among the reduced tests at
    ``paths`` (:func:`read_stored_motion`; valid as
    :func:`rocklab.io.valid_tests` says)."""
    return valid_tests(paths, qc_path, group=MOTION_GROUP)


def write_test_with_motion(ds: xr.Dataset, path: str | Path) -> xr.Dataset:
    """Write the reduced test ``ds`` to ``path`` with its :func:`stored_motion`
    as the group :data:`MOTION_GROUP` (module docstring); returns that motion."""
    motion = stored_motion(ds)
    write_netcdf(ds, path, groups={MOTION_GROUP: motion})
    return motion


def instrument_fits(instrument: str, fs: float) -> FlightFits:
    """The settings of :func:`extract_motion`'s fits of the flights for a record of ``instrument`` at ``fs`` [Hz].

    A rotation record's are :func:`rocklab.lab.rotation.flight_fits`; the
    others take :func:`extract_motion`'s defaults.  The workflow's stored
    motion and the diagnosis' model of what the fits read of a flight
    (:func:`rocklab.diagnosis.flight_filter.filter_reading`) both take them here.
    """
    return flight_fits(fs) if instrument == "rotation" else {}


def stored_motion(ds: xr.Dataset) -> xr.Dataset:
    """The motion of a reduced test as the workflow stores it (module docstring).

    :func:`extract_motion` of theta with the default settings (a rotation
    record's: :func:`rocklab.lab.rotation.flight_fits`), the test's
    :data:`TEST_ATTRS`, and ``centre_amplification``: the largest |reading|
    of the monitor channel after the first impact over that of the
    rigid-body motion (:func:`monitor_readings`,
    :func:`centre_amplification`; NaN without a working monitor).  The
    impacts of a rotation record that fell on a lost stretch keep no
    velocities (:func:`rocklab.lab.rotation.unseen_impacts`); those of an
    inertial record take them from the steps of the gyroscope's rate
    (:func:`rocklab.lab.inertial.impacts_from_rate`).  A test
    with no rotation (unreadable) or no motion found keeps the reason in
    ``motion_error`` instead of the motion.

    Parameters
    ----------
    ds : xarray.Dataset
        A reduced test (``rocklab.lab.reduction``).
    """
    a = ds.attrs
    attrs = {k: a[k] for k in TEST_ATTRS if k in a}
    if "theta" not in ds:
        error = f"no rotation: {a.get('reject_detail', '')}"
        return xr.Dataset(attrs={**_cf_attrs(attrs), **attrs, "motion_error": error})
    try:
        fs = float(a["sampling_rate_hz"])
        fits = instrument_fits(a.get("instrument", ""), fs)
        m = extract_motion(ds.time.values, ds.theta.values, fs, a["boundary"], float(a["p"]), **fits)
    except ValueError as exc:
        return xr.Dataset(attrs={**_cf_attrs(attrs), **attrs, "motion_error": str(exc)})
    if "theta_lost" in ds and len(m.impacts):
        # an impact on a lost stretch of a rotation record was not measured: its velocities would be the bridge's
        unseen = unseen_impacts(m.impacts.t_s, m.impacts.t_after_s, ds.time.values, ds.theta_lost.values.astype(bool))
        impacts = m.impacts.copy()
        impacts.loc[unseen, ["thetadot_before", "thetadot_after", "e_velocity"]] = np.nan
        m = replace(m, impacts=impacts)
    if a.get("instrument") == "inertial" and len(m.impacts):
        # the gyroscope measures the velocities themselves: the steps of its rate, not the flights of its integral
        m = replace(m, impacts=impacts_from_rate(ds, m.impacts))
    amp = np.nan
    mon = monitor_readings(ds)
    if mon is not None and np.isfinite(m.t_first_impact):
        amp = centre_amplification(mon[1], mon[2], int(np.searchsorted(ds.time.values, m.t_first_impact)))
    return motion_to_dataset(m, {**attrs, "centre_amplification": amp})
