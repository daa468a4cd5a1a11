"""Shared fixtures: a tiny campaign cut from the embedded one."""

import shutil
from pathlib import Path

import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[1]
CAMPAIGN = ROOT / "raw" / "campaign"


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
