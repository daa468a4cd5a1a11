# Stage 2: the QC table of the whole campaign, one row per row of tests.csv.
# A checkpoint: the test drawn in Figs. 6, 8 and 9 is chosen from its verdicts.


QC_OUTPUTS = [res("qc.csv"), res("kinematics.csv"), res("report", "qc.html"), res("report", "kinematics.html")]


checkpoint qc_table:
    input:
        rows=reduced_rows(TEST_IDS),
        log=str(RAW / "tests.csv"),
    output:
        qc=res("qc.csv"),
        kinematics=res("kinematics.csv"),
        docs_summary=res("summaries", "quality_control.json"),
    log:
        res("logs", "qc_table.log"),
    benchmark:
        res("benchmarks", "qc_table.tsv")
    params:
        raw_dir=lambda wildcards, input: str(Path(input.log).parent),
        schema=schema_path("qc.schema.yaml"),
    script:
        "../../scripts/qc_table.py"


# The report's pages of the two tables: sortable, filterable, columns described.
rule qc_pages:
    input:
        qc=res("qc.csv"),
        kinematics=res("kinematics.csv"),
    output:
        qc=report_page("qc", "qc", "qc.csv, the verdict of every test"),
        kinematics=report_page("kinematics", "kinematics", "kinematics.csv, peaks and the Eq. 8 check"),
    log:
        res("logs", "report_pages", "qc.log"),
    benchmark:
        res("benchmarks", "report_pages", "qc.tsv")
    params:
        schemas={"qc": schema_path("qc.schema.yaml")},
    script:
        "../../scripts/report_pages.py"
