# Stage 4: model diagnosis (issue 6) - what the base simulation gets wrong,
# which physical extensions the data carry, and the gain on held-out tests:
# one job per boundary condition writing each series' diagnosis, then the
# boundary conditions summed up over the series;
# Figs. 14-15 per series; the restitution of the UMinho limestone blocks.

# rocklab.data, not the diagnosis package: Snakemake parses this file at every start
from rocklab.data import LIMESTONE

DIAGNOSIS = config["diagnosis"]
# the limestone tables ship with the library (rocklab.data): found where it is installed
BLOCKS = Path(recorded_path(LIMESTONE))


def diagnosis_outputs():
    return [res("diagnosis.json"), res("report", "diagnosis.html"), res("figures", "fig14.png"),
            res("figures", "fig15.png"), res("figures", "diagnosis")] + campaign_effects_outputs()


def campaign_effects_outputs():
    return [res("report", "campaign_effects.html"), res("figures", "campaign_covariates.png")]


def limestone_outputs():
    return [res("limestone_diagnosis.json"), res("report", "limestone_diagnosis.html")]


#: The series of each boundary condition, in the order of tests.csv (one diagnosis job each).
#: (the tests refused at the door are in no series: they have no diagnosis)
SERIES_BY_BOUNDARY = {}
for _series, _ids in TESTS_BY_SERIES.items():
    SERIES_BY_BOUNDARY.setdefault(CAMPAIGN.test_row(_ids[0]).boundary, []).append(_series)

# One job per boundary condition, not per series: a job spends 2 s starting
# Python and importing the library, as long as diagnosing a small series, so
# 26 per-series jobs spent some 50 s of the embedded campaign's diagnosis on
# start-up.  Each still writes one file per series, as the checkpoint reads.
for _boundary, _series in SERIES_BY_BOUNDARY.items():
    _ids = [t for s in _series for t in TESTS_BY_SERIES[s]]

    rule:
        name:
            "diagnose_series_" + re.sub(r"\W", "_", _boundary)
        priority: PRIORITY["campaign_chain"]
        input:
            reduced_inputs(_ids),
        output:
            [res("diagnosis", f"{s}.json") for s in _series],
        params:
            series=list(_series),
            # the tests of each series, each with its own QC verdict, read
            # series by series: the job holds one series' tests at a time
            tests={s: [res("tests", f"{t}.nc") for t in TESTS_BY_SERIES[s]] for s in _series},
            # their motion, extracted once by the reduction
            motions=[res("motion", f"{t}.nc") for t in _ids],
            n_boot=DIAGNOSIS["n_boot"],
            n_history=DIAGNOSIS["n_history"],
            seed=DIAGNOSIS["seed"],
        log:
            res("logs", "diagnosis", f"{_boundary}.log"),
        benchmark:
            res("benchmarks", "diagnosis", f"{_boundary}.tsv")
        script:
            "../../scripts/diagnose_series.py"


checkpoint diagnosis:
    priority: PRIORITY["campaign_chain"]
    input:
        expand(res("diagnosis", "{series}.json"), series=sorted(TESTS_BY_SERIES)),
    output:
        json=report_item(res("diagnosis.json"), "diagnosis_json", "diagnosis", "diagnosis.json, for programs", "Summary"),
        md=res("diagnosis.md"),
        docs_summary=res("summaries", "diagnosis.json"),
    params:
        seed=DIAGNOSIS["seed"],
    log:
        res("logs", "diagnosis.log"),
    benchmark:
        res("benchmarks", "diagnosis.tsv")
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


def diagnosis_samples(kind):
    """The sample test of every diagnosed series (the tests the figures draw), once the diagnosis has run,
    and every test of a series with a form discovered beyond the catalogue (drawn against them all)."""

    def inputs(wildcards):
        # here, not at the top: the diagnosis package is read once the checkpoint has run, not at every start
        from rocklab.diagnosis.result import CampaignDiagnosis

        diagnosis = CampaignDiagnosis.from_json(checkpoints.diagnosis.get().output.json)
        ids = diagnosis.sample_tests
        ids |= {t for e in diagnosis.series if e.discovered for t in TESTS_BY_SERIES[e.key]}
        return sorted(res(kind, f"{t}.nc") for t in ids)

    return inputs


rule diagnosis_figures:
    priority: PRIORITY["longest_figures"]
    input:
        diagnosis=res("diagnosis.json"),
        tests=diagnosis_samples("tests"),
        motions=diagnosis_samples("motion"),
    output:
        fig14=report_figure("14", "diagnosis", "two-sided, models against the test", "Summary"),
        fig15=report_figure("15", "diagnosis", "one-sided, models against the test", "Summary"),
        # every series' figure its own report item, labelled by its series
        series=report_item(directory(res("figures", "diagnosis")), "diagnosis_series", "diagnosis",
                           {"series": "{series}"}, "Per series", patterns=["{series}.png"]),
    log:
        res("logs", "diagnosis_figures.log"),
    benchmark:
        res("benchmarks", "diagnosis_figures.tsv")
    script:
        "../../scripts/diagnosis_figures.py"


rule limestone_diagnosis:
    input:
        events=str(BLOCKS / "limestone-rocking-events.csv"),
    output:
        json=report_item(res("limestone_diagnosis.json"), "limestone_json", "limestone",
                         "limestone_diagnosis.json, for programs"),
        md=res("limestone_diagnosis.md"),
        figure=report_item(res("figures", "limestone_family.png"), "limestone_family", "limestone",
                           "the impact law across slendernesses: data, Housner, listed causes, families"),
        docs_summary=res("summaries", "limestone.json"),
    params:
        n_boot=DIAGNOSIS["n_boot"],
        seed=DIAGNOSIS["seed"],
    log:
        res("logs", "limestone_diagnosis.log"),
    benchmark:
        res("benchmarks", "limestone_diagnosis.tsv")
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
        tests=res("tests.csv"),
        qc=res("qc.csv"),
        diagnosis=res("diagnosis.json"),
    output:
        table=res("diagnosis", "campaign_effects.csv"),
        figure=report_item(res("figures", "campaign_covariates.png"), "campaign_covariates", "diagnosis",
                           "the parameters against h/b and contact depth", "Summary"),
        docs_summary=res("summaries", "campaign_level.json"),
    params:
        margin=DIAGNOSIS["campaign_margin"],
        schema=schema_path("campaign_effects.schema.yaml"),
    log:
        res("logs", "campaign_effects.log"),
    benchmark:
        res("benchmarks", "campaign_effects.tsv")
    script:
        "../../scripts/campaign_effects.py"


# The report's page of campaign_effects.csv: sortable, filterable, columns described.
rule campaign_effects_pages:
    input:
        campaign_effects=res("diagnosis", "campaign_effects.csv"),
    output:
        campaign_effects=report_page("campaign_effects", "diagnosis",
                                     "campaign_effects.csv, the paper's campaign-wide statements tested", "Summary"),
    params:
        schemas={"campaign_effects": schema_path("campaign_effects.schema.yaml")},
    log:
        res("logs", "report_pages", "campaign_effects.log"),
    benchmark:
        res("benchmarks", "report_pages", "campaign_effects.tsv")
    script:
        "../../scripts/report_pages.py"
