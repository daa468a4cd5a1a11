# Stage 3: energy dissipation of every valid test (Sects. 3-4): impacts,
# peaks, experimental and analytic coefficients, per-series statistics.


rule dissipation_tables:
    input:
        qc=res("qc.csv"),
        tests=expand(res("tests", "{test_id}.nc"), test_id=TEST_IDS),
    output:
        tests=res("tests.csv"),
        impacts=res("impacts.csv"),
        e_by_n=res("e_by_n.csv"),
        series=res("series.csv"),
        laws=res("amplitude_laws.csv"),
        effects=res("effects.csv"),
    params:
        schemas=workflow.source_path("../schemas/"),
        n_boot=config.get("statistics", {}).get("n_boot", 4000),
        seed=config.get("statistics", {}).get("seed", 0),
    log:
        res("logs", "dissipation_tables.log"),
    benchmark:
        res("benchmarks", "dissipation_tables.tsv")
    script:
        "../../scripts/dissipation_tables.py"
