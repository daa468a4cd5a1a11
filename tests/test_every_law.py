"""Every law on every boundary (issue 42, item 2): no pair of causes the catalogue can name is refused
by the exact simulator or the numba engine, both agree where both apply, a law of the impact speed on a
wall swinging through a gap is the diagnosis' closed form of the excursion, and a series whose
diagnosis raises is reported as not finished while the rest of the campaign runs."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from rocklab.diagnosis import catalogue
from rocklab.diagnosis import series as S
from rocklab.diagnosis.causes import Stage
from rocklab.diagnosis.extended import model_params
from rocklab.diagnosis.result import CampaignDiagnosis
from rocklab.diagnosis.wall_model import impact_speeds, simulator
from rocklab.physics import wall
from rocklab.seismic.calibrated import MapWall
from rocklab.simulation.batch import free_batch, free_record
from rocklab.simulation.reference import simulate_free

#: The walls: a boundary, and whether a one-sided wall swings through a gap (Fig. 12).
WALLS = {"two-sided": ("two-sided", False), "one-sided": ("one-sided", False), "one-sided-gap": ("one-sided", True)}
ALPHA, P = 0.12, float(wall.frequency_parameter(1.0))
T_END = 1.5


def _value(q):
    """A value of parameter ``q`` away from its null, inside its bounds."""
    return q.null + 0.15 * ((q.upper if q.upper > q.null else q.lower) - q.null)


def _causes(boundary):
    """The causes of a boundary the diagnosis can name: listed, families, and those estimated after selection."""
    own = [*catalogue.for_boundary(boundary, families=True), *catalogue.for_boundary(boundary, Stage.AFTER_SELECTION)]
    return [c for c in own if c.name != "contact_gap"]


def _model(boundary, gap, names, values=None):
    values = (
        {q.name: _value(q) for c in catalogue.in_order() for q in c.params} | {"gap_over_alpha": 0.05} | (values or {})
    )
    ext = [*names, *(["contact_gap"] if gap else [])]
    mp = model_params([MapWall(ALPHA, P, boundary)], ext, values)
    return mp, simulator(mp.row(0))


@pytest.mark.parametrize("wall_kind", WALLS)
def test_every_pair_of_causes_is_simulated_by_the_reference_and_the_engine_alike(wall_kind):
    """Each pair of causes (each cause alone too) at values off their nulls: the reference simulates its
    free run, the engine too, to the same impacts within 1e-9 rad/s; the one refusal left is the
    engine's of a rocking angle that depends on the amplitude (defined flight by flight in free rocking,
    where the engines integrate ground motion; the diagnosis simulates it with the reference)."""
    boundary, gap = WALLS[wall_kind]
    causes = _causes(boundary)
    pairs = [(c,) for c in causes] + list(itertools.combinations(causes, 2))
    compared = 0
    for pair in pairs:
        names = [c.name for c in pair]
        _, model = _model(boundary, gap, names)
        ref = simulate_free(model, 0.6 * model.alpha, t_end=T_END, fs=50.0).impacts
        assert len(ref) >= 1, names
        if model.hinge_rounding:
            with pytest.raises(NotImplementedError, match="depends on the amplitude"):
                free_batch(model, 0.6 * model.alpha, t_end=T_END, max_impacts=4)
            continue
        ds = free_batch(model, 0.6 * model.alpha, t_end=T_END, dt=1.0 / 400.0, substeps=8, max_impacts=40)
        # the impacts well inside both runs (one close to the end may fall on either side of it)
        n = int(np.sum(ref.t < T_END - 0.05))
        assert int(ds.n_impacts[0]) >= n, names
        np.testing.assert_allclose(ds.t_impact[0, :n], ref.t[:n], rtol=0, atol=1e-9, err_msg=str(names))
        np.testing.assert_allclose(
            ds.thetadot_after[0, :n], ref.thetadot_after[:n], rtol=0, atol=1e-9, err_msg=str(names)
        )
        compared += 1
    assert compared >= len(pairs) // 2


def _excursions(impacts):
    """(landing speed that starts each excursion through the gap, speed leaving the base at its return)
    [rad/s] from the reference's or the engine's impacts: base impacts leaving hinge +1, then -1."""
    base = impacts[impacts.kind == "base"]
    v, after = base.thetadot_before.to_numpy(), base.thetadot_after.to_numpy()
    starts = np.flatnonzero((v[:-1] < 0) & (v[1:] > 0))
    return -v[starts], after[starts + 1]


@pytest.mark.parametrize(
    "values",
    [
        {"g0": 1.0, "g1": 0.7, "g2": 1.4, "g3": 0.9},
        {"g0": 1.2, "g1": 1.3, "g2": 0.6, "g3": 0.5, "gap_over_alpha": 0.1, "a": 1.1, "b": 0.3},
    ],
)
def test_a_law_of_the_impact_speed_through_a_gap_is_the_closed_form_of_the_excursion(values):
    """One-sided wall with a gap: base impact (Eq. 2), flight into the gap, transverse impact, flight back,
    base impact (Eq. 2), the law of the impact speed last on the whole sequence, g of the landing speed
    that started it (wall_model.impact_speeds): the reference and the engine give it within 1e-9."""
    names = ["restitution_speed", *(["restitution_amplitude"] if "a" in values else [])]
    mp, model = _model("one-sided", True, names, {"c": 1.0, **values})
    h = simulate_free(model, 0.6 * model.alpha, t_end=3.0, fs=50.0)
    v, out = _excursions(h.impacts)
    assert v.size >= 2
    closed = impact_speeds(v, np.ones_like(v), mp, timed=False)[0]
    np.testing.assert_allclose(out, closed, rtol=1e-9)
    # the law acts: without it the excursion gives another speed
    mp0, model0 = _model("one-sided", True, names[1:], {"c": 1.0, **values})
    assert np.max(np.abs(impact_speeds(v, np.ones_like(v), mp0, timed=False)[0] / closed - 1)) > 1e-3
    ds = free_batch(model, 0.6 * model.alpha, t_end=3.0, dt=1.0 / 400.0, substeps=8, max_impacts=60)
    n = len(h.impacts)
    np.testing.assert_allclose(ds.thetadot_after[0, :n], h.impacts.thetadot_after, rtol=0, atol=1e-9)


def test_the_engine_s_law_of_the_impact_speed_is_the_reference_s_at_every_speed():
    """The engine's row of a law of the impact speed (knots past the fourth column) gives the e of the
    reference's law, past the last knot and within the bounds of bounded_factor too."""
    from rocklab.simulation import engine

    _, model = _model("two-sided", False, ["restitution_speed", "restitution_scale"], {"g3": 2.5, "c": 0.9})
    law = model.numba_law()
    assert law.shape == (3, 5 + 4) and law[0, 4] == engine.SPEED_EACH
    prm = tuple(model.numba_params())
    for r in np.linspace(0.0, 2.0, 21):
        v = -r * model.thetadot_r
        want = float(model.base_law.coefficient(v, 1, model.alpha, model.p))
        assert engine._coefficient(law, 0, v, prm) == pytest.approx(want, rel=1e-12, abs=1e-15)


def test_a_series_whose_diagnosis_raises_is_reported_not_finished_and_the_rest_runs(monkeypatch, tmp_path):
    """A job of three series, the diagnosis of one raising: its entry says so (not_finished, the
    exception), the others have their verdicts, and the file, the boundaries' entries, the report and
    the summary are made, the unfinished series left out of them but named in the report."""
    from rocklab.diagnosis.diagnosis_report import diagnosis_markdown
    from rocklab.diagnosis.diagnosis_summary import diagnosis_summary
    from rocklab.diagnosis.pooling import with_boundaries
    from rocklab.lab import virtual_lab as vl

    real = S.diagnose_series

    def failing(tests, *, key="", **kw):
        if key == "bad":
            raise NotImplementedError("a law the simulator lacks")
        return real(tests, key=key, **kw)

    monkeypatch.setattr(S, "diagnose_series", failing)
    spec = vl.DEFAULT_SPECIMENS.set_index("specimen").loc["1a"]
    entries = []
    for key in ("a", "bad", "c"):
        records = vl.series_records(key, spec, "two-sided", {}, n=1, fs=200.0, seed=1, t_end=20.0)
        entries.append(S.diagnose_records(records, key, n_boot=0, n_history=0))
    bad = entries[1]
    assert bad.not_finished == "NotImplementedError: a law the simulator lacks"
    assert bad.boundary == "two-sided" and bad.n_tests == 1 and bad.base is None and bad.verdict == []
    assert all(e.not_finished is None and e.base is not None for e in (entries[0], entries[2]))
    path = tmp_path / "series.json"
    CampaignDiagnosis.from_dict(entries).to_json(path)
    back = CampaignDiagnosis.of_series_files([path])
    assert [e.key for e in back.not_finished] == ["bad"] and [e.key for e in back.series] == ["a", "c"]
    full = with_boundaries(back)
    (boundary,) = full.boundaries
    assert boundary.n_series == 2
    assert "bad (two-sided, 1 test): NotImplementedError" in diagnosis_markdown(full)
    assert [r["series"] for r in diagnosis_summary(full)["series"]] == ["a", "c"]


@pytest.mark.parametrize("wall_kind", WALLS)
def test_the_engine_s_record_of_every_cause_is_the_reference_s(wall_kind):
    """Each cause alone, off its null: the engine's record of the free run (free_record, which the
    diagnosis' model bias simulates its tests with) is the reference's at the diagnosis' tolerances
    within 2e-9 rad, sample by sample, on the reference's grid (NaN past the end, as the reference's); the
    engine refuses a rocking angle
    that depends on the amplitude, and the caller then takes the reference."""
    boundary, gap = WALLS[wall_kind]
    for cause in _causes(boundary):
        _, model = _model(boundary, gap, [cause.name])
        if model.hinge_rounding:
            with pytest.raises(NotImplementedError, match="depends on the amplitude"):
                free_record(model, 0.6 * model.alpha, t_end=T_END)
            continue
        # an end between two samples: the grid's last sample lies past it, NaN in both
        t_end = T_END + 2e-3
        ref = simulate_free(model, 0.6 * model.alpha, t_end=t_end, fs=400.0, rtol=1e-9, atol=1e-12, apexes=False)
        run = free_record(model, 0.6 * model.alpha, t_end=t_end, fs=400.0)
        assert run is not None, cause.name
        np.testing.assert_array_equal(run[0], ref.t)
        assert np.isnan(ref.theta[-1]) and np.isfinite(ref.theta[:-1]).all(), cause.name
        np.testing.assert_allclose(run[1], ref.theta, rtol=0, atol=2e-9, equal_nan=True, err_msg=cause.name)


def test_a_wall_that_overturns_has_no_engine_record():
    """Released beyond its instability angle the wall overturns: the engine gives no record (the
    reference's ends in NaN), so the caller takes the reference's."""
    _, model = _model("two-sided", False, [])
    assert free_record(model, 1.2 * model.alpha, t_end=5.0) is None
    assert np.isnan(simulate_free(model, 1.2 * model.alpha, t_end=5.0).theta[-1])
