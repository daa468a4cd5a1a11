"""The diagnosis' results as objects (rocklab.diagnosis.result): the files of the embedded campaign
validate against their schemas and are written back byte for byte; a file that breaks its schema,
or a key the objects do not know, is refused; the schemas ship with the library."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest
import yaml

from rocklab.diagnosis import result as R

ROOT = Path(__file__).resolve().parents[1]


def results_dir() -> Path:
    """The results of `make run` (config.yaml's results_dir)."""
    return ROOT / yaml.safe_load((ROOT / "config" / "config.yaml").read_text())["results_dir"]


def embedded(*names):
    """Paths of files of the embedded campaign's results; the test is skipped without them."""
    paths = [results_dir() / name for name in names]
    missing = [p.name for p in paths if not p.is_file()]
    if missing:
        pytest.skip(f"no {', '.join(missing)} from `make run` here (CI has none)")
    return paths


def series_files():
    """results/diagnosis/<job>.json: the series of each diagnosis job."""
    folder = results_dir() / "diagnosis"
    return sorted(folder.glob("series-*.json")) if folder.is_dir() else []


#: A series entry with every key a full diagnosis writes (numbers made up), as a JSON document.
SERIES = {
    "scope": "series",
    "key": "1a-2s",
    "boundary": "two-sided",
    "n_tests": 6,
    "n_impacts": 120,
    "base": {"model": "Housner", "errors": {"n_impacts": {"measured": 20.0, "model": 60.0}, "log_peak_rms": None}},
    "what_is_wrong": "the simulation keeps rocking",
    "verdict": ["restitution_scale"],
    "unexplained": False,
    "residual_structure": [],
    "findings": [
        {
            "effect": "restitution_scale",
            "params": {"c": 0.95},
            "ci95": {"c": [0.94, 0.96]},
            "n_tests": 6,
            "evidence": {"signature": "e/e_an = 0.95", "fit": "lowered by 4"},
            "error_heldout": {"deviance_per_obs": -10.0},
            "gain": {"deviance_per_obs": 4.0},
            "discovered": False,
        }
    ],
    "weak_evidence": {},
    "rejected": {"hinge_asymmetry": "its signature in the data is absent"},
    "signatures": {"restitution_scale": "e/e_an = 0.95"},
    "heldout": {"base": {"deviance_per_obs": -6.0}, "model": {"deviance_per_obs": -10.0}},
    "model_bias": {"b": {"c": 2e-5}, "u_model": {"c": 1e-5}},
    "sample_test": "T0001",
}


def test_the_embedded_campaign_diagnosis_reads_and_writes_back_byte_for_byte(tmp_path):
    (path,) = embedded("diagnosis.json")
    diagnosis = R.CampaignDiagnosis.from_json(path)
    assert diagnosis.series and all(isinstance(e, R.SeriesDiagnosis) for e in diagnosis.series)
    assert {e.boundary for e in diagnosis.boundaries} == {"two-sided", "one-sided"}
    assert diagnosis.entries == diagnosis.series + diagnosis.boundaries
    for b in diagnosis.boundaries:
        assert all(isinstance(f, R.PooledFinding) for f in b.findings)
        assert [f.effect for f in b.named] == [f.effect for f in b.findings if f.effect in b.verdict]
    assert diagnosis.sample_tests == {e.sample_test for e in diagnosis.series}
    diagnosis.to_json(tmp_path / "diagnosis.json")
    assert (tmp_path / "diagnosis.json").read_bytes() == path.read_bytes()
    # the dict form is the JSON itself
    assert diagnosis.to_dict() == json.loads(path.read_text())


def test_each_job_file_holds_its_series_of_the_campaign_and_writes_back(tmp_path):
    (campaign,) = embedded("diagnosis.json")
    paths = series_files()
    if not paths:
        pytest.skip("no results/diagnosis/<job>.json here")
    whole = R.CampaignDiagnosis.from_json(campaign)
    parts = [R.CampaignDiagnosis.from_json(p) for p in paths]
    for path, part in zip(paths, parts):
        # series-<first>[+<last>]: its series, none of another file
        first = path.stem.removeprefix("series-").partition("+")[0]
        assert not part.boundaries and part.series[0].key == first
        part.to_json(tmp_path / path.name)
        assert (tmp_path / path.name).read_bytes() == path.read_bytes(), path.name
    # the campaign's series are those of the files, by series (as the workflow joins them)
    assert R.CampaignDiagnosis.of_series_files(paths).entries == whole.series


def test_the_campaign_diagnosis_is_made_again_from_its_series_files(tmp_path):
    """What the diagnosis checkpoint does (scripts/diagnosis.py): the same bytes as `make run` wrote."""
    from rocklab.diagnosis import with_boundaries, write_diagnosis
    from rocklab.lab.campaign import open_campaign
    from rocklab.lab.hierarchy import thickness_of_walls, walls_of_series

    campaign, md = embedded("diagnosis.json", "diagnosis.md")
    if not series_files():
        pytest.skip("no results/diagnosis/<job>.json here")
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    lab = open_campaign(ROOT / config["raw_dir"])
    series = R.CampaignDiagnosis.of_series_files(series_files())
    entries = with_boundaries(series.to_dict(), walls=walls_of_series(lab), thickness=thickness_of_walls(lab))
    write_diagnosis(entries, tmp_path / "d.json", tmp_path / "d.md")
    assert (tmp_path / "d.json").read_bytes() == campaign.read_bytes()
    assert (tmp_path / "d.md").read_bytes() == md.read_bytes()


def test_the_limestone_result_reads_and_writes_back_byte_for_byte(tmp_path):
    (path,) = embedded("limestone_diagnosis.json")
    limestone = R.LimestoneDiagnosis.from_json(path)
    assert limestone.all.scope == "all blocks" and limestone.all.h_over_b is None
    assert [g.scope for g in limestone.groups] == ["block group"] * len(limestone.groups)
    assert all(isinstance(f, R.FamilyComparison) for f in limestone.all.families)
    limestone.to_json(tmp_path / "limestone.json")
    assert (tmp_path / "limestone.json").read_bytes() == path.read_bytes()


def test_keys_written_in_some_cases_only_are_left_out_where_they_are_none(tmp_path):
    entry = R.SeriesDiagnosis.from_dict(SERIES)
    assert list(entry.to_dict()) == list(SERIES)
    assert entry.too_small is None and entry.extended is None and entry.findings[0].ci_note is None
    assert entry.finding("restitution_scale").params == {"c": 0.95} and entry.finding("contact_gap") is None
    assert entry.named == entry.findings and entry.discovered == []
    R.CampaignDiagnosis([entry]).to_json(tmp_path / "d.json")
    assert json.loads((tmp_path / "d.json").read_text()) == [SERIES]
    # a boundary condition without a series large enough: its heldout is written, as null
    b = R.BoundaryDiagnosis(scope="boundary", key="one-sided", boundary="one-sided", heldout=None, too_small="why")
    assert b.to_dict()["heldout"] is None and "extended" not in b.to_dict()


def test_the_findings_a_boundary_condition_leaves_to_its_series():
    other = {**SERIES, "key": "1b-2s", "unexplained": True, "verdict": [], "findings": []}
    boundary = R.BoundaryDiagnosis(scope="boundary", key="two-sided", boundary="two-sided", verdict=[])
    diagnosis = R.CampaignDiagnosis.from_dict([SERIES, other, boundary])
    assert [e.key for e in diagnosis.unexplained] == ["1b-2s"]
    ((entry, finding),) = diagnosis.minority("two-sided")
    assert entry.key == "1a-2s" and finding.effect == "restitution_scale"
    boundary.verdict = ["restitution_scale"]
    assert diagnosis.minority("two-sided") == [] and diagnosis.minority("one-sided") == []
    # a campaign without the boundary's entry: every finding of its series
    assert len(R.CampaignDiagnosis(diagnosis.series).minority("two-sided")) == 1


def test_a_file_that_breaks_the_schema_is_refused_naming_the_key(tmp_path):
    bad = copy.deepcopy(SERIES)
    bad["findings"][0]["n_tests"] = "six"
    with pytest.raises(ValueError, match=r"0/findings/0/n_tests: 'six' is not of type 'integer'"):
        R.CampaignDiagnosis.from_dict([bad]).to_json(tmp_path / "d.json")
    assert not (tmp_path / "d.json").exists()
    missing = {k: v for k, v in SERIES.items() if k != "sample_test"}
    (tmp_path / "d.json").write_text(json.dumps([missing]))
    with pytest.raises(ValueError, match="d.json: 0"):
        R.CampaignDiagnosis.from_json(tmp_path / "d.json")
    (tmp_path / "d.json").write_text("{not json")
    with pytest.raises(ValueError, match="d.json: not a readable diagnosis"):
        R.CampaignDiagnosis.of(tmp_path / "d.json")
    with pytest.raises(ValueError, match="not a readable diagnosis"):
        R.CampaignDiagnosis.of(tmp_path / "none.json")


def test_a_key_the_objects_do_not_know_is_refused():
    with pytest.raises(ValueError, match="SeriesDiagnosis: unknown key.s. colour"):
        R.SeriesDiagnosis.from_dict({**SERIES, "colour": "red"})
    with pytest.raises(ValueError, match="Finding: unknown key"):
        R.CampaignDiagnosis.from_dict([{**SERIES, "findings": [{"effect": "x", "weight": 1}]}])
    with pytest.raises(ValueError, match="a list of entries"):
        R.CampaignDiagnosis.from_dict(SERIES)


def test_non_finite_numbers_are_written_as_null(tmp_path):
    import numpy as np

    entry = copy.deepcopy(SERIES)
    entry["findings"][0]["params"] = {"c": np.float64("nan")}
    entry["n_impacts"] = np.int64(120)
    R.CampaignDiagnosis.from_dict([entry]).to_json(tmp_path / "d.json")
    (written,) = json.loads((tmp_path / "d.json").read_text())
    assert written["findings"][0]["params"] == {"c": None} and written["n_impacts"] == 120


@pytest.mark.parametrize("schema", [R.DIAGNOSIS_SCHEMA, R.LIMESTONE_SCHEMA], ids=lambda p: p.name)
def test_the_schemas_ship_with_the_library_and_the_workflow_links_them(schema):
    assert schema.is_file() and schema.is_relative_to(Path(R.__file__).parents[1] / "data")
    assert (ROOT / "workflow" / "schemas" / schema.name).resolve() == schema.resolve()


@pytest.mark.parametrize("schema", [R.DIAGNOSIS_SCHEMA, R.LIMESTONE_SCHEMA], ids=lambda p: p.name)
def test_every_key_of_the_schemas_is_described(schema):
    """Every property of every object of a schema has a description (its own or its definition's)."""
    doc = yaml.safe_load(schema.read_text())
    defs = doc.get("$defs", {})

    def described(spec):
        ref = spec.get("$ref", "")
        return bool(spec.get("description")) or bool(defs.get(ref.rsplit("/", 1)[-1], {}).get("description"))

    def undescribed(spec, where):
        """The keys below ``spec`` without a description (the items of its lists and maps searched too)."""
        out = []
        for name, sub in spec.get("properties", {}).items():
            out += ([] if described(sub) else [f"{where}.{name}"]) + undescribed(sub, f"{where}.{name}")
        for key in ("items", "additionalProperties"):
            if isinstance(spec.get(key), dict):
                out += undescribed(spec[key], f"{where}[]")
        return out

    missing = [w for name, spec in [("(top)", doc), *defs.items()] for w in undescribed(spec, name)]
    missing += [name for name, spec in defs.items() if not described(spec)]
    assert not missing, missing


def test_a_claim_on_a_mean_is_judged_on_the_number_table_3_quotes():
    """One estimate of a statement on the mean: campaign_effects.csv's row and Table 3's whole history
    (the mean over tests, CR2 with the walls as clusters, Imbens-Kolesar df)."""
    import pandas as pd

    effects, t3 = (pd.read_csv(p) for p in embedded("diagnosis/campaign_effects.csv", "table3.csv"))
    for boundary in ("two-sided", "one-sided"):
        claim = effects[
            (effects.boundary == boundary) & (effects.response == "e_ratio") & (effects.covariate == "mean")
        ]
        table = t3[(t3.boundary == boundary) & (t3.window == "complete")].iloc[0]
        assert len(claim)
        for _, row in claim.iterrows():
            assert (row.estimate, row.ci_low, row.ci_high, row.df) == pytest.approx(
                (table["mean"], table.ci_low, table.ci_high, table.df), rel=1e-5
            )


#: Each record of the files and the definition of its object in the schemas.
RECORDS = [
    (R.DIAGNOSIS_SCHEMA, "series_entry", R.SeriesDiagnosis),
    (R.DIAGNOSIS_SCHEMA, "boundary_entry", R.BoundaryDiagnosis),
    (R.DIAGNOSIS_SCHEMA, "finding", R.Finding),
    (R.DIAGNOSIS_SCHEMA, "pooled_finding", R.PooledFinding),
    (R.DIAGNOSIS_SCHEMA, "base", R.BaseRun),
    (R.DIAGNOSIS_SCHEMA, "structure", R.Structure),
    (R.DIAGNOSIS_SCHEMA, "series_change", R.SeriesChange),
    (R.DIAGNOSIS_SCHEMA, "changing_series", R.ChangingSeries),
    (R.LIMESTONE_SCHEMA, "block_entry", R.BlockDiagnosis),
    (R.LIMESTONE_SCHEMA, "finding", R.Finding),
    (R.LIMESTONE_SCHEMA, "family", R.FamilyComparison),
    (R.LIMESTONE_SCHEMA, "structure", R.Structure),
    (R.LIMESTONE_SCHEMA, None, R.LimestoneDiagnosis),
]


@pytest.mark.parametrize(("schema", "name", "record"), RECORDS, ids=lambda x: getattr(x, "__name__", None))
def test_each_object_holds_the_keys_of_its_schema_in_their_order_and_requires_what_it_requires(schema, name, record):
    """Issue 40: the schema and the object cannot disagree, field by field: the same keys in the same
    order, and the keys a file must have are those the object always writes (all but ``_optional``)."""
    from dataclasses import fields

    doc = yaml.safe_load(Path(schema).read_text())
    d = doc if name is None else doc["$defs"][name]
    names = [f.name for f in fields(record)]
    assert list(d["properties"]) == names
    assert d.get("additionalProperties") is False
    assert sorted(d.get("required", [])) == sorted(n for n in names if n not in record._optional)


def _definition(schema, *path):
    """The JSON schema of an object at ``path`` (keys into the schema, "$defs" and "properties" included)."""
    d = yaml.safe_load(Path(schema).read_text())
    for key in path:
        d = d[key]
    return d


#: The nested objects that stay mappings in the objects, and their shapes (TypedDict).
SHAPES = [
    (R.DIAGNOSIS_SCHEMA, ("$defs", "measured_and_model"), R.MeasuredAndModel),
    (R.DIAGNOSIS_SCHEMA, ("$defs", "heldout"), R.HeldOut),
    (R.DIAGNOSIS_SCHEMA, ("$defs", "series_entry", "properties", "model_bias"), R.ModelBias),
    (R.DIAGNOSIS_SCHEMA, ("$defs", "series_entry", "properties", "extended"), R.SeriesExtended),
    (R.DIAGNOSIS_SCHEMA, ("$defs", "boundary_entry", "properties", "extended"), R.BoundaryExtended),
    (R.DIAGNOSIS_SCHEMA, ("$defs", "pooled_finding", "properties", "evidence"), R.PooledEvidence),
    (R.LIMESTONE_SCHEMA, ("$defs", "block_entry", "properties", "base"), R.BlockBase),
    (R.LIMESTONE_SCHEMA, ("properties", "slenderness"), R.Slenderness),
    (
        R.LIMESTONE_SCHEMA,
        ("$defs", "block_entry", "properties", "weak_evidence", "additionalProperties"),
        R.WeakEvidence,
    ),
]


@pytest.mark.parametrize(("schema", "path", "shape"), SHAPES, ids=lambda x: getattr(x, "__name__", None))
def test_each_nested_mapping_has_the_keys_of_its_schema(schema, path, shape):
    """Issue 40: the nested objects typed key by key (no mapping of anything in the result objects) as
    their schemas say: the same keys in the same order, required where the schema requires them."""
    d = _definition(schema, *path)
    assert list(d["properties"]) == list(shape.__annotations__)
    assert d.get("additionalProperties") is False
    assert set(d.get("required", [])) == set(shape.__required_keys__)
