"""The wheel installs into a clean environment and works outside the checkout.

Recipe: the wheel is built offline from a copy of the sources (``pip wheel
--no-build-isolation``, with this environment's setuptools) and installed
with ``--no-deps`` into a fresh venv.  The dependencies are not downloaded:
a ``.pth`` file in the venv adds this environment's site-packages as a plain
folder, and a folder added so has its own ``.pth`` files ignored, so the
editable install of the checkout that lives there is not loaded.  Everything
runs from a temporary folder without ``PYTHONPATH``: the rocklab found is the
wheel's (checked), and so are its data and its entry points.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
import tomllib
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from test_docs import check_readme_example_output, readme_example

import rocklab

ROOT = Path(__file__).resolve().parents[1]


def unmet_build_requirements():
    """The build requirements of pyproject.toml that this environment does not meet, as text."""
    requires = tomllib.loads((ROOT / "pyproject.toml").read_text())["build-system"]["requires"]
    unmet = []
    for req in map(Requirement, requires):
        try:
            installed = version(req.name)
        except PackageNotFoundError:
            installed = None
        if installed is None or not req.specifier.contains(installed, prereleases=True):
            unmet.append(f"{req} (installed: {installed})")
    return unmet


def run(args, **kwargs):
    """Run a command; its output is in the failure message."""
    done = subprocess.run([str(a) for a in args], capture_output=True, text=True, timeout=120, **kwargs)
    assert done.returncode == 0, f"{' '.join(map(str, args))}\n{done.stdout}\n{done.stderr}"
    return done


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """A venv with the wheel of the checkout; returns (venv, folder to run in, environment)."""
    unmet = unmet_build_requirements()
    if unmet:
        pytest.skip(f"cannot build the wheel offline: {', '.join(unmet)}; `make venv` installs requirements.lock")
    tmp = tmp_path_factory.mktemp("install")
    # a copy: building in place would write build/ and *.egg-info into the checkout
    sources = tmp / "sources"
    shutil.copytree(ROOT / "src", sources / "src", ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy2(ROOT / name, sources / name)
    run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "--no-index", "-w", tmp, sources])
    (wheel,) = tmp.glob("rocklab-*.whl")

    venv = tmp / "venv"
    run([sys.executable, "-m", "venv", "--without-pip", venv])
    python = venv / "bin" / "python"
    run([sys.executable, "-m", "pip", "--python", python, "install", "--no-deps", "--no-index", wheel])
    purelib = Path(run([python, "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"]).stdout.strip())
    dependencies = dict.fromkeys([sysconfig.get_path("purelib"), sysconfig.get_path("platlib")])
    (purelib / "dependencies-of-the-test.pth").write_text("\n".join(dependencies) + "\n")

    work = tmp / "work"
    work.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}
    env["PYTHONNOUSERSITE"] = "1"
    return venv, work, env


CHECKS = """
import json
from importlib.metadata import files, version

import obspy

import rocklab
from rocklab.diagnosis.block_tests import read_events
from rocklab.diagnosis.result import DIAGNOSIS_SCHEMA, LIMESTONE_SCHEMA
from rocklab.seismic.accelerograms import accelerogram_dir, load_record

record = load_record("40EIC180")
stream = obspy.read(accelerogram_dir() / "IELC180.AT2")  # no format: obspy asks the wheel's plugins
# the two plugins added last, SLAMMER finding its dt in the wheel's EQdata.txt
slammer = obspy.read(accelerogram_dir() / "TAF-111")[0]
csv = obspy.read(accelerogram_dir() / "RSN1086_NORTHR_SYL360.AT2")[0]
events = read_events()
print(json.dumps({
    "rocklab": rocklab.__file__,
    "records": str(accelerogram_dir()),
    "version": rocklab.__version__,
    "metadata_version": version("rocklab"),
    "licenses": sorted(f.name for f in files("rocklab") if "licenses" in f.parts),
    "npts": record.stats.npts,
    "format": stream[0].stats._format,
    "new_formats": [slammer.stats._format, slammer.stats.delta, csv.stats._format],
    "trials": int(events.source_id.nunique()),
    "schemas": [str(p) for p in (DIAGNOSIS_SCHEMA, LIMESTONE_SCHEMA) if p.is_file()],
}))
"""


def test_wheel_holds_the_library_its_data_and_licence(installed):
    venv, work, env = installed
    out = json.loads(run([venv / "bin" / "python", "-c", CHECKS], cwd=work, env=env).stdout)
    assert Path(out["rocklab"]).is_relative_to(venv), out["rocklab"]
    assert Path(out["records"]).is_relative_to(venv), out["records"]
    assert out["version"] == out["metadata_version"] == rocklab.__version__
    assert out["licenses"] == ["LICENSE"]
    assert out["npts"] == 2688  # elcentro_NS_full.dat (manifest.csv)
    assert out["format"] == "PEER_LEGACY_AT2"
    assert out["new_formats"] == ["SLAMMER", 0.01, "CSV_TWO_COLUMN"]
    assert out["trials"] == 134  # 135 trials, one duplicate left out (README of the tables)
    # the schemas that the results are written and read by (rocklab.diagnosis.result)
    assert len(out["schemas"]) == 2 and all(Path(p).is_relative_to(venv) for p in out["schemas"]), out["schemas"]


def test_readme_example_runs_from_the_wheel(installed):
    venv, work, env = installed
    (work / "example.py").write_text(readme_example())
    check_readme_example_output(run([venv / "bin" / "python", "example.py"], cwd=work, env=env).stdout)


def test_version_option(installed):
    venv, work, env = installed
    done = run([venv / "bin" / "rocklab", "--version"], cwd=work, env=env)
    assert done.stdout.strip() == f"rocklab {rocklab.__version__}"
