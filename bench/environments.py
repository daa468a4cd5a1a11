"""Benchmark: the published numbers under other floating-point environments (issue 39).

    python bench/environments.py --out results/bench [--envs native generic avx2] [--cores 2]

Runs the main job (``snakemake all``) on the embedded campaign, and the
target ``shake_table`` where its data are at hand (``--shake-table-dir``,
by default ``../shared/data/shake-table`` beside the checkout), from an
empty results folder, once under each environment of
:data:`rocklab.reproducibility.ENVIRONMENTS` (``native`` may reuse a
results folder of ``make run``: ``--native-results results``), and compares
every number of the pages (``rocklab.report.pages.docs_numbers``) between
them and with the committed ``docs/numbers.json``. Writes
``<out>/environments.json``: each number that moved, its values, its spread
and the tolerance its stage declares; docs/reproducibility.md shows them.
Target: every number within its declared tolerance (exit status 1 if not).
"""

from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from rocklab import summaries
from rocklab.report import pages
from rocklab.reproducibility import ENVIRONMENTS, environment, moves

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
#: The pseudo-environment of the committed pages.
COMMITTED = "committed"


def _cpu() -> str:
    """The CPU's model name and its widest SIMD extension."""
    try:
        info = Path("/proc/cpuinfo").read_text()
    except OSError:
        return platform.processor() or platform.machine()
    model = next((line.split(":", 1)[1].strip() for line in info.splitlines() if line.startswith("model name")), "")
    flags = next((line.split(":", 1)[1].split() for line in info.splitlines() if line.startswith("flags")), [])
    simd = next((f for f in ("avx512f", "avx2", "avx", "sse4_2") if f in flags), "none")
    return f"{model} ({simd})"


#: The shake-table data where developers and CI keep them (GPL-3.0: never in the repository).
SHAKE_TABLE = ROOT.parent / "shared" / "data" / "shake-table"


def run_workflow(name: str, work: Path, cores: int, shake_table: Path | None) -> tuple[Path, float]:
    """The embedded campaign's main job (and the shake table's, if given) under environment
    ``name``: its results folder and wall time."""
    results = work / name / "results"
    results.parent.mkdir(parents=True, exist_ok=True)
    targets = ["all", "shake_table"] if shake_table else ["all"]
    cmd = [str(SNAKEMAKE), *targets, "--cores", str(cores), "--quiet", "--snakefile", str(ROOT / "Snakefile")]
    cmd += ["--directory", str(results.parent), "--config", f"raw_dir={ROOT / 'raw' / 'campaign'}"]
    cmd += [f"results_dir={results}"] + ([f"shake_table_dir={shake_table}"] if shake_table else [])
    env = environment(name, numba_cache=work / name / "numba-cache")
    t0 = time.perf_counter()
    with open(work / name / "snakemake.log", "w") as log:
        run = subprocess.run(cmd, cwd=results.parent, env=env, stdout=log, stderr=subprocess.STDOUT)
    if run.returncode:
        sys.exit(f"the run under {name} failed (exit status {run.returncode}): see {work / name / 'snakemake.log'}")
    return results, time.perf_counter() - t0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/bench"))
    ap.add_argument("--envs", nargs="+", default=list(ENVIRONMENTS), choices=list(ENVIRONMENTS))
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--native-results", type=Path, help="results of `make run` on this checkout, for 'native'")
    ap.add_argument("--workdir", type=Path, help="where the runs go (default: a temporary folder)")
    ap.add_argument(
        "--reuse",
        action="store_true",
        help="compare the finished runs already in --workdir (of this commit) instead of running them again",
    )
    ap.add_argument(
        "--shake-table-dir",
        type=Path,
        default=SHAKE_TABLE if SHAKE_TABLE.is_dir() else None,
        help="the shake-table data, to measure the target shake_table too (default: ../shared/data/shake-table)",
    )
    args = ap.parse_args(argv)
    shake_table = args.shake_table_dir.resolve() if args.shake_table_dir else None
    work = args.workdir or Path(tempfile.mkdtemp(prefix="rocklab-environments-"))
    commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    numbers = {COMMITTED: pages.read_numbers(ROOT / "docs" / "numbers.json")}
    wall = {}
    for name in args.envs:
        if name == "native" and args.native_results:
            results = args.native_results
        elif args.reuse and (work / name / "results" / "docs" / "numbers.json").is_file():
            results = work / name / "results"
        else:
            results, wall[name] = run_workflow(name, work, args.cores, shake_table)
            print(f"{name}: {wall[name]:.0f} s", flush=True)
        numbers[name] = pages.docs_numbers(results)
    # the shake table is volatile in the pages' check (its data are outside the repository), not here
    compared = {s: t for s, t in pages.SECTIONS.items() if s != "shake_table" or shake_table}
    found = moves(numbers, compared)
    out = {
        "commit": commit,
        "cpu": _cpu(),
        "cores": args.cores,
        "environments": {n: ENVIRONMENTS[n] for n in args.envs},
        "wall_s": wall,
        "n_floats": {
            s: sum(isinstance(v, float) for _, v in summaries.leaves(numbers[COMMITTED].get(s))) for s in compared
        },
        "moves": [
            {
                "number": m.key,
                "values": m.values,
                "spread": m.spread,
                "tolerance": m.tolerance._asdict() if m.tolerance else None,
                "headroom": m.headroom,
                "admitted": m.admitted,
            }
            for m in found
        ],
    }
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "environments.json").write_text(json.dumps(out, indent=1) + "\n")
    refused = [m for m in found if not m.admitted]
    print(f"{len(found)} numbers moved between {', '.join(numbers)}; {len(refused)} beyond their tolerance")
    for m in refused:
        print(f"  {m.key}: {m.values} (tolerance {m.tolerance})")
    return 1 if refused else 0


if __name__ == "__main__":
    sys.exit(main())
