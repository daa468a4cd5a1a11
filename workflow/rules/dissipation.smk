# Stage 3: energy dissipation of every valid test (Sects. 3-4) from its stored
# motion: impacts, peaks, experimental and analytic coefficients, per-series
# statistics, Table 3.  A checkpoint: the test drawn in Fig. 20a is chosen
# from its tests.csv.

#: The tables of the report (results/report/<name>.html): what each holds, its schema if any.
DISSIPATION_PAGES = {
    "tests": ("tests.csv, every valid test", "tests.schema.yaml"),
    "series": ("series.csv, every series", "series.schema.yaml"),
    "table3": ("table3.csv, Table 3", "table3.schema.yaml"),
    "summary": ("summary.csv, by boundary condition", "summary.schema.yaml"),
    "amplitude_laws": ("amplitude_laws.csv, Eqs. 15 and 17", None),
    "effects": ("effects.csv, the factors between series", None),
}


DISSIPATION_OUTPUTS = [res(name) for name in ("table3.csv", "table3.md", "summary.csv")] + [
    res("report", f"{name}.html") for name in DISSIPATION_PAGES
]


checkpoint dissipation_tables:
    input:
        qc=rules.qc_table.output.qc,
        # each reduction job's tests analysed as it extracted their motions
        analysed=expand(rules.reduce.output.dissipation, job=REDUCTION_JOBS),
    output:
        tests=res("tests.csv"),
        impacts=res("impacts.csv"),
        e_by_n=res("e_by_n.csv"),
        series=res("series.csv"),
        laws=res("amplitude_laws.csv"),
        effects=res("effects.csv"),
        table3=res("table3.csv"),
        table3_md=res("table3.md"),
        summary=res("summary.csv"),
        docs_summary=res("summaries", "dissipation.json"),
    log:
        res("logs", "dissipation_tables.log"),
    benchmark:
        res("benchmarks", "dissipation_tables.tsv")
    params:
        test_ids=TEST_IDS,
        schemas=schema_path(""),
        n_boot=config["statistics"]["n_boot"],
        seed=config["statistics"]["seed"],
        walls=WALL_OF_SPECIMEN,
    script:
        "../../scripts/dissipation_tables.py"


# The report's pages of the tables: sortable, filterable, columns described.
rule dissipation_pages:
    input:
        **{name: res(f"{name}.csv") for name in DISSIPATION_PAGES},
    output:
        **{name: report_page(name, "dissipation", what, "Tables") for name, (what, _) in DISSIPATION_PAGES.items()},
    log:
        res("logs", "report_pages", "dissipation.log"),
    benchmark:
        res("benchmarks", "report_pages", "dissipation.tsv")
    params:
        schemas={name: schema_path(schema) for name, (_, schema) in DISSIPATION_PAGES.items() if schema},
    script:
        "../../scripts/report_pages.py"
