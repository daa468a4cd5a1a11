# Stage 1: each test's raw record to its wall motion (reader, channel health,
# four-DOF kinematics, validity by the lab's rules), one netCDF per test.


rule reduce_test:
    input:
        record_input,
    output:
        res("tests", "{test_id}.nc"),
    params:
        test=test_params,
        raw_dir=config["raw_dir"],
        options={"channels": config.get("channels", {}), "validity": config.get("validity", {})},
    log:
        res("logs", "reduce_test", "{test_id}.log"),
    benchmark:
        res("benchmarks", "reduce_test", "{test_id}.tsv")
    script:
        "../../scripts/reduce_test.py"
