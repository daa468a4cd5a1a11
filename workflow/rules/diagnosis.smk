# Stage 4: model diagnosis (issue 6) - what the base simulation gets wrong,
# which physical extensions the data carry, and the gain on held-out tests:
# one job per series, then the boundary conditions over the series;
# Figs. 14-15 per series; the restitution of the UMinho limestone blocks.

from rocklab.diagnosis.block_tests import TABLES

DIAGNOSIS = config["diagnosis"]
# the limestone tables ship with the library (rocklab.data): found where it is installed
BLOCKS = Path(recorded_path(TABLES))


def diagnosis_outputs():
    return [res("diagnosis.json"), res("figures", "fig14.png"), res("figures", "fig15.png"),
            res("figures", "diagnosis"), res("limestone_diagnosis.json")]


rule diagnose_series:
    input:
        # the series' tests only, each with its own QC verdict: a test edited
        # elsewhere in the campaign does not diagnose this series again
        tests=lambda wildcards: [res("tests", f"{t}.nc") for t in TESTS_BY_SERIES[wildcards.series]],
        # their motion, extracted once by the reduction
        motions=lambda wildcards: [res("motion", f"{t}.nc") for t in TESTS_BY_SERIES[wildcards.series]],
    output:
        res("diagnosis", "{series}.json"),
    wildcard_constraints:
        series="|".join(map(re.escape, TESTS_BY_SERIES)),
    params:
        n_boot=DIAGNOSIS["n_boot"],
        n_history=DIAGNOSIS["n_history"],
        seed=DIAGNOSIS["seed"],
    log:
        res("logs", "diagnosis", "{series}.log"),
    benchmark:
        res("benchmarks", "diagnosis", "{series}.tsv")
    script:
        "../../scripts/diagnose_series.py"


checkpoint diagnosis:
    input:
        expand(res("diagnosis", "{series}.json"), series=sorted(TESTS_BY_SERIES)),
    output:
        json=report(res("diagnosis.json"), caption="../report/diagnosis.rst", category="Model diagnosis"),
        md=res("diagnosis.md"),
    params:
        seed=DIAGNOSIS["seed"],
    log:
        res("logs", "diagnosis.log"),
    benchmark:
        res("benchmarks", "diagnosis.tsv")
    script:
        "../../scripts/diagnosis.py"


def diagnosis_samples(kind):
    """The sample test of every diagnosed series (the tests the figures draw), once the diagnosis has run."""

    def inputs(wildcards):
        with open(checkpoints.diagnosis.get().output.json) as f:
            entries = json.load(f)
        return sorted({res(kind, f"{e['sample_test']}.nc") for e in entries if e["scope"] == "series"})

    return inputs


rule diagnosis_figures:
    input:
        diagnosis=res("diagnosis.json"),
        tests=diagnosis_samples("tests"),
        motions=diagnosis_samples("motion"),
    output:
        fig14=report(res("figures", "fig14.png"), caption="../report/fig14.rst", category="Model diagnosis"),
        fig15=report(res("figures", "fig15.png"), caption="../report/fig15.rst", category="Model diagnosis"),
        series=directory(res("figures", "diagnosis")),
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
        json=res("limestone_diagnosis.json"),
        md=res("limestone_diagnosis.md"),
    params:
        n_boot=DIAGNOSIS["n_boot"],
        seed=DIAGNOSIS["seed"],
    log:
        res("logs", "limestone_diagnosis.log"),
    benchmark:
        res("benchmarks", "limestone_diagnosis.tsv")
    script:
        "../../scripts/limestone_diagnosis.py"
