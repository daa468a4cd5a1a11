"""Shared fixtures (a tiny campaign cut from the embedded one), and the kind of every test.

Kinds (markers, registered in pyproject.toml; ``make test`` runs them all):

- ``unit``: the library, a test in well under a second or two; ``make
  test-unit`` runs them in under a minute on two cores.
- ``slow``: the library's long computations (maps against their reference,
  bootstraps, simulations of whole campaigns).
- ``workflow``: Snakemake or an installed package run as a user runs them.
- ``docs``: the committed pages, the README and the report against the results.

The kind is given here, by file and test, not in the test files: a test that
runs Snakemake (its ``skipif`` names snakemake) is a workflow test wherever it is.

Workflow tests run at once on several workers: each gives Snakemake a working
directory of its own (``--directory``, for its locks and metadata), never the
checkout, save dry runs, which take no lock.
"""

import shutil
from pathlib import Path

import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[1]
CAMPAIGN = ROOT / "raw" / "campaign"

#: The kind of every test of a file, where it is not ``unit``.
KIND_OF_FILE = {
    "test_workflow.py": "workflow",
    "test_interrupt.py": "workflow",
    "test_install.py": "workflow",
    "test_slurm.py": "workflow",
    "test_shapes.py": "workflow",
    "test_docs.py": "docs",
    "test_report.py": "docs",
}
#: Tests of the library that take a second or more each, their fixtures included
#: (``pytest -m unit --durations=0``, 2 cores): file -> names of tests, or of
#: the fixtures that make every test using them slow.
SLOW = {
    # a module's campaigns diagnosed once: 110 s and 80 s
    "test_diagnosis.py": {"diagnosed"},
    "test_diagnosis_flight.py": {"diagnosed", "test_a_viscous_loss_is_still_the_listed_flight_damping"},
    "test_overturning.py": {
        "test_maps_agree_with_the_event_driven_reference_up_to_the_boundary",
        "test_calibrated_maps_agree_with_the_event_driven_reference",
        "test_cells_at_the_onset_threshold_finish",
    },
    "test_batch.py": {
        "test_overturning_batch_matches_reference",
        "test_ground_batch_covers_the_free_motion_after_the_record",
        "test_onset_on_the_first_sample",
    },
    "test_campaign.py": {"test_embedded_records_read_as_python_reads_them"},
    # the mixed campaign of every instrument, reduced once: 8 s; the accuracy at 240 and 1000 Hz: 3 s
    "test_instruments.py": {"mixed", "test_per_impact_restitution_within_0005_of_the_truth_at_240_and_1000_hz"},
    # a wall of the contact lab (MuJoCo) written and reduced once: 7 s
    "test_contact_lab.py": {"campaign"},
    # a mixed campaign of text, TDMS, C3D and video, written and reduced once: 4 s
    "test_native_files.py": {"mixed"},
    # one series written as text, TDMS, C3D and film, each campaign reduced and diagnosed: 10 s
    "test_native_verdicts.py": {"diagnosed"},
    # one series per instrument and scenario diagnosed once: 16 s
    "test_instruments_diagnosis.py": {"diagnosed"},
    # virtual series simulated and diagnosed: a few seconds each
    "test_series_inference.py": {
        "friction",
        "test_one_test_names_nothing_and_says_why",
        "test_three_tests_at_100_hz_losing_7_percent_of_e_name_it",
        "test_a_null_series_of_three_tests_names_nothing",
    },
    # every pair of causes on each wall, by the reference and the engine: 4-9 s; three series diagnosed: 3 s
    "test_every_law.py": {
        "test_every_pair_of_causes_is_simulated_by_the_reference_and_the_engine_alike",
        "test_a_series_whose_diagnosis_raises_is_reported_not_finished_and_the_rest_runs",
    },
    # ten-test virtual series simulated and diagnosed: 30-50 s each; a hundred null series of the engine: 1.5 s
    "test_series_change.py": {
        "test_a_corner_crushed_part_way_is_named_where_and_how_much",
        "test_a_rocking_edge_worn_test_after_test_is_named_gradual_and_its_law_kept",
        "test_a_rocking_edge_that_stays_names_no_change",
        "test_a_series_of_one_state_names_no_change_at_the_level_though_its_tests_vary",
    },
}
#: Tests that run Snakemake without a ``skipif`` that names it: file -> test names.
WORKFLOW = {"test_config.py": {"test_every_run_takes_the_workflow_profile"}}


def test_kind(item):
    """The kind of a collected test (see the module's docstring)."""
    kind = KIND_OF_FILE.get(item.path.name, "unit")
    if kind == "unit" and (
        item.originalname in WORKFLOW.get(item.path.name, ())
        or any("snakemake" in str(m.kwargs.get("reason", "")) for m in item.iter_markers("skipif"))
    ):
        return "workflow"
    slow = SLOW.get(item.path.name, set())
    if kind == "unit" and (item.originalname in slow or slow & set(item.fixturenames)):
        return "slow"
    return kind


#: Files whose tests run longest or wait on other processes (the SLURM scheduler's polls): run
#: first. pytest-xdist hands tests out in collection order, and one of these last kept one worker
#: busy (or idle, waiting) for minutes after the other had finished.
FIRST = ("test_slurm.py", "test_environments.py", "test_shapes.py")


def pytest_collection_modifyitems(items):
    for item in items:
        item.add_marker(test_kind(item))
    # a stable sort: each file's tests stay together, in their order (its module fixtures once)
    items.sort(key=lambda item: FIRST.index(item.path.name) if item.path.name in FIRST else len(FIRST))


def pytest_terminal_summary(terminalreporter):
    """What the test SLURM cluster ran (tests/test_slurm.py's ``slurm`` properties), even under ``-q``."""
    lines = [v for r in terminalreporter.stats.get("passed", []) for k, v in r.user_properties if k == "slurm"]
    if lines:
        terminalreporter.write_sep("-", "jobs on the test SLURM cluster")
        for line in lines:
            terminalreporter.write_line(line)


@pytest.fixture
def tiny_campaign(tmp_path):
    """Three tests of the embedded campaign (two-sided push, one-sided, 100 Hz) in a writable copy."""
    dst = tmp_path / "campaign"
    (dst / "tests").mkdir(parents=True)
    tests = pd.read_csv(CAMPAIGN / "tests.csv", dtype=str, keep_default_na=False)
    keep = tests[tests.test_id.isin(["T0001", "T0027", "T0100"])]
    keep.to_csv(dst / "tests.csv", index=False)
    for name in ("specimens.csv", "setups.csv"):
        shutil.copy(CAMPAIGN / name, dst / name)
    for f in keep.file:
        shutil.copy(CAMPAIGN / f, dst / f)
    return dst
