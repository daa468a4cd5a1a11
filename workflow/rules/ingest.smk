# Stage 1: each test's raw record to its wall motion (reader, channel health,
# four-DOF kinematics, validity by the lab's rules), one netCDF per test, and
# the motion extracted from it (release, impacts, peaks), stored once for the
# dissipation tables and the diagnosis; and per job the attributes of its tests'
# QC rows (results/reduction/<job>.json), the input that stands for the job's
# files downstream (reduced_inputs in common.smk).
#
# Whole specimens packed into jobs of at most reduction.max_tests_per_job
# tests (a larger specimen cut into parts of its own), and one job for the
# tests refused at the door, not one per test or per series: a job spends
# longer starting Python and importing the library (about 2 s of CPU) than
# reducing thirty tests.

for _k, (_job, _ids) in enumerate(REDUCTION_JOBS.items()):

    rule:
        name:
            # a rule name is an identifier; the index keeps "1a-b" and "1a_b" apart
            f"reduce_{_k:03d}_" + re.sub(r"\W", "_", _job)
        priority: PRIORITY["campaign_chain"]
        output:
            tests=[res("tests", f"{t}.nc") for t in _ids],
            motion=[res("motion", f"{t}.nc") for t in _ids],
            rows=reduction_rows(_job),
        params:
            tests=lambda wildcards, ids=_ids: {t: test_params(t) for t in ids},
            raw_dir=config["raw_dir"],
            options={"channels": config["channels"], "validity": config["validity"]},
        log:
            res("logs", "reduce", f"{_job}.log"),
        benchmark:
            res("benchmarks", "reduce", f"{_job}.tsv")
        script:
            "../../scripts/reduce_tests.py"
