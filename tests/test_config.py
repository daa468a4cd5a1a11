"""The workflow's configuration: one schema holds every key and default, the library agrees with it,
and a misspelt key or a results folder inside the campaign is refused with a line that names it."""

import errno
import inspect
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import jsonschema
import pytest
import yaml

from rocklab.config import (
    SCHEMA,
    ConfigError,
    calibrated_map_n,
    check_paths,
    check_writable,
    recorded_path,
    schema_defaults,
    schema_error,
)

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")


@pytest.fixture(scope="module")
def schema():
    return yaml.safe_load((ROOT / SCHEMA).read_text())


def _objects(schema, where="config"):
    yield where, schema
    for k, sub in schema.get("properties", {}).items():
        if sub.get("type") == "object":
            yield from _objects(sub, f"{where}.{k}")


def _signature_defaults(fn, *names):
    params = inspect.signature(fn).parameters
    return {k: params[k].default for k in names}


def test_every_key_has_a_description_and_a_default_and_no_other_key_is_accepted(schema):
    for where, obj in _objects(schema):
        assert obj.get("additionalProperties") is False, where
        for key, sub in obj["properties"].items():
            assert sub.get("description"), f"{where}.{key}"
            assert "default" in sub, f"{where}.{key}"


def test_every_key_is_read_by_the_workflow(schema):
    """A key nothing reads is not configuration: the rules read each one by name, but for the
    sections they hand whole to the library (whose defaults hold the same keys, see below)."""
    text = "".join(p.read_text() for p in [ROOT / "Snakefile", *sorted((ROOT / "workflow" / "rules").glob("*.smk"))])
    whole = {"config.channels", "config.validity", "config.maps.eq17"}
    for where, obj in _objects(schema):
        for key in obj["properties"]:
            assert f'["{key}"]' in text or where in whole, f"{where}.{key}"
    assert 'options={"channels": config["channels"], "validity": config["validity"]}' in text
    assert 'p.eq17["a"], p.eq17["b"]' in (ROOT / "scripts" / "overturning_maps.py").read_text()


def test_snakemake_fills_every_default(schema):
    """The rules read config["maps"]["n"] etc. without defaults of their own: validation fills them."""
    validate = pytest.importorskip("snakemake.utils").validate
    config = {"maps": {"n": 11}}
    validate(config, str(ROOT / SCHEMA))
    expected = schema_defaults(schema)
    expected["maps"]["n"] = 11
    assert config == expected
    shipped = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    validate(shipped, str(ROOT / SCHEMA))
    assert shipped == schema_defaults(schema)


def test_library_defaults_equal_the_schema(schema):
    from rocklab.diagnosis import diagnose_records
    from rocklab.dissipation.statistics import campaign_tables
    from rocklab.lab import channels, validity
    from rocklab.lab.campaign import Campaign
    from rocklab.physics.impact import AmplitudeLaw
    from rocklab.seismic.maps import overturning_map
    from rocklab.seismic.walls import ALPHA, R

    d = schema_defaults(schema)
    assert d["channels"] == channels.OPTIONS
    assert d["validity"] == validity.RULES
    assert d["statistics"] == _signature_defaults(campaign_tables, "n_boot", "seed")
    max_tests = _signature_defaults(Campaign.reduction_jobs, "max_tests")["max_tests"]
    assert d["reduction"] == {"max_tests_per_job": max_tests}
    diagnosis = dict(d["diagnosis"])
    assert diagnosis.pop("max_tests_per_job") == _signature_defaults(Campaign.diagnosis_jobs, "max_tests")["max_tests"]
    assert diagnosis == _signature_defaults(diagnose_records, "n_boot", "n_history", "seed")
    maps = d["maps"]
    assert (maps["alpha"], maps["R"]) == (ALPHA, R)
    names = ("n", "lo", "hi", "alpha", "R", "form", "polarity", "chunks")
    assert {k: maps[k] for k in names} == _signature_defaults(overturning_map, *names)
    assert maps["eq17"] == _signature_defaults(AmplitudeLaw, "a", "b")


def _error(config, schema):
    try:
        jsonschema.Draft202012Validator(schema).validate(config)
    except jsonschema.ValidationError as exc:
        return str(schema_error(exc))
    raise AssertionError("the configuration passed")


def test_schema_errors_name_the_key(schema):
    assert _error({"result_dir": "x"}, schema).startswith("unknown config key result_dir (the keys here: raw_dir,")
    assert _error({"maps": {"nn": 3}}, schema).startswith("unknown config key maps.nn (the keys here: records, n,")
    msg = _error({"statistics": {"n_boot": "100"}}, schema)
    assert msg.startswith("config key statistics.n_boot: '100' is not of type 'integer'") and "--configfile" in msg
    # Snakemake wraps the error in its own; the message is found in its args
    assert str(schema_error(RuntimeError("Error validating config file.", _validation_error(schema)))).startswith(
        "unknown config key raw-dir"
    )


def _validation_error(schema):
    return next(jsonschema.Draft202012Validator(schema).iter_errors({"raw-dir": "x"}))


def test_check_paths(tmp_path):
    raw = tmp_path / "campaign"
    with pytest.raises(ConfigError, match="is not a folder"):
        check_paths(raw, tmp_path / "out")
    raw.mkdir()
    with pytest.raises(ConfigError, match="has no tests.csv"):
        check_paths(raw, tmp_path / "out")
    (raw / "tests.csv").write_text("test_id\n")
    check_paths(raw, tmp_path / "out")
    check_paths(raw, tmp_path / "campaign-results")  # a sibling whose name starts alike
    for inside in (raw, raw / "results", raw / "a" / ".." / "b", tmp_path / "x" / ".." / "campaign"):
        with pytest.raises(ConfigError, match="is inside raw_dir"):
            check_paths(raw, inside)


def test_check_writable_creates_the_folder_and_leaves_nothing_in_it(tmp_path):
    check_writable(tmp_path / "new" / "results")
    assert list((tmp_path / "new" / "results").iterdir()) == []


@pytest.mark.parametrize("code", [errno.EROFS, errno.EACCES, errno.ENOSPC])
def test_a_results_folder_that_cannot_be_written_is_refused_by_name(tmp_path, monkeypatch, code):
    """A read-only mount, another user's folder, a full disk: the write itself is refused
    (file modes do not tell, and root passes them); the workflow's own test mounts one."""

    def refused(*args, **kwargs):
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(tempfile, "mkstemp", refused)
    with pytest.raises(ConfigError, match=rf"results_dir '{tmp_path}' cannot be written \({os.strerror(code)}\)"):
        check_writable(tmp_path)


def test_the_calibrated_maps_grid_is_a_subgrid_of_the_papers():
    assert calibrated_map_n(201, 101) == 101
    # a quick look at n = 3 keeps its own grid
    assert calibrated_map_n(3, 101) == 3
    with pytest.raises(ConfigError, match="maps.calibrated_n: 151 with maps.n = 201"):
        calibrated_map_n(201, 151)


def test_recorded_path_is_relative_inside_the_working_directory(tmp_path):
    assert recorded_path(tmp_path / "workflow" / "x.yaml", workdir=tmp_path) == os.path.join("workflow", "x.yaml")
    assert recorded_path(tmp_path / "x.csv", workdir=tmp_path / "checkout") == str((tmp_path / "x.csv").resolve())


def _dry_run(*config):
    cmd = [str(SNAKEMAKE), "-n", "--cores", "1", "--config", *config]
    run = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, env={**os.environ, "PYTHONWARNINGS": "ignore"})
    return run.returncode, run.stdout + run.stderr


@pytest.mark.skipif(not SNAKEMAKE.exists(), reason="snakemake not installed beside this interpreter")
@pytest.mark.parametrize(
    "config, message",
    [
        (["result_dir=x"], "unknown config key result_dir"),
        (["raw-dir=raw/campaign"], "unknown config key raw-dir"),
        (["results_dir=raw/campaign/results"], "is inside raw_dir"),
        (["raw_dir=raw"], "raw_dir 'raw' has no tests.csv"),
    ],
)
def test_the_workflow_refuses_a_bad_configuration(config, message):
    rc, out = _dry_run(*config)
    assert rc != 0 and message in out, out[-2000:]


def test_the_raw_format_is_specified_in_the_repository():
    """The format's page ships with the code; nothing points outside the repository for it."""
    assert "## tests.csv" in (ROOT / "docs" / "raw-format.md").read_text()
    folders = ("src", "scripts", "workflow", "config", "tests", "docs")
    files = [p for f in folders for p in (ROOT / f).rglob("*") if p.suffix in {".py", ".smk", ".yaml", ".md"}]
    assert not [p for p in files if "shared/spec" in p.read_text() and p.name != "test_config.py"]


def test_every_run_takes_the_workflow_profile(tmp_path):
    """profiles/default is read by a plain `snakemake` in the checkout: no input
    checksums (Snakemake would hash every input of a job once per output)."""
    snakemake = Path(sys.executable).with_name("snakemake")
    if not snakemake.exists():
        pytest.skip("snakemake not installed beside this interpreter")
    profile = yaml.safe_load((ROOT / "profiles" / "default" / "config.yaml").read_text())
    assert profile == {"max-checksum-file-size": 0}
    cmd = [str(snakemake), "-n", "qc_table", "--cores", "1", "--config", f"results_dir={tmp_path}"]
    run = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "Using workflow specific profile profiles/default" in run.stdout + run.stderr
