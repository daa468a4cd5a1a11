# Stage 4: model diagnosis (issue 6) - what the base simulation gets wrong,
# which physical extension the data carry, and the gain on held-out tests.


rule diagnosis:
    input:
        qc=res("qc.csv"),
        tests=expand(res("tests", "{test_id}.nc"), test_id=TEST_IDS),
    output:
        json=res("diagnosis.json"),
        md=res("diagnosis.md"),
    params:
        n_boot=config.get("diagnosis", {}).get("n_boot", 40),
        n_history=config.get("diagnosis", {}).get("n_history", 2),
    log:
        res("logs", "diagnosis.log"),
    benchmark:
        res("benchmarks", "diagnosis.tsv")
    script:
        "../../scripts/diagnosis.py"
