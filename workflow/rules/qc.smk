# Stage 2: the QC table of the whole campaign, one row per row of tests.csv.
# A checkpoint: the test drawn in Figs. 6, 8 and 9 is chosen from its verdicts.


checkpoint qc_table:
    input:
        tests=expand(res("tests", "{test_id}.nc"), test_id=TEST_IDS),
        log=str(RAW / "tests.csv"),
    output:
        qc=res("qc.csv"),
        kinematics=res("kinematics.csv"),
    params:
        raw_dir=config["raw_dir"],
        schema=schema_path("qc.schema.yaml"),
    log:
        res("logs", "qc_table.log"),
    benchmark:
        res("benchmarks", "qc_table.tsv")
    script:
        "../../scripts/qc_table.py"
