# Stage 3: energy dissipation of every valid test (Sects. 3-4) from its stored
# motion: impacts, peaks, experimental and analytic coefficients, per-series
# statistics, Table 3.  A checkpoint: the test drawn in Fig. 20a is chosen
# from its tests.csv.


def report_table(name):
    """A table output, shown in the report with workflow/report/<name>.rst."""
    return report(res(name), caption=f"../report/{name.removesuffix('.csv')}.rst",
                  category="Dissipation tables (Sects. 3-4)")


def dissipation_outputs():
    return [res(name) for name in ("table3.csv", "table3.md", "summary.csv")]


checkpoint dissipation_tables:
    input:
        qc=res("qc.csv"),
        motions=expand(res("motion", "{test_id}.nc"), test_id=TEST_IDS),
    output:
        tests=report_table("tests.csv"),
        impacts=res("impacts.csv"),
        e_by_n=res("e_by_n.csv"),
        series=report_table("series.csv"),
        laws=report_table("amplitude_laws.csv"),
        effects=report_table("effects.csv"),
        table3=report_table("table3.csv"),
        table3_md=res("table3.md"),
        summary=report_table("summary.csv"),
    params:
        schemas=schema_path(""),
        n_boot=config["statistics"]["n_boot"],
        seed=config["statistics"]["seed"],
    log:
        res("logs", "dissipation_tables.log"),
    benchmark:
        res("benchmarks", "dissipation_tables.tsv")
    script:
        "../../scripts/dissipation_tables.py"
