"""Benchmark: the start-up of the workflow's jobs, the imports of each script.

    python bench/startup.py --out DIR [--repeat 3] [--baseline CHECKOUT]

Every job of the workflow is a new Python process that Snakemake's
``script:`` directive starts: it pays the imports of its script before any
work.  For each script of ``scripts/`` that ``snakemake all`` runs, its
module-level import statements run in a Python process of their own (the
sources of this checkout first on the path), and the CPU time of that
process (user + system, the kernel's count: robust on a shared machine) is
recorded, the least of ``--repeat`` runs.  The sum weighted by the jobs
each script has in ``snakemake all`` (:data:`JOBS`) is the start-up CPU of
the main job; the imports of Snakemake's preamble (the same in every job),
those of the Snakefile and its rules (Snakemake's own process, once, before
the first job) and a bare interpreter are measured apart.  What a job
imports later, in the functions it calls (scipy in the reduction, say), is
not counted: the job pays it all the same.

With ``--baseline``, a checkout (or an export of its ``src``, ``scripts``,
``Snakefile`` and ``workflow``) of another commit is measured too, in the same sitting, run
for run alternated with this one, and the ratio of the weighted sums is
reported.  Writes ``<out>/startup.json``.
"""

from __future__ import annotations

import argparse
import ast
import json
import os
import re
import resource
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: Jobs of each script in ``snakemake all`` on the embedded campaign: the
#: reduction packed into 3 jobs, 2 diagnosis series kinds, 2 batches of
#: paper maps and 2 of calibrated maps, 7 report pages.
JOBS = {
    "reduce_tests.py": 3,
    "qc_table.py": 1,
    "dissipation_tables.py": 1,
    "kinematics_figures.py": 1,
    "dissipation_figures.py": 1,
    "diagnose_series.py": 2,
    "diagnosis.py": 1,
    "diagnosis_figures.py": 1,
    "limestone_diagnosis.py": 1,
    "campaign_effects.py": 1,
    "overturning_maps.py": 4,
    "map_summary.py": 1,
    "map_figures.py": 1,
    "map_calibrated.py": 1,
    "report_pages.py": 7,
    "docs_pages.py": 1,
}
#: What Snakemake's preamble imports in every ``script:`` job, its unpickled
#: ``snakemake`` object aside.
PREAMBLE = "import pickle\nfrom snakemake.logging import logger\nfrom snakemake.iocontainers import Snakemake"


def import_lines(script: Path) -> str:
    """The module-level import statements of a script, as source."""
    source = script.read_text()
    tree = ast.parse(source, filename=str(script))
    imports = [n for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom))]
    return "\n".join(ast.get_source_segment(source, n) for n in imports)


def snakefile_imports(root: Path) -> str:
    """The imports of rocklab in the Snakefile and its rules (``workflow/rules/*.smk``), as source."""
    files = [root / "Snakefile", *sorted((root / "workflow" / "rules").glob("*.smk"))]
    lines = (line for f in files for line in f.read_text().splitlines())
    return "\n".join(line for line in lines if re.match(r"(from|import) rocklab\b", line))


def import_cpu(code: str, src: Path) -> float:
    """CPU time [s] (user + system) of a Python process running ``code`` with ``src`` first on the path."""
    env = {**os.environ, "PYTHONPATH": str(src)}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([sys.executable, "-c", code], check=True, env=env)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def measure(checkouts: dict[str, Path], repeat: int) -> dict:
    """Least import CPU [s] of each script in each checkout, runs alternated between checkouts."""
    codes = {
        name: {script: import_lines(root / "scripts" / script) for script in JOBS} for name, root in checkouts.items()
    }
    for name, code in codes.items():
        code["(preamble)"] = PREAMBLE
        code["(Snakefile)"] = snakefile_imports(checkouts[name])
        code["(python)"] = "pass"
    best = {name: dict.fromkeys(codes[name], float("inf")) for name in checkouts}
    for _ in range(repeat):
        for script in codes[next(iter(checkouts))]:
            for name, root in checkouts.items():
                best[name][script] = min(best[name][script], import_cpu(codes[name][script], root / "src"))
    return best


def summary(best: dict[str, float]) -> dict:
    """Per script and weighted by its jobs in ``snakemake all``: import CPU [s]."""
    scripts = {s: {"jobs": n, "import_cpu_s": best[s], "jobs_cpu_s": n * best[s]} for s, n in JOBS.items()}
    n_jobs = sum(JOBS.values())
    return {
        "scripts": scripts,
        "n_jobs": n_jobs,
        "weighted_import_cpu_s": sum(s["jobs_cpu_s"] for s in scripts.values()),
        "preamble_cpu_s": best["(preamble)"],
        "snakefile_cpu_s": best["(Snakefile)"],
        "python_cpu_s": best["(python)"],
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/bench"))
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--baseline", type=Path, default=None, help="another checkout, measured in the same sitting")
    args = ap.parse_args(argv)
    checkouts = {"this": ROOT} | ({"baseline": args.baseline.resolve()} if args.baseline else {})
    best = measure(checkouts, args.repeat)
    out = {"repeat": args.repeat, **summary(best["this"])}
    if args.baseline:
        out["baseline"] = {"checkout": str(args.baseline), **summary(best["baseline"])}
        out["weighted_over_baseline"] = out["weighted_import_cpu_s"] / out["baseline"]["weighted_import_cpu_s"]
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "startup.json").write_text(json.dumps(out, indent=1) + "\n")
    base = out.get("baseline", {}).get("scripts", {})
    print(f"{'script':24s} jobs  import CPU [s]" + ("  baseline [s]" if base else ""))
    for script, s in out["scripts"].items():
        line = f"{script:24s} {s['jobs']:4d}  {s['import_cpu_s']:14.2f}"
        print(line + (f"  {base[script]['import_cpu_s']:12.2f}" if base else ""))
    line = f"{'weighted sum':24s} {out['n_jobs']:4d}  {out['weighted_import_cpu_s']:14.2f}"
    print(line + (f"  {out['baseline']['weighted_import_cpu_s']:12.2f}" if base else ""))
    for key, what in (("preamble_cpu_s", "Snakemake's preamble, per job"), ("snakefile_cpu_s", "the Snakefile's")):
        line = f"{what:30s} {out[key]:.2f} s"
        print(line + (f"  (baseline {out['baseline'][key]:.2f} s)" if base else ""))
    print(f"{'bare python':30s} {out['python_cpu_s']:.2f} s")


if __name__ == "__main__":
    main()
