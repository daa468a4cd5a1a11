"""Every target on any campaign shape: small virtual campaigns of random shape through the workflow.

A shape is what the raw format allows a lab's campaign to be (docs/raw-format.md):
one or many specimens and series, a single test, one or both boundary
conditions, no rejection, some or only rejections, 100 to 1000 Hz, the optional
columns of tests.csv left out, a specimen without tests.  Hypothesis draws a
few shapes (derandomised: the same ones on every run) and each runs the
default target ``all`` (the campaign, the maps of one record on a tiny grid,
the limestone blocks, the docs pages): no shape may stop it, except a campaign
with no valid test, which ends with a message that says so and its ``qc.csv``;
what a shape lacks (a boundary, a rejection, enough tests for the diagnosis to
name a cause) is zero or "not measured" on its pages.
"""

import json
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pandas as pd
import pytest
import yaml

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import example, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

pytest.importorskip("rocklab.simulation.rocking_model")
from rocklab.lab.virtual_lab import DEFAULT_SPECIMENS, VirtualTest, write_campaign  # noqa: E402
from rocklab.lab.virtual_record import Fault  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")

#: Faults and releases that reject a test, one per kind of verdict the QC gives.
REJECTIONS = (
    dict(faults=[Fault("unreadable")]),
    dict(faults=[Fault("dead", 0), Fault("dead", 1)]),
    dict(release_ratio=0.2),
)
#: Free rocking simulated [s]: every wall of DEFAULT_SPECIMENS is at rest
#: before it (a shorter record ends rocking, an out-of-plumb residual).
T_END = 20.0


@dataclass(frozen=True)
class Shape:
    """The shape of a virtual campaign (see the module's docstring)."""

    specimens: tuple
    boundaries: tuple
    n_tests: int
    rejected: str  # 'none', 'some' (the last test) or 'all'
    fs: tuple  # Hz, test by test (cycled)
    without_note: bool
    without_contact_depth: bool  # only where every test is two-sided
    idle_specimen: bool  # specimens.csv lists a specimen without tests

    def plan(self):
        tests = []
        for k in range(self.n_tests):
            boundary = self.boundaries[k % len(self.boundaries)]
            reject = self.rejected == "all" or (self.rejected == "some" and k == self.n_tests - 1)
            tests.append(
                VirtualTest(
                    test_id=f"S{k + 1:03d}",
                    specimen=self.specimens[k % len(self.specimens)],
                    boundary=boundary,
                    contact_depth_mm=120.0 if boundary == "one-sided" else None,
                    fs=float(self.fs[k % len(self.fs)]),
                    residual_top_mm=0.0,
                    **(REJECTIONS[k % len(REJECTIONS)] if reject else {}),
                )
            )
        return tests

    def write(self, folder):
        """The campaign folder in the raw format; the test ids that must be valid."""
        used = list(self.specimens)
        if self.idle_specimen:
            used.append(next(s for s in DEFAULT_SPECIMENS.specimen if s not in used))
        specimens = DEFAULT_SPECIMENS[DEFAULT_SPECIMENS.specimen.isin(used)]
        truth = write_campaign(folder, self.plan(), specimens=specimens, seed=7, t_end=T_END)
        tests = pd.read_csv(folder / "tests.csv", dtype=str, keep_default_na=False)
        drop = ["note"] * self.without_note
        if self.without_contact_depth and set(self.boundaries) == {"two-sided"}:
            drop.append("contact_depth_mm")
        tests.drop(columns=drop).to_csv(folder / "tests.csv", index=False)
        return truth.test_id[truth.expected_valid].tolist()


@st.composite
def shapes(draw):
    n_specimens = draw(st.integers(1, 2))
    specimens = tuple(draw(st.permutations(["1a", "3b", "5c"]))[:n_specimens])
    boundaries = draw(st.sampled_from([("two-sided",), ("one-sided",), ("two-sided", "one-sided")]))
    n_tests = draw(st.integers(1, 4))
    return Shape(
        specimens=specimens,
        boundaries=boundaries,
        n_tests=n_tests,
        rejected=draw(st.sampled_from(["none", "some", "all"])),
        fs=tuple(draw(st.lists(st.sampled_from([100, 250, 500, 1000]), min_size=1, max_size=n_tests))),
        without_note=draw(st.booleans()),
        without_contact_depth=draw(st.booleans()),
        idle_specimen=draw(st.booleans()),
    )


def _run_all(shape, workdir):
    """Write the shape's campaign under workdir and run `all` there (its own working directory).

    Returns the completed process, the results folder and the test ids that must be valid.
    """
    campaign, results = workdir / "campaign", workdir / "results"
    valid = shape.write(campaign)
    config = {
        "raw_dir": str(campaign),
        "results_dir": str(results),
        "figures": {"fig9_specimen": shape.specimens[0]},
        # the maps of one short record on a 5 x 5 grid: test_overturning covers the stage
        "maps": {"records": ["Pac164"], "n": 5, "calibrated_n": 5},
        # one virtual test per instrument and rate (tests/test_instruments.py covers the table)
        "instruments": {"accuracy_tests": 1},
    }
    (workdir / "config.yaml").write_text(yaml.safe_dump(config))
    cmd = [
        str(SNAKEMAKE),
        "all",
        "--snakefile",
        str(ROOT / "Snakefile"),
        "--directory",
        str(workdir),
        "--configfile",
        str(workdir / "config.yaml"),
        "--cores",
        "1",
    ]
    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    run = subprocess.run(cmd, capture_output=True, text=True, cwd=workdir, env=env)
    return run, results, valid


NO_REJECTION = Shape(("1a", "3b"), ("two-sided", "one-sided"), 3, "none", (100, 1000), True, False, True)
ONLY_REJECTIONS = Shape(("5c",), ("two-sided",), 3, "all", (250,), True, True, False)


@pytest.mark.skipif(not SNAKEMAKE.exists(), reason="snakemake not installed beside this interpreter")
@settings(max_examples=2, deadline=None, derandomize=True, database=None)
@example(shape=NO_REJECTION)
@example(shape=ONLY_REJECTIONS)
@given(shape=shapes())
def test_every_target_on_any_campaign_shape(shape, tmp_path_factory):
    run, results, valid = _run_all(shape, tmp_path_factory.mktemp("shape"))
    qc = pd.read_csv(results / "qc.csv", keep_default_na=False)
    assert qc.test_id.tolist() == [f"S{k + 1:03d}" for k in range(shape.n_tests)]
    assert qc.test_id[qc.valid.astype(str) == "True"].tolist() == valid, qc
    if not valid:
        assert run.returncode != 0
        assert "no test of the campaign is valid" in run.stderr, run.stderr[-3000:]
        return
    assert run.returncode == 0, (shape, run.stderr[-3000:])
    pages = {p.name for p in (ROOT / "docs" / "templates").glob("*.md")}
    assert {p.name for p in (results / "docs").iterdir()} == pages | {"numbers.json"}
    assert (results / "report" / "qc.html").is_file() and (results / "figures" / "fig09.png").is_file()
    # what the campaign lacks (a boundary, a rejection, a series) is zero or "not measured",
    # never an error, and its pages keep no placeholder
    numbers = json.loads((results / "docs" / "numbers.json").read_text())
    qc_numbers = numbers["quality_control"]
    assert qc_numbers["verdicts"]["valid"] == len(valid)
    for absent in {"two-sided", "one-sided"} - set(shape.boundaries):
        assert numbers["dissipation"][absent.replace("-", "_")]["stands_apart"] == []
    page = (results / "docs" / "quality-control.md").read_text()
    for s in qc_numbers["series"]:
        assert f"| {s['series']} | {s['n_valid']} | {s['n_rejected']} |" in page, s
    assert not [p for p in (results / "docs").glob("*.md") if "{{" in p.read_text()]
