# Stage 1: each test's raw record to its wall motion (reader, channel health,
# four-DOF kinematics, validity by the lab's rules), one netCDF per test, and
# the motion extracted from it (release, impacts, peaks), stored once for the
# dissipation tables and the diagnosis.
#
# One job per series (and one for the tests refused at the door), not per test: a job spends ten times longer starting
# Python and importing the library (1.0 s) than reducing one test (0.1 s).

for _k, (_series, _ids) in enumerate(REDUCTION_GROUPS.items()):

    rule:
        name:
            # a rule name is an identifier; the index keeps "1a-2s" and "1a_2s" apart
            f"reduce_{_k:03d}_" + re.sub(r"\W", "_", _series)
        input:
            lambda wildcards, ids=_ids: record_inputs(ids),
        output:
            tests=[res("tests", f"{t}.nc") for t in _ids],
            motion=[res("motion", f"{t}.nc") for t in _ids],
        params:
            tests=lambda wildcards, ids=_ids: {t: test_params(t) for t in ids},
            raw_dir=config["raw_dir"],
            options={"channels": config["channels"], "validity": config["validity"]},
        log:
            res("logs", "reduce", f"{_series}.log"),
        benchmark:
            res("benchmarks", "reduce", f"{_series}.tsv")
        script:
            "../../scripts/reduce_tests.py"
