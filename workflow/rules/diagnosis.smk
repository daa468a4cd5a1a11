# Stage 4: model diagnosis (issue 6) - what the base simulation gets wrong,
# which physical extensions the data carry, and the gain on held-out tests:
# jobs of whole series writing each series' diagnosis, then the
# boundary conditions summed up over the series;
# Figs. 14-15 per series; the restitution of the UMinho limestone blocks.

# rocklab.data, not the diagnosis package: Snakemake parses this file at every start
from rocklab.data import LIMESTONE

DIAGNOSIS = config["diagnosis"]
# the limestone tables ship with the library (rocklab.data): found where it is installed
BLOCKS = Path(recorded_path(LIMESTONE))


CAMPAIGN_EFFECTS_OUTPUTS = [res("report", "campaign_effects.html"), res("figures", "campaign_covariates.png")]
DIAGNOSIS_OUTPUTS = [
    res("diagnosis.json"),
    res("report", "diagnosis.html"),
    res("figures", "fig14.png"),
    res("figures", "fig15.png"),
    res("figures", "diagnosis"),
] + CAMPAIGN_EFFECTS_OUTPUTS
LIMESTONE_OUTPUTS = [res("limestone_diagnosis.json"), res("report", "limestone_diagnosis.html")]


# Whole series packed into jobs of at most diagnosis.max_tests_per_job tests
# (DIAGNOSIS_JOBS, common.smk): a job spends 2 s starting Python and importing
# the library, as long as diagnosing a small series, so 26 per-series jobs
# spent some 50 s of the embedded campaign's diagnosis on start-up; a large
# series is a job of its own, so that a large campaign's series run side by
# side (one job per boundary condition held the two-sided series, most of
# the diagnosis, on one core).  It writes the entries of its series, in the
# order of tests.csv, to one file.
rule diagnose_series:
    input:
        lambda wildcards: reduced_inputs([t for s in DIAGNOSIS_JOBS[wildcards.job] for t in TESTS_BY_SERIES[s]]),
    output:
        res("diagnosis", "{job}.json"),
    log:
        res("logs", "diagnosis", "{job}.log"),
    benchmark:
        res("benchmarks", "diagnosis", "{job}.tsv")
    wildcard_constraints:
        job=one_of(DIAGNOSIS_JOBS),
    priority: lambda wildcards: diagnosis_priority(wildcards.job)
    params:
        series=lambda wildcards: DIAGNOSIS_JOBS[wildcards.job],
        # the tests of each series, each with its own QC verdict, read
        # series by series: the job holds one series' tests at a time
        tests=lambda wildcards: {s: [test_file(t) for t in TESTS_BY_SERIES[s]] for s in DIAGNOSIS_JOBS[wildcards.job]},
        n_boot=DIAGNOSIS["n_boot"],
        n_history=DIAGNOSIS["n_history"],
        seed=DIAGNOSIS["seed"],
    script:
        "../../scripts/diagnose_series.py"


checkpoint diagnosis:
    input:
        expand(rules.diagnose_series.output, job=DIAGNOSIS_JOBS),
    output:
        json=report_item(
            res("diagnosis.json"), "diagnosis_json", "diagnosis", "diagnosis.json, for programs", "Summary"
        ),
        md=res("diagnosis.md"),
        docs_summary=res("summaries", "diagnosis.json"),
    log:
        res("logs", "diagnosis.log"),
    benchmark:
        res("benchmarks", "diagnosis.tsv")
    priority: PRIORITY["campaign_chain"]
    params:
        walls=WALL_OF_SERIES,
        thickness=WALL_THICKNESS,
    script:
        "../../scripts/diagnosis.py"


# The report's page of diagnosis.md.
rule diagnosis_pages:
    input:
        diagnosis=res("diagnosis.md"),
    output:
        diagnosis=report_page("diagnosis", "diagnosis", "diagnosis.md, every series and boundary", "Summary"),
    log:
        res("logs", "report_pages", "diagnosis.log"),
    benchmark:
        res("benchmarks", "report_pages", "diagnosis.tsv")
    script:
        "../../scripts/report_pages.py"


# Each series' sample test, and every test of a series with a form discovered
# beyond the catalogue, are read by the job: the folders of their reduction
# jobs are its inputs, the files its params (Snakemake would stat thousands of
# files at each scheduling round of a large campaign).
rule diagnosis_figures:
    input:
        diagnosis=rules.diagnosis.output.json,
        tests=reduced_inputs(TEST_IDS),
    output:
        fig14=report_figure("14", "diagnosis", "two-sided, models against the test", "Summary"),
        fig15=report_figure("15", "diagnosis", "one-sided, models against the test", "Summary"),
        # every series' figure its own report item, labelled by its series
        series=report_item(
            directory(res("figures", "diagnosis")),
            "diagnosis_series",
            "diagnosis",
            {"series": "{series}"},
            "Per series",
            patterns=["{series}.png"],
        ),
    log:
        res("logs", "diagnosis_figures.log"),
    benchmark:
        res("benchmarks", "diagnosis_figures.tsv")
    priority: PRIORITY["long_leaves"]
    params:
        tests={s: [test_file(t) for t in ids] for s, ids in TESTS_BY_SERIES.items()},
    script:
        "../../scripts/diagnosis_figures.py"


rule limestone_diagnosis:
    input:
        events=str(BLOCKS / "limestone-rocking-events.csv"),
    output:
        json=report_item(
            res("limestone_diagnosis.json"), "limestone_json", "limestone", "limestone_diagnosis.json, for programs"
        ),
        md=res("limestone_diagnosis.md"),
        figure=report_item(
            res("figures", "limestone_family.png"),
            "limestone_family",
            "limestone",
            "the impact law across slendernesses: data, Housner, listed causes, families",
        ),
        docs_summary=res("summaries", "limestone.json"),
    log:
        res("logs", "limestone_diagnosis.log"),
    benchmark:
        res("benchmarks", "limestone_diagnosis.tsv")
    params:
        n_boot=DIAGNOSIS["n_boot"],
        seed=DIAGNOSIS["seed"],
    script:
        "../../scripts/limestone_diagnosis.py"


# The report's page of limestone_diagnosis.md.
rule limestone_pages:
    input:
        limestone_diagnosis=res("limestone_diagnosis.md"),
    output:
        limestone_diagnosis=report_page("limestone_diagnosis", "limestone", "limestone_diagnosis.md, per block group"),
    log:
        res("logs", "report_pages", "limestone.log"),
    benchmark:
        res("benchmarks", "report_pages", "limestone.tsv")
    script:
        "../../scripts/report_pages.py"


# The campaign level (issue 12): every parameter of the series against the
# specimen and test covariates, the paper's campaign-wide statements tested;
# from the tables, not the tests' files (a second or two).
rule campaign_effects:
    input:
        tests=rules.dissipation_tables.output.tests,
        qc=rules.qc_table.output.qc,
        diagnosis=rules.diagnosis.output.json,
    output:
        table=res("diagnosis", "campaign_effects.csv"),
        figure=report_item(
            res("figures", "campaign_covariates.png"),
            "campaign_covariates",
            "diagnosis",
            "the parameters against h/b and contact depth",
            "Summary",
        ),
        docs_summary=res("summaries", "campaign_level.json"),
    log:
        res("logs", "campaign_effects.log"),
    benchmark:
        res("benchmarks", "campaign_effects.tsv")
    params:
        walls=WALL_OF_SPECIMEN,
        schema=schema_path("campaign_effects.schema.yaml"),
    script:
        "../../scripts/campaign_effects.py"


# The report's page of campaign_effects.csv: sortable, filterable, columns described.
rule campaign_effects_pages:
    input:
        campaign_effects=res("diagnosis", "campaign_effects.csv"),
    output:
        campaign_effects=report_page(
            "campaign_effects",
            "diagnosis",
            "campaign_effects.csv, the paper's campaign-wide statements tested",
            "Summary",
        ),
    log:
        res("logs", "report_pages", "campaign_effects.log"),
    benchmark:
        res("benchmarks", "report_pages", "campaign_effects.tsv")
    params:
        schemas={"campaign_effects": schema_path("campaign_effects.schema.yaml")},
    script:
        "../../scripts/report_pages.py"
