"""The real shake-table outcomes (rocklab.shake_table): reader, sign check, folds, scores,
calibration against a known truth and the target end to end on a subset.

The data (GPL-3.0) are not in the repository: the tests that need them read
``../shared/data/shake-table`` beside the checkout and skip where it is absent.
"""

import gzip
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from rocklab.io import validate_table
from rocklab.physics.wall import G
from rocklab.report import pages, tables
from rocklab.shake_table import block, calibration, evaluation, records

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data" / "shake-table"
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
SCHEMAS = ROOT / "workflow" / "schemas"

needs_data = pytest.mark.skipif(
    not (DATA / "tests.csv").is_file(),
    reason=f"no shake-table data at {DATA} (GPL-3.0, kept outside the repository; CI has ../shared)",
)


# --- reader ---------------------------------------------------------------------------------


@needs_data
def test_reader_on_the_real_files():
    tests = records.read_tests(DATA)
    assert len(tests) == tests.test.nunique() > 0
    with_file = tests[tests.motion_file != ""]
    # the most strongly shaken record: its sign check is decisive
    row = with_file.loc[with_file.peak_table_acc_g.idxmax()]
    st = records.read_motion(DATA, row)
    acc, dsp = st.select(channel="ACC")[0], st.select(channel="DSP")[0]
    assert acc.stats.units == "m/s2" and dsp.stats.units == "m" and acc.stats.delta == pytest.approx(0.005)
    assert acc.stats.npts == row.n_samples_200hz
    # the offset is the mean of the first 0.5 s, as SOURCE.md computes it at 800 Hz
    assert acc.stats.offset_g == pytest.approx(row.acc_offset_g, abs=2e-3)
    assert np.mean(acc.data[:100]) == pytest.approx(0.0, abs=1e-9)
    # +x is the displacement's direction: the accelerometer is read with the opposite sign
    assert acc.stats.sign_gain == pytest.approx(-1.0, abs=0.1) and acc.stats.sign_corr < -0.9
    raw = pd.read_csv(DATA / row.motion_file)
    np.testing.assert_allclose(acc.data, -(raw.table_acc_g - acc.stats.offset_g) * G, rtol=1e-12)
    # the velocity from the displacement agrees with the source's PGV (PGV/PGA x PGA)
    m = records.motion_measures(st)
    if not row.scaled_pga_is_nominal:
        assert m["pgv_m_s"] == pytest.approx(row.pgv_over_pga_s * row.scaled_pga_g * G, rel=0.25)
        assert m["pga_g"] == pytest.approx(row.pga_bp_0p1_25hz_g, rel=0.05)


def test_a_missing_folder_names_the_config_key(tmp_path):
    with pytest.raises(FileNotFoundError, match="shake_table_dir"):
        records.check_dir(tmp_path / "nowhere")


# --- the sign check -------------------------------------------------------------------------


def _motion_folder(tmp_path, acc_sign):
    """A one-test folder in the data's layout: a 1.2 Hz table motion, acceleration of sign ``acc_sign``."""
    dt, t = 0.005, np.arange(0, 20, 0.005)
    w = 2 * np.pi * 1.2
    disp = 50.0 * np.sin(w * t) * np.clip(t / 2, 0, 1) * np.clip((20 - t) / 2, 0, 1)  # mm
    acc = np.gradient(np.gradient(disp * 1e-3, dt), dt) / G  # g, the displacement's own sign
    (tmp_path / "motions").mkdir()
    with gzip.open(tmp_path / "motions" / "Test001.csv.gz", "wt") as fh:
        pd.DataFrame({"time_s": t, "table_acc_g": acc_sign * acc + 0.02, "table_disp_mm": disp}).to_csv(fh, index=False)
    (tmp_path / "geometry.json").write_text("{}")
    row = {"test": 1, "ground_motion": "synthetic", "motion_file": "motions/Test001.csv.gz"}
    pd.DataFrame([row]).to_csv(tmp_path / "tests.csv", index=False)
    return row


def test_sign_check_accepts_the_convention_and_refuses_a_flipped_accelerometer(tmp_path):
    (tmp_path / "a").mkdir()
    row = _motion_folder(tmp_path / "a", -1.0)
    st = records.read_motion(tmp_path / "a", row)
    acc, dsp = st.select(channel="ACC")[0], st.select(channel="DSP")[0]
    assert acc.stats.sign_gain == pytest.approx(-1.0, abs=0.05)
    # after the reader, acceleration and displacement share +x: a = d''
    d2 = np.gradient(np.gradient(dsp.data, 0.005), 0.005)
    mid = slice(800, 3200)
    assert np.corrcoef(acc.data[mid], d2[mid])[0, 1] > 0.99
    (tmp_path / "b").mkdir()
    row = _motion_folder(tmp_path / "b", +1.0)
    with pytest.raises(ValueError, match="Test001.csv.gz.*sign convention"):
        records.read_motion(tmp_path / "b", row)


def test_a_weak_record_is_not_refused_on_a_noisy_sign():
    records.check_sign(+0.4, 0.1)  # below SIGN_CHECK_MIN_CORR: no verdict
    with pytest.raises(ValueError):
        records.check_sign(+0.9, 0.9)


# --- folds ----------------------------------------------------------------------------------


def test_folds_never_share_a_ground_motion_and_are_balanced():
    rng = np.random.default_rng(1)
    groups = rng.choice([f"gm{i}" for i in range(30)], 400)
    fold = calibration.folds_by_group(groups, 5)
    for g in np.unique(groups):
        assert np.unique(fold[groups == g]).size == 1, g
    sizes = np.bincount(fold)
    assert sizes.size == 5 and sizes.max() - sizes.min() <= np.unique(groups, return_counts=True)[1].max()
    with pytest.raises(ValueError):
        calibration.folds_by_group(["one"] * 5)


@needs_data
def test_folds_of_the_real_tests_never_share_a_record():
    tests = records.read_tests(DATA)
    groups = tests.ground_motion.to_numpy(str)
    fold = calibration.folds_by_group(groups, 5)
    assert pd.DataFrame({"g": groups, "f": fold}).groupby("g").f.nunique().max() == 1


# --- scores ---------------------------------------------------------------------------------


def test_scores_against_hand_values():
    s = evaluation.scores([1, 0, 1, 0], [0.9, 0.2, 0.4, 0.5])
    assert s["accuracy"] == 0.75  # 0.4 misses an overturn; 0.5 is not > 0.5: a right standing call
    assert s["brier"] == pytest.approx((0.01 + 0.04 + 0.36 + 0.25) / 4)
    assert s["log_loss"] == pytest.approx(-(np.log(0.9) + np.log(0.8) + np.log(0.4) + np.log(0.5)) / 4)


def test_score_table_has_the_schema_and_columns_of_the_issue():
    rng = np.random.default_rng(0)
    n = 40
    pred = pd.DataFrame({"specimen": np.repeat(["SP1", "SP2"], n // 2), "observed": rng.random(n) < 0.4})
    for m in evaluation.MODELS:
        pred[f"p_{m.replace('-', '_')}"] = rng.random(n)
    table = evaluation.score_table(pred)
    assert list(table.columns) == ["specimen", "model", "accuracy", "brier", "log_loss", "n_tests"]
    assert set(table.model) == set(evaluation.MODELS)
    validate_table(table, SCHEMAS / "shake_table_scores.schema.yaml")
    with pytest.raises(Exception, match="model"):
        validate_table(table.assign(model="block"), SCHEMAS / "shake_table_scores.schema.yaml")


def test_logistic_threshold_recovers_a_known_threshold():
    rng = np.random.default_rng(2)
    x = np.exp(rng.uniform(np.log(0.01), np.log(1.0), 3000))
    y = rng.random(x.size) < evaluation.cal.logistic_probability(x, 0.12, 0.15)
    x50, beta = calibration.logistic_threshold(x, y)
    assert x50 == pytest.approx(0.12, rel=0.1) and beta == pytest.approx(0.15, rel=0.2)


# --- the block and the calibration ----------------------------------------------------------


SYNTHETIC_GEOMETRY = {
    "S": {
        "mass_kg": 300.0,
        "footprint": {
            "rocking_2d": {
                "plus_x_edge": {"alpha_rad": 0.25, "R_m": 0.30, "I_o_kgm2": 45.0, "p_rad_per_s": 4.5},
                "minus_x_edge": {"alpha_rad": 0.50, "R_m": 0.34, "I_o_kgm2": 55.0, "p_rad_per_s": 4.4},
            }
        },
    }
}


def test_the_nominal_block_is_the_geometry_and_housners_e():
    b = block.specimen_block(SYNTHETIC_GEOMETRY, "S")
    # Eq. 1 by hand: e = 1 - 2 m R^2 / I_O sin^2 alpha
    assert b["e_plus"] == pytest.approx(1 - 2 * 300 * 0.3**2 / 45 * np.sin(0.25) ** 2)
    assert b["e_minus"] == pytest.approx(1 - 2 * 300 * 0.34**2 / 55 * np.sin(0.5) ** 2)
    m = block.block_model(b)
    assert (m.alpha_pos, m.alpha_minus, m.form) == (0.25, 0.5, "exact")
    assert m.p == pytest.approx(np.sqrt(4.5 * 4.4))
    m = block.block_model(b, 0.5, 0.4, 0.9)
    assert m.alpha_pos == pytest.approx(0.125 * np.exp(0.2)) and m.alpha_minus == pytest.approx(0.25 * np.exp(-0.2))
    assert m.base_law.flat(m.alpha)[:, 0] == pytest.approx([0.9 * b["e_plus"], 0.9 * b["e_minus"]])


def _pulse_records(n=36, seed=0):
    """Sine pulses of random amplitude, frequency and sign: one 'ground motion' each."""
    rng = np.random.default_rng(seed)
    dt, out = 0.01, []
    for _ in range(n):
        f, a, s = rng.uniform(0.8, 3.0), rng.uniform(0.02, 0.25) * G, rng.choice([-1, 1])
        t = np.arange(0, 2.0 / f + 0.5, dt)
        out.append(s * a * np.sin(2 * np.pi * f * t) * (t < 2.0 / f))
    return out, dt


def test_calibration_recovers_the_instability_angle_of_outcomes_made_by_the_block():
    """Outcomes simulated by the block at a known r are fitted back to that r (not to the nominal 1)."""
    b = block.specimen_block(SYNTHETIC_GEOMETRY, "S")
    grid = {
        "alpha_r_over_alpha": np.geomspace(0.1, 1.0, 8),
        "s_alpha": np.array([-0.5, 0.0, 0.5]),
        "c": np.array([1.0]),
    }
    recs, dt = _pulse_records()
    out = block.outcome_grid(recs, [dt] * len(recs), b, np.arange(len(recs)), grid)
    true = {"alpha_r_over_alpha": grid["alpha_r_over_alpha"][3], "s_alpha": 0.0, "c": 1.0}
    y = out.overturned.sel(true).values
    assert 0.2 < y.mean() < 0.8, "the synthetic set must hold both outcomes"
    lik = calibration.OutcomeLikelihood(out.overturned.values, y, grid)
    fit = calibration.calibrate(lik, np.arange(y.size).astype(str), np.arange(y.size), n_boot=30)
    assert fit["values"]["alpha_r_over_alpha"] == pytest.approx(true["alpha_r_over_alpha"])
    assert fit["values"]["s_alpha"] == 0.0
    lo, hi = calibration.intervals(fit["boot"])["alpha_r_over_alpha"]
    assert lo <= true["alpha_r_over_alpha"] <= hi < 1.0
    assert calibration.named(block.R, (lo, hi))
    # the prediction reproduces the outcomes it was fitted to
    assert np.mean((fit["probability"] > 0.5) == y) == 1.0


# --- the target, end to end on two ground motions ---------------------------------------------


@needs_data
@pytest.mark.skipif(not SNAKEMAKE.exists(), reason="snakemake not installed beside this interpreter")
def test_shake_table_target_end_to_end_on_a_subset(tmp_path):
    results = tmp_path / "results"
    cfg = tmp_path / "config.yaml"
    cfg.write_text(
        yaml.safe_dump(
            {
                "results_dir": str(results),
                "shake_table_dir": str(DATA),
                "shake_table": {
                    "ground_motions": ["RSN1749_NWCHINA1_XIK270", "RSN221_LIVERMOR_B-LFA270", "RSN1758_SANJUAN_HDA270"],
                    "folds": 3,
                    "n_boot": 5,
                    "n_boot_cv": 3,
                    "map_n": 3,
                    "threads": 1,
                },
            }
        )
    )
    cmd = [str(SNAKEMAKE), "shake_table", "--cores", "1", "--quiet", "--directory", str(ROOT), "--configfile", str(cfg)]
    run = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, env={**os.environ, "PYTHONWARNINGS": "ignore"})
    assert run.returncode == 0, run.stderr[-3000:]
    st = results / "shake_table"
    scores = pd.read_csv(st / "scores.csv")
    assert list(scores.columns) == ["specimen", "model", "accuracy", "brier", "log_loss", "n_tests"]
    assert len(scores) == 8
    pred = pd.read_csv(st / "predictions.csv")
    assert pred.groupby("ground_motion").fold.nunique().max() == 1
    for name in evaluation.MODELS:
        assert pred[f"p_{name.replace('-', '_')}"].between(0, 1).all()
    for f in ("nominal_errors.csv", "fragility.csv", "parameters.csv", "maps_SP1.nc", "maps_SP2.nc"):
        assert (st / f).is_file()
    assert (results / "figures" / "shake_table_fragility.png").is_file()
    assert all((results / "benchmarks" / "shake_table" / f"{j}.tsv").is_file() for j in ("motions", "calibration"))
    # the page reads the run's numbers, and says "not run" without them
    template = (ROOT / "docs" / "templates" / "shake-table.md").read_text()
    numbers = pages.docs_numbers(results)
    assert numbers["shake_table"]["SP1"]["n_tests"] == len(pred) // 2
    assert numbers["performance"]["shake_table"]["job_times_s"].keys() >= {"motions", "calibration"}
    page = pages.render(template, numbers)
    assert "not measured" not in page and tables.NOT_RUN not in page
    assert tables.NOT_RUN in pages.render(template, pages.docs_numbers(tmp_path), strict=False)


@pytest.mark.skipif(not SNAKEMAKE.exists(), reason="snakemake not installed beside this interpreter")
def test_the_target_stops_naming_the_key_when_the_folder_is_missing(tmp_path):
    cmd = [
        str(SNAKEMAKE),
        "shake_table",
        "--dry-run",
        "--directory",
        str(ROOT),
        "--config",
        f"results_dir={tmp_path / 'results'}",
        f"shake_table_dir={tmp_path / 'nowhere'}",
    ]
    run = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    assert run.returncode != 0
    assert "shake_table_dir" in run.stdout + run.stderr
