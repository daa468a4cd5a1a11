"""Figs. 14-15 of the paper for any campaign: measured, literature and extended models.

For a sample test of a series, theta/alpha against time from the release:
panel a, the measured motion with the literature models (Housner's e, Eq. 2,
for two-sided walls; Eq. 14, the two-sided e of Hogan 1992 and e = 0 of
Liberatore & Spera 2003 for one-sided walls, Fig. 15a); panel b, the same
motion with the extended model that :mod:`rocklab.diagnosis` chose for the
series (Figs. 14b, 15b).  Every model runs from the test's measured release
(:func:`rocklab.diagnosis.extended.simulate_measured`), by the compiled engine
where it holds the wall (within its stated tolerance of the exact simulator,
some 1e-8 rad, far below a line's width), else by the exact simulator.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import matplotlib

matplotlib.use("Agg")
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from rocklab.diagnosis import block_tests, measured_test, simulate_measured, stored_records
from rocklab.diagnosis.catalogue import by_name
from rocklab.diagnosis.causes import Stage, instability_angle
from rocklab.diagnosis.evidence import flight_time_alpha, in_series_order, observe
from rocklab.diagnosis.extended import model_params
from rocklab.diagnosis.result import CampaignDiagnosis, Finding, LimestoneDiagnosis, SeriesDiagnosis, floats
from rocklab.diagnosis.wall_model import impact_speeds
from rocklab.physics import restitution
from rocklab.physics.boundary import Boundary
from rocklab.physics.flight import quarter_period
from rocklab.physics.wall import overturning_velocity

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.axes import Axes

    from rocklab.diagnosis import MeasuredTest

#: Literature models of panel a: label -> base of :func:`rocklab.diagnosis.extended.rocking_model`.
LITERATURE: dict[str, dict[str, str]] = {
    Boundary.TWO_SIDED: {"Housner e_an,2s (Eq. 2)": "analytic"},
    Boundary.ONE_SIDED: {
        "e_an,1s (Eq. 14)": "analytic",
        "two-sided e (Hogan 1992)": "two-sided-e",
        "e = 0 (Liberatore & Spera 2003)": "zero",
    },
}


def _plot(ax: Axes, t: np.ndarray, theta: np.ndarray, test: MeasuredTest, **kw: Any) -> None:
    sel = t >= test.t_release
    ax.plot(t[sel] - test.t_release, theta[sel] / test.alpha, **kw)


def history_figure(test: MeasuredTest, entry: SeriesDiagnosis) -> Figure:
    """Figs. 14-15 for one test: measured motion, literature models, extended model.

    Parameters
    ----------
    test : rocklab.diagnosis.MeasuredTest
        With its record (``t``, ``theta``).
    entry : rocklab.diagnosis.result.SeriesDiagnosis
        The series' entry of results/diagnosis.json.

    Returns
    -------
    matplotlib.figure.Figure
    """
    assert test.t is not None and test.theta is not None  # a test read with its record
    fig, axes = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True)
    t_end = (test.t_end - test.t_release) * 1.3 + 0.5
    for ax in axes:
        _plot(ax, test.t, test.theta, test, color="k", lw=1.2, label=f"measured ({test.test_id})")
    for (label, base), style in zip(LITERATURE[test.boundary].items(), ("-", "--", ":")):
        t, th = simulate_measured(test, base=base, t_end=t_end, engine=True)
        _plot(axes[0], t, th, test, ls=style, lw=0.9, label=label)
    ext = entry.extended
    if ext:
        t, th = simulate_measured(test, ext["effects"], floats(ext["params"]), t_end=t_end, engine=True)
        params = ", ".join(f"{k} = {v:.3g}" for k, v in ext["params"].items())
        _plot(axes[1], t, th, test, color="C3", lw=0.9, label=f"{' + '.join(ext['effects'])}\n({params})")
    else:
        axes[1].text(0.5, 0.5, "no extension carried by the data", transform=axes[1].transAxes, ha="center")
    n = "14" if test.boundary == Boundary.TWO_SIDED else "15"
    # at the top of the axes, where nothing else is drawn: placed there, not searched for (the search,
    # a bounding box of every tick label, cost a fifth of the figure)
    axes[0].set_title(f"Fig. {n} - series {entry.key} ({test.boundary}): a, literature models", y=1.0)
    axes[1].set_title("b, the model extended by the causes the diagnosis found", y=1.0)
    for ax in axes:
        ax.set_ylabel("theta / alpha")
        ax.set_xlim(0, t_end)
        ax.axhline(0, color="0.7", lw=0.5)
        ax.legend(fontsize=7, loc="upper right")
    axes[1].set_xlabel("t - t_release [s]")
    # fixed margins (what tight layout finds with five-character ticks): a
    # campaign has a figure per series, and the layout cost each as much as its drawing
    fig.subplots_adjust(left=0.1, right=0.983, bottom=0.09, top=0.945, hspace=0.16)
    return fig


def _impact_law(
    tests: Sequence[MeasuredTest], ext: Sequence[str], values: Mapping[str, float | None], x: np.ndarray
) -> np.ndarray:
    """e / e_an of a model at impact speeds x [thetadot_r] on each test's release hinge, shape (tests, x)."""
    mp = model_params(tests, ext, floats(values))
    vr = overturning_velocity(mp.alpha, mp.p)[:, None]
    side = np.array([t.side0 for t in tests], float)[:, None] + 0.0 * x
    v = x * vr
    return impact_speeds(v, side, mp)[0] / (v * np.abs(mp.e0)[:, None])


def _flight_angle_seen(
    tests: Sequence[MeasuredTest], ext: Sequence[str], values: Mapping[str, float | None], A: np.ndarray
) -> np.ndarray:
    """alpha_r / alpha that Housner's closed form gives the model's flight time at apexes A [rad], (tests, A)."""
    mp = model_params(tests, ext, floats(values))
    p, alpha = mp.p[:, None], mp.alpha[:, None]
    side = np.array([t.side0 for t in tests], float)[:, None] + 0.0 * A
    return flight_time_alpha(A, 2.0 * quarter_period(A, mp.flight(A, side), p), p) / alpha


#: Tests of a series that the figure of its discovered forms draws at most, spread evenly over it: some
#: thousands of impacts show a law as well as all of them, and reading every test of the large series
#: of a campaign ten times the embedded one was nine tenths of the figures' time.
MAX_TESTS_DRAWN = 100


def discovery_figure(tests: Sequence[MeasuredTest], entry: SeriesDiagnosis) -> Figure | None:
    """Each form the diagnosis discovered beyond the catalogue against the data and the best listed model.

    One panel per discovered finding of ``entry`` (a series of
    results/diagnosis.json), in the variables of the family's signature:
    an instability angle that depends on the amplitude as the angle each
    flight time gives (Housner's closed form inverted) against the
    flight's apex; a family with a curve of its own (the losses in flight)
    as :func:`family_curve_figure`; an impact law as e/e_an against the impact speed
    (per impact), or against the test's place in the series (the
    per-test medians) for a drift.  The models are read the same way:
    the discovered family at its fit, and the listed causes the catalogue
    chose alone (``listed_verdict``, ``listed_params``).

    Parameters
    ----------
    tests : list of rocklab.diagnosis.MeasuredTest
        Tests of the series, in series order (:func:`rocklab.diagnosis.evidence.in_series_order`):
        all, or some spread over it (:data:`MAX_TESTS_DRAWN`, the figure says how many).
    entry : rocklab.diagnosis.result.SeriesDiagnosis

    Returns
    -------
    matplotlib.figure.Figure or None
        None when nothing was discovered.
    """
    found = entry.discovered
    if not found:
        return None
    ob = observe(tests)
    listed, listed_values = entry.listed_verdict or [], entry.listed_params or {}
    values = {k: v for f in entry.findings for k, v in f.params.items()}
    # a cause estimated after selection (the stop) acts on the free run's end, not on the laws drawn here
    chosen = [f.effect for f in entry.findings if by_name(f.effect).stage is Stage.SELECTION]
    fig, axes = plt.subplots(1, len(found), figsize=(7 * len(found), 4.5), squeeze=False)
    for ax, f in zip(axes[0], found):
        cause = by_name(f.effect)
        fam = cause.family
        pars = ", ".join(f"{k} = {v:.3g}" for k, v in f.params.items())
        lab = f"{f.effect} (discovered): {pars}\n{f.reduces_to}"
        lab_listed = f"best listed: {' + '.join(listed) or 'the base model'}"
        if f.curve is not None:
            # a family with a curve of its own (the losses in flight against the flight's speed)
            family_curve_figure(f, entry.key, ax)
        elif fam == instability_angle.CAUSE.name:
            x = ob.S.A[:, :-1] / ob.alpha
            ax.plot(x.ravel(), ob.a_T.ravel(), ".", color="0.3", ms=3, zorder=3, label="measured flights")
            # up to the largest flight measured: at the instability point the flight time is unbounded
            A = np.linspace(0.02, np.nanmax(x), 60)[None, :] * ob.alpha
            for ext, v, style, label in ((chosen, values, "-", lab), (listed, listed_values, "--", lab_listed)):
                y = _flight_angle_seen(tests, ext, v, A)
                ax.plot(A[0] / ob.alpha[0, 0], y[0], style, lw=1.5, label=label)
            ax.set_xlabel("apex of the flight / alpha")
            ax.set_ylabel("alpha_r / alpha from the flight time (Housner)")
        elif cause.drifts:
            column = cause.log_column
            n = np.array([t.order if column is None else t.log.get(column, np.nan) for t in tests])
            med = np.array([np.median(ob.ratio[i][ob.ok[i]]) if ob.ok[i].any() else np.nan for i in range(len(tests))])
            ax.plot(n, med, "ko", ms=4, label="measured, per test (median over its impacts)")
            for ext, v, style, label in ((chosen, values, "-", lab), (listed, listed_values, "--", lab_listed)):
                y = np.median(_impact_law(tests, ext, v, np.array([0.3, 0.5, 0.7])), axis=1)
                order = np.argsort(n)
                ax.plot(n[order], y[order], style, lw=1.5, label=label)
            ax.set_xlabel(
                "place of the test in the series (0 first, 1 last)"
                if column is None
                else f"the test's {column} over the series' range (0 least, 1 largest)"
            )
            ax.set_ylabel("e / e_an")
        else:
            ax.plot(ob.vr[ob.ok], ob.ratio[ob.ok], ".", color="0.3", ms=3, zorder=3, label="measured impacts")
            x = np.linspace(0.02, 1.0, 60)
            for ext, v, style, label in ((chosen, values, "-", lab), (listed, listed_values, "--", lab_listed)):
                ax.plot(x, _impact_law(tests, ext, v, x)[0], style, lw=1.5, label=label)
            ax.set_xlabel("impact speed / thetadot_r")
            ax.set_ylabel("e / e_an")
        gain = f.heldout_gain
        ax.set_title(
            f"{entry.key}: held-out gain {gain['vs_best_listed']:.3g} +- {gain['vs_best_listed_se']:.2g} "
            "over the best listed model",
            fontsize=9,
        )
        ax.legend(fontsize=7, loc="best")
    if entry.n_tests is not None and len(tests) < entry.n_tests:
        fig.suptitle(f"{len(tests)} of the series' {entry.n_tests} tests drawn, spread evenly over it", fontsize=8)
    fig.set_layout_engine("tight")
    return fig


def series_figures(
    diagnosis: CampaignDiagnosis | str | Path, tests_by_series: Mapping[str, Sequence[str | Path]]
) -> dict[str, Figure]:
    """Figs. 14-15 for the sample test of every series of results/diagnosis.json.

    Parameters
    ----------
    diagnosis : rocklab.diagnosis.result.CampaignDiagnosis or path
        results/diagnosis.json.
    tests_by_series : mapping
        Series id -> its reduced tests (``results/tests/<job>/<test_id>.nc``, each
        with its stored motion, :func:`rocklab.lab.motion.write_test_with_motion`).
        Of a series the sample test is read, and every test where the series
        has a form discovered beyond the catalogue (:func:`discovery_figure`):
        each file once, whatever the number of series.

    Returns
    -------
    dict
        Series id -> Figure, ``discovered/<series>`` -> the figure of
        :func:`discovery_figure` where the series has a discovered form
        (a family's curve, :func:`family_curve_figure`, in its panel),
        plus ``fig14`` and ``fig15``: the largest
        two-sided and one-sided series, as the paper's figures (a note when
        the campaign has none).
    """
    campaign = CampaignDiagnosis.of(diagnosis)
    out: dict[str, Figure] = {}
    for e in campaign.series:
        # every series of a diagnosis has its key, its sample test and its tests counted
        assert e.key is not None and e.sample_test is not None
        paths = {Path(p).stem: p for p in tests_by_series[e.key]}
        (recs,) = stored_records([paths[e.sample_test]]).values()
        out[e.key] = history_figure(measured_test(recs[0]), e)
        if e.discovered:
            found = discovery_figure(_series_tests(paths), e)
            assert found is not None  # the series has a discovered form
            out[f"discovered/{e.key}"] = found
    for name, boundary in (("fig14", Boundary.TWO_SIDED), ("fig15", Boundary.ONE_SIDED)):
        own = campaign.series_of(boundary)
        out[name] = out[str(max(own, key=lambda e: e.n_tests or 0).key)] if own else _empty(boundary)
    return out


def family_curve_figure(finding: Finding, key: str | None, ax: Axes | None = None) -> Figure:
    """A discovered family's curve against the data and the catalogue's best member.

    For the losses in flight (:mod:`rocklab.diagnosis.causes.flight_loss`):
    the speed each long flight loses between take-off and the next impact,
    relative to its take-off speed, against that speed over thetadot_r,
    with the flight-loss curve of the family fitted and of the listed
    viscous loss fitted by the catalogue alone.

    Parameters
    ----------
    finding : rocklab.diagnosis.result.Finding
        A finding of results/diagnosis.json with a ``curve``
        (:attr:`rocklab.diagnosis.causes.Cause.curve`).
    key : str
        Its series.
    ax : matplotlib.axes.Axes, optional
        Where to draw it (a panel of :func:`discovery_figure`); a new figure
        if None.

    Returns
    -------
    matplotlib.figure.Figure
    """
    c, gain = finding.curve, finding.heldout_gain
    assert c is not None and gain is not None  # a finding with a curve, compared held out
    if ax is None:
        ax = plt.subplots(figsize=(8, 5))[1]
    ax.plot(c["measured"]["x"], c["measured"]["y"], "o", color="0.5", ms=3, label=c["measured"]["label"])
    ax.plot(c["best_listed"]["x"], c["best_listed"]["y"], "--", color="C1", label=c["best_listed"]["label"])
    ax.plot(
        c["family"]["x"],
        c["family"]["y"],
        color="C3",
        lw=1.5,
        label=f"{c['family']['label']}, discovered: {finding.reduces_to}\n"
        f"held-out gain {gain['vs_best_listed']:.3g} +- {gain['vs_best_listed_se']:.2g} over the listed causes, "
        f"{gain['vs_base']:.3g} +- {gain['vs_base_se']:.2g} over the base model",
    )
    ax.set_xlabel(c["x"])
    ax.set_ylabel(c["y"])
    ax.set_title(f"Series {key}: {finding.effect}, the curve found against the data")
    ax.legend(fontsize=7, loc="best")
    fig = ax.figure
    assert isinstance(fig, Figure)  # an axes of a figure (set_layout_engine), not of a subfigure
    fig.set_layout_engine("tight")
    return fig


def family_figure(result: LimestoneDiagnosis, events: pd.DataFrame) -> Figure:
    """The impact law across the limestone blocks: the families against the data and the listed causes.

    The median measured r/e_an (e_an Housner's, Eq. 2) of every trial
    against (B/H)^2, the variable of Eq. 2, with the mean of each block
    group; and the same median of each model's e/e_an over the impacts of
    the trials, averaged over each group: Housner's e (1), the listed cause
    of lowest BIC and each generalised family fitted to all trials (``families`` of
    :func:`rocklab.diagnosis.block_tests.diagnose_blocks`).

    Parameters
    ----------
    result : rocklab.diagnosis.result.LimestoneDiagnosis
        results/limestone_diagnosis.json (:func:`rocklab.diagnosis.block_tests.diagnose_blocks`).
    events : pandas.DataFrame
        The per-impact table it was computed from (:func:`rocklab.diagnosis.block_tests.read_events`).

    Returns
    -------
    matplotlib.figure.Figure
    """
    trials = block_tests.pooled(block_tests.group_trials(events))
    problem = block_tests.BlockProblem(trials)
    e_an = restitution.two_sided(trials.alpha)[:, None]
    x = np.tan(trials.alpha) ** 2
    ok = np.isfinite(trials.r)

    def per_trial(e: np.ndarray) -> np.ndarray:
        return np.array([np.median(e[i][ok[i]]) for i in range(len(x))])

    xs = np.unique(x)

    def by_group(v: np.ndarray) -> np.ndarray:
        return np.array([v[x == u].mean() for u in xs])

    measured = per_trial(trials.r / e_an)
    fig, ax = plt.subplots(figsize=(8, 5))
    ax.plot(x, measured, "o", color="0.6", ms=3, label="measured, per trial (median over its impacts)")
    ax.plot(xs, by_group(measured), "ks", ms=6, label="measured, mean of each block group")
    ax.axhline(1.0, color="C0", lw=1.0, label="Housner's e (Eq. 2)")
    for i, fam in enumerate(result.all.families):
        if i == 0:
            best = per_trial(problem.model_e(trials, floats(fam.best_listed_params)) / e_an)
            pars = ", ".join(f"{k} = {v:.3g}" for k, v in fam.best_listed_params.items())
            ax.plot(xs, by_group(best), "--", color="C1", label=f"best listed: {fam.best_listed} ({pars})")
        model = per_trial(problem.model_e(trials, floats(fam.params)) / e_an)
        pars = ", ".join(f"{k} = {v:.3g}" for k, v in fam.params.items())
        gain = fam.heldout_gain
        ax.plot(
            xs,
            by_group(model),
            color=f"C{3 + i}",
            lw=1.5,
            label=f"{fam.effect}{' (discovered)' if fam.discovered else ''}: {pars}\n"
            f"held-out gain {gain['vs_base']:.3g} +- {gain['vs_base_se']:.2g} over Housner, "
            f"{gain['vs_best_listed']:.3g} +- {gain['vs_best_listed_se']:.2g} over the best listed; "
            f"{fam.reduces_to}",
        )
    ax.set_xlabel("(B/H)^2")
    ax.set_ylabel("e / e_an (Housner, Eq. 2)")
    ax.set_title(f"Limestone blocks: impact law across slendernesses ({result.all.n_tests} trials)")
    ax.legend(fontsize=7, loc="best")
    fig.set_layout_engine("tight")
    return fig


def _series_tests(paths: Mapping[str, str | Path]) -> list[MeasuredTest]:
    """Valid tests of one series, ``paths`` (stem -> path) its tests, as the diagnosis read them.

    At most :data:`MAX_TESTS_DRAWN`, spread evenly over the series' files.
    """
    ordered = sorted(paths.values())
    drawn = np.unique(np.linspace(0, len(ordered) - 1, min(len(ordered), MAX_TESTS_DRAWN)).round().astype(int))
    (recs,) = stored_records([ordered[i] for i in drawn]).values()
    return in_series_order([t for t in map(measured_test, recs) if t.n_impacts >= 2])


def _empty(boundary: str) -> Figure:
    """The figure of a campaign without a diagnosed series of this boundary condition."""
    fig, ax = plt.subplots(figsize=(9, 2))
    ax.text(0.5, 0.5, f"no {boundary} series with two tests of two impacts or more", ha="center", va="center")
    ax.set_axis_off()
    return fig
