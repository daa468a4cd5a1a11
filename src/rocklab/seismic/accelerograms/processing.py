"""Baseline correction and ground-motion parameters of an accelerogram (PGA, PGV, durations).

Baseline correction follows the usual strong-motion practice (e.g. Boore &
Bommer 2005, "Processing of strong-motion accelerograms"; PEER NGA and
Caltech Vol. II processing):

1. remove the mean of the pre-event portion (first ``pre_event`` seconds) or,
   when there is none, of the whole record;
2. integrate to velocity and least-squares fit a polynomial of order
   ``velocity_order`` (default 1: a straight line) to it; subtract the fit's
   time derivative from the acceleration.  Order 1 removes the constant
   acceleration offset that makes velocity drift linearly, order 2 a linear
   acceleration trend (quadratic velocity drift);
3. optionally, an acausal (zero-phase) Butterworth band-pass
   ``freqmin``-``freqmax`` Hz of ``corners`` poles, after a half-cosine taper
   of ``taper`` seconds at each end and zero padding of 1.5 / ``freqmin``
   seconds on each side (removed afterwards).  The taper is short on purpose:
   records such as El Centro 1940 have their peaks within 3 s of the start,
   which a 5 %-of-record taper would cut.

The Table 4 records are *already corrected* (PEER NGA, legacy PEER and
Caltech Vol. II are band-passed, the column files are copies of corrected
records), so the default used by :func:`rocklab.seismic.accelerograms.load_record` is
steps 1-2 only: a guard against residual offsets and the rounding of the text
values, which leaves PGA unchanged to well within 0.1 %.  Filtering again would
lower the peaks of records that were processed with other corners.

Peak ground velocity comes from the cumulative trapezoidal integral of the
corrected acceleration (initial velocity zero).  Two durations are computed:
the record length ``(npts - 1) * dt`` (time of the last sample; this is what
Table 4 lists, e.g. 2990 x 0.005 s -> 14.945 s for RRS228) and the significant
duration D5-95 between 5 % and 95 % of the Arias intensity.
"""

from __future__ import annotations

from typing import Any, cast

import numpy as np
import numpy.typing as npt
from obspy import Trace

from rocklab.physics.constants import G
from rocklab.physics.flight import FloatArray


def cumulative_trapezoid(y: npt.ArrayLike, dx: float) -> FloatArray:
    """Cumulative trapezoidal integral of ``y`` sampled every ``dx``, starting at 0.

    The arithmetic of ``scipy.integrate.cumulative_trapezoid(y, dx=dx,
    initial=0)``, step for step, so bit for bit the same; numpy's own spares
    every job that reads a record the 0.4 s of importing scipy.integrate.

    Parameters
    ----------
    y : array_like
        Uniformly sampled values (e.g. acceleration [m/s^2]).
    dx : float
        Sample interval (e.g. [s]).

    Returns
    -------
    ndarray
        The integral at every sample, float64, in the units of ``y`` times
        those of ``dx`` (e.g. velocity [m/s]); 0 at the first.
    """
    y = np.asarray(y, float)
    return np.concatenate(([0.0], np.cumsum(dx * (y[1:] + y[:-1]) / 2.0)))


def velocity(acc: npt.ArrayLike, dt: float) -> FloatArray:
    """Velocity [m/s] by cumulative trapezoid of ``acc`` [m/s^2], v(0) = 0."""
    return cumulative_trapezoid(acc, dt)


def baseline_correct_array(
    acc: npt.ArrayLike,
    dt: float,
    pre_event: float | None = None,
    velocity_order: int | None = 1,
    freqmin: float | None = None,
    freqmax: float | None = None,
    corners: int = 4,
    taper: float = 1.0,
) -> FloatArray:
    """Baseline-corrected copy of ``acc`` [m/s^2] (steps 1-3 of the module doc).

    Parameters
    ----------
    acc : array_like
        Acceleration [m/s^2], uniformly sampled at ``dt`` [s].
    pre_event : float, optional
        Length [s] of the pre-event portion whose mean is removed; ``None``
        removes the mean of the whole record.
    velocity_order : int or None
        Order of the polynomial fitted to the velocity (``None`` or 0: skip).
    freqmin, freqmax : float, optional
        Band-pass corners [Hz]; both ``None`` skips filtering, one of them
        gives a high-pass or low-pass.
    corners : int
        Butterworth order (poles), applied forward and backward.
    taper : float
        Length [s] of the half-cosine taper at each end before filtering.
    """
    a = np.array(acc, dtype=np.float64)
    n = a.size
    t = np.arange(n) * dt
    if pre_event is not None:
        m = max(1, int(round(pre_event / dt)))
        a -= a[:m].mean()
    else:
        a -= a.mean()
    if velocity_order:
        coeff = np.polynomial.polynomial.polyfit(t, velocity(a, dt), velocity_order)
        a -= np.polynomial.polynomial.polyval(t, np.polynomial.polynomial.polyder(coeff))
    if freqmin is None and freqmax is None:
        return a
    # imported here: the default processing never filters, and scipy.signal
    # would add 0.4 s to every job that reads a record
    from scipy import signal

    nyq = 0.5 / dt
    if freqmax is not None and freqmax >= nyq:
        raise ValueError(f"freqmax {freqmax} Hz is not below the Nyquist frequency {nyq} Hz")
    pad = int(np.ceil(1.5 / freqmin / dt)) if freqmin else 0
    x = np.concatenate([np.zeros(pad), a * signal.windows.tukey(n, min(1.0, 2 * taper / (n * dt))), np.zeros(pad)])
    if freqmin and freqmax:
        sos = signal.butter(corners, [freqmin / nyq, freqmax / nyq], btype="bandpass", output="sos")
    elif freqmin:
        sos = signal.butter(corners, freqmin / nyq, btype="highpass", output="sos")
    else:
        # not None: one of the corners is, and freqmin is not
        sos = signal.butter(corners, cast(float, freqmax) / nyq, btype="lowpass", output="sos")
    return cast(FloatArray, signal.sosfiltfilt(sos, x)[pad : pad + n])


def baseline_correct(trace: Trace, **kwargs: Any) -> Trace:
    """Baseline-corrected copy of an obspy Trace in m/s^2 (see :func:`baseline_correct_array`).

    The parameters used are appended to ``stats.processing``.
    """
    out = trace.copy()
    out.data = baseline_correct_array(trace.data, trace.stats.delta, **kwargs)
    out.stats.processing = list(out.stats.get("processing", [])) + [f"rocklab.baseline_correct({describe(**kwargs)})"]
    return out


def describe(
    pre_event: float | None = None,
    velocity_order: int | None = 1,
    freqmin: float | None = None,
    freqmax: float | None = None,
    corners: int = 4,
    taper: float = 1.0,
) -> str:
    """One-line text of a baseline-correction setting (for manifests and stats.processing)."""
    steps = [f"mean removed (pre-event {pre_event:.2f} s)" if pre_event is not None else "mean removed (whole record)"]
    if velocity_order:
        steps.append(f"order-{velocity_order} polynomial fitted to velocity removed")
    if freqmin is not None or freqmax is not None:
        steps.append(f"acausal Butterworth {corners}-pole {freqmin}-{freqmax} Hz, {taper:g} s cosine tapers")
    return "; ".join(steps)


def peak_ground_acceleration(acc: npt.ArrayLike) -> float:
    """PGA: max |a|, in the units of ``acc``."""
    return float(np.max(np.abs(acc)))


def peak_ground_velocity(acc: npt.ArrayLike, dt: float) -> float:
    """PGV [m/s]: max |v| of the trapezoidal integral of ``acc`` [m/s^2]."""
    return float(np.max(np.abs(velocity(acc, dt))))


def record_duration(npts: int, dt: float) -> float:
    """Record length [s] as the time of the last sample, (npts - 1) dt (Table 4's D)."""
    return (npts - 1) * dt


def arias_intensity(acc: npt.ArrayLike, dt: float) -> FloatArray:
    """Cumulative Arias intensity [m/s]: pi / (2 g) * integral of a^2 dt."""
    return np.pi / (2 * G) * cumulative_trapezoid(np.asarray(acc, float) ** 2, dt)


def significant_duration(acc: npt.ArrayLike, dt: float, start: float = 0.05, end: float = 0.95) -> float:
    """Significant duration [s] between ``start`` and ``end`` fractions of the Arias intensity."""
    ia = arias_intensity(acc, dt)
    frac = ia / ia[-1]
    t = np.arange(frac.size) * dt
    return float(np.interp(end, frac, t) - np.interp(start, frac, t))


def ground_motion_parameters(trace: Trace) -> dict[str, float]:
    """PGA [g], PGV [cm/s], record length and D5-95 [s] of a Trace in m/s^2."""
    acc, dt = trace.data, trace.stats.delta
    return {
        "pga_g": peak_ground_acceleration(acc) / G,
        "pgv_cm_s": 100.0 * peak_ground_velocity(acc, dt),
        "duration_s": record_duration(trace.stats.npts, dt),
        "d5_95_s": significant_duration(acc, dt),
    }
