"""Campaigns of other instruments through the workflow: a mixed one (transducer, rotation and
inertial tests of the same walls, and the instruments' own files: TDMS, C3D, a film) through the
default target `all`, every valid test of each kind read, judged valid and carried to the
dissipation, the diagnosis and the pages; and one without transducers at all through `campaign`."""

import os
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
import yaml

from rocklab.lab import virtual_lab as vl

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
INSTRUMENTS = {"transducers": 400.0, "rotation": 240.0, "inertial": 1000.0}
#: The instruments' own files (issue 43): the format -> the prefix of its tests, the rate [Hz].
NATIVE = {"tdms": ("D", 400.0), "c3d": ("C", 240.0), "video": ("V", 60.0)}


def _run_target(tmp_path, plan, target="campaign"):
    """Write ``plan`` as a campaign and run ``target`` on it (a working directory of its own);
    its truth and its results folder."""
    folder, results = tmp_path / "campaign", tmp_path / "results"
    truth = vl.write_campaign(folder, plan, seed=11).set_index("test_id")
    config = {
        "raw_dir": str(folder),
        "results_dir": str(results),
        "figures": {"fig9_specimen": "1a"},
        # `all` beyond the campaign: the maps of one short record on a 5 x 5 grid (test_overturning
        # covers the stage), one virtual test per instrument and rate (test_instruments the table)
        "maps": {"records": ["Pac164"], "n": 5, "calibrated_n": 5},
        "instruments": {"accuracy_tests": 1},
    }
    (tmp_path / "config.yaml").write_text(yaml.safe_dump(config))
    cmd = [
        str(SNAKEMAKE),
        target,
        "--cores",
        "1",
        "--snakefile",
        str(ROOT / "Snakefile"),
        "--directory",
        str(tmp_path),
        "--configfile",
        str(tmp_path / "config.yaml"),
    ]
    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    run = subprocess.run(cmd, capture_output=True, text=True, cwd=tmp_path, env=env)
    assert run.returncode == 0, run.stderr[-3000:]
    return truth, results


@pytest.mark.skipif(not SNAKEMAKE.exists(), reason="snakemake not installed beside this interpreter")
def test_a_mixed_campaign_of_every_instrument_and_file_runs_through_the_default_target(tmp_path):
    """Transducer, rotation and inertial tests of two walls, and (issue 43) TDMS, C3D and a small
    film of one of them, in one campaign: every test read, judged and carried to the dissipation,
    the diagnosis and the pages of `all`."""
    from rocklab.lab.virtual_native import VideoEffects

    plan = [
        vl.VirtualTest(
            f"{kind[0].upper()}{spec}{k}", specimen=spec, fs=fs, instrument=kind, theta0_ratio=0.99 + 0.004 * k
        )
        for spec in ("1a", "2a")
        for kind, fs in INSTRUMENTS.items()
        for k in range(2)
    ]
    plan += [
        vl.VirtualTest(
            f"{prefix}{k}",
            specimen="1a",
            fs=fs,
            instrument=kind,
            theta0_ratio=0.99 + 0.004 * k,
            video=VideoEffects(height_px=160, width_px=120, marker_px=7.0),
        )
        for kind, (prefix, fs) in NATIVE.items()
        for k in range(2)
    ]
    plan.append(vl.VirtualTest("Rdead", specimen="1a", fs=240.0, instrument="rotation", faults=[vl.Fault("dead")]))
    truth, results = _run_target(tmp_path, plan, "all")
    qc = pd.read_csv(results / "qc.csv", keep_default_na=False).set_index("test_id")
    recorded = {"tdms": "transducers", "c3d": "rotation", "video": "rotation"}
    assert qc.instrument.to_dict() == truth.instrument.replace(recorded).to_dict()
    assert qc.valid.to_dict() == truth.expected_valid.to_dict(), qc.reject_detail.to_dict()
    assert qc.reject_reason["Rdead"] == "instrument_malfunction" and qc.channels_dead["Rdead"] == "theta_rad"
    films = truth.index[truth.instrument == "video"]
    assert (qc.frames_tracked[films] > 0).all() and (qc.frames_tracked.drop(films) == 0).all()
    tests = pd.read_csv(results / "tests.csv").set_index("test_id")
    valid = truth.index[truth.expected_valid]
    assert set(tests.index) == set(valid)
    # the same walls give the same restitution whatever recorded them (the files of one wall aside)
    by_instrument = truth.instrument[valid].reindex(tests.index)
    e = tests.e_exp_eq11[by_instrument.isin(INSTRUMENTS)].groupby(by_instrument).median()
    assert (e.max() - e.min()) < 0.01, e
    assert (results / "diagnosis.json").is_file()
    numbers = (results / "docs" / "numbers.json").read_text()
    assert '"quality_control"' in numbers and list((results / "docs").glob("*.md"))


@pytest.mark.skipif(not SNAKEMAKE.exists(), reason="snakemake not installed beside this interpreter")
def test_a_campaign_without_transducers_runs_through_the_campaign_target(tmp_path):
    """A lab without the transducer frame: no setup, no setup in setups.csv; Figs. 6, 8 and 9 draw its theta."""
    plan = [
        vl.VirtualTest(f"{kind[0].upper()}{k}", specimen="1a", fs=fs, instrument=kind, theta0_ratio=0.99 + 0.002 * k)
        for kind, fs in (("rotation", 100.0), ("inertial", 500.0))
        for k in range(3)
    ]
    truth, results = _run_target(tmp_path, plan)
    qc = pd.read_csv(results / "qc.csv", keep_default_na=False).set_index("test_id")
    assert qc.valid.all() and set(qc.instrument) == {"rotation", "inertial"}
    assert list((results / "figures").glob("fig06*")), sorted(p.name for p in (results / "figures").iterdir())
