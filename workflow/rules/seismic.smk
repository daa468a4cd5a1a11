# Stage: overturning maps of Sect. 5 (Figs. 21-23): the maps of each record,
# then the indices of Fig. 22 with the reductions between models, and the
# figures; the calibrated walls of the campaign's diagnosis beside them.
from rocklab.seismic.accelerograms import read_manifest
from rocklab.seismic.walls import MODELS
from rocklab.config import calibrated_map_n

MAPS = config["maps"]
CALIBRATED_N = calibrated_map_n(MAPS["n"], MAPS["calibrated_n"])
MANIFEST = read_manifest()
MAP_RECORDS = MAPS["records"] or list(MANIFEST.record)
MAP_FIG_RECORD = MAPS["figure_record"]
if MAP_FIG_RECORD not in MAP_RECORDS:
    MAP_FIG_RECORD = MAP_RECORDS[0]
# The wall and the grid of every map, paper's or calibrated.
MAP_PARAMS = {
    "n": MAPS["n"],
    "lo": MAPS["lo"],
    "hi": MAPS["hi"],
    "alpha": MAPS["alpha"],
    "R": MAPS["R"],
    "form": MAPS["form"],
    "eq17": MAPS["eq17"],
    "polarity": MAPS["polarity"],
    "chunks": MAPS["chunks"],
}


MAP_OUTPUTS = (
    [res("maps", name) for name in ("summary.csv", "reductions.csv", "comparison.csv")]
    + [res("figures", f"fig{n}.png") for n in (21, 22, 23)]
    + [res("report", f"{name}.html") for name in ("map_summary", "map_reductions", "map_comparison")]
)
CALIBRATED_OUTPUTS = [res("maps", "calibrated.csv"), res("report", "map_calibrated.html")]

# The maps of several records per job (maps.records_per_job): a job's
# start-up (imports, the numba kernel's cache) is 1.5-2 s, as much as the
# maps of a short record, and 16 records x 2 rules as separate jobs spent
# about a fifth of the maps' time starting.
#: The records of each map job, by its number (from 1).
MAP_BATCHES = {
    str(k): MAP_RECORDS[i : i + MAPS["records_per_job"]]
    for k, i in enumerate(range(0, len(MAP_RECORDS), MAPS["records_per_job"]), 1)
}
#: The map job of each record.
MAP_BATCH = {r: k for k, batch in MAP_BATCHES.items() for r in batch}


# A job's declared output is the folder of the maps it writes (a rule's
# outputs are patterns of its wildcards, and a job holds as many records as
# maps.records_per_job): the rules that read maps take the folders as
# input, the maps' paths as params (map_path).  Its records are params too:
# another record in the batch recomputes it (not under --rerun-triggers
# mtime alone).
rule overturning_maps:
    input:
        records=lambda wildcards: [record_path(r) for r in MAP_BATCHES[wildcards.batch]],
    output:
        directory(res("maps", "records-{batch}")),
    log:
        res("logs", "maps", "batch{batch}.log"),
    benchmark:
        res("benchmarks", "maps", "batch{batch}.tsv")
    wildcard_constraints:
        batch=one_of(MAP_BATCHES),
    priority: PRIORITY["maps"]
    threads: MAPS["threads"]
    resources:
        mem_mb=1000,
        runtime=lambda wildcards: 20 * len(MAP_BATCHES[wildcards.batch]),
        cpus_per_task=MAPS["threads"],
    params:
        **MAP_PARAMS,
        records=lambda wildcards: MAP_BATCHES[wildcards.batch],
        # each record's own log; the job's (log:) names them
        logs=lambda wildcards: [res("logs", "maps", f"{r}.log") for r in MAP_BATCHES[wildcards.batch]],
        models=list(MODELS),
    script:
        "../../scripts/overturning_maps.py"


# The calibrated walls (rocklab.seismic.calibrated) are named by the
# campaign's diagnosis, a checkpoint: the maps of a batch's records go to
# the job's folder (calibrated_map_folder).
rule calibrated_maps:
    input:
        records=lambda wildcards: [record_path(r) for r in MAP_BATCHES[wildcards.batch]],
        diagnosis=rules.diagnosis.output.json,
    output:
        directory(res("maps", "calibrated", "records-{batch}")),
    log:
        res("logs", "maps_calibrated", "batch{batch}.log"),
    benchmark:
        res("benchmarks", "maps_calibrated", "batch{batch}.tsv")
    wildcard_constraints:
        batch=one_of(MAP_BATCHES),
    priority: PRIORITY["maps"]
    threads: MAPS["threads"]
    resources:
        mem_mb=1000,
        runtime=lambda wildcards: 30 * len(MAP_BATCHES[wildcards.batch]),
        cpus_per_task=MAPS["threads"],
    params:
        **{**MAP_PARAMS, "n": CALIBRATED_N},
        records=lambda wildcards: MAP_BATCHES[wildcards.batch],
        logs=lambda wildcards: [res("logs", "maps_calibrated", f"{r}.log") for r in MAP_BATCHES[wildcards.batch]],
    script:
        "../../scripts/overturning_maps.py"


rule map_summary:
    input:
        expand(rules.overturning_maps.output, batch=MAP_BATCHES),
    output:
        summary=res("maps", "summary.csv"),
        reductions=res("maps", "reductions.csv"),
        comparison=res("maps", "comparison.csv"),
        docs_summary=res("summaries", "maps.json"),
    log:
        res("logs", "map_summary.log"),
    benchmark:
        res("benchmarks", "map_summary.tsv")
    params:
        maps=[map_path(r, m) for r in MAP_RECORDS for m in MODELS],
        summary_schema=schema_path("map_summary.schema.yaml"),
        reductions_schema=schema_path("map_reductions.schema.yaml"),
        comparison_schema=schema_path("map_comparison.schema.yaml"),
    script:
        "../../scripts/map_summary.py"


rule map_figures:
    input:
        summary=rules.map_summary.output.summary,
        maps=expand(rules.overturning_maps.output, batch=MAP_BATCH[MAP_FIG_RECORD]),
    output:
        fig21=report_figure("21", "maps", "two-sided maps"),
        fig22=report_figure("22", "maps", "indices record by record"),
        fig23=report_figure("23", "maps", "one-sided maps"),
    log:
        res("logs", "map_figures.log"),
    benchmark:
        res("benchmarks", "map_figures.tsv")
    params:
        two_sided=[map_path(MAP_FIG_RECORD, m) for m in ("2s-housner", "2s-0.95")],
        one_sided=[map_path(MAP_FIG_RECORD, m) for m in ("1s-zero", "1s-1.05", "1s-eq17")],
    script:
        "../../scripts/map_figures.py"


# The report's pages of the three tables: sortable, filterable, columns described.
rule map_pages:
    input:
        map_summary=rules.map_summary.output.summary,
        map_reductions=rules.map_summary.output.reductions,
        map_comparison=rules.map_summary.output.comparison,
    output:
        map_summary=report_page("map_summary", "maps", "maps/summary.csv, the indices of every map"),
        map_reductions=report_page("map_reductions", "maps", "maps/reductions.csv, from one model to another"),
        map_comparison=report_page(
            "map_comparison", "maps", "maps/comparison.csv, record by record against Table 4 and the paper"
        ),
    log:
        res("logs", "report_pages", "maps.log"),
    benchmark:
        res("benchmarks", "report_pages", "maps.tsv")
    params:
        schemas={
            "map_summary": schema_path("map_summary.schema.yaml"),
            "map_reductions": schema_path("map_reductions.schema.yaml"),
            "map_comparison": schema_path("map_comparison.schema.yaml"),
        },
    script:
        "../../scripts/report_pages.py"


# The lab's findings on the maps (issue 13, item 4): the calibrated walls of
# the campaign's diagnosis on every record, against the paper's e alone.
rule calibrated_map_changes:
    input:
        maps=calibrated_map_batches,
        diagnosis=rules.diagnosis.output.json,
    output:
        table=res("maps", "calibrated.csv"),
        docs_summary=res("summaries", "calibrated.json"),
    log:
        res("logs", "calibrated_map_changes.log"),
    benchmark:
        res("benchmarks", "calibrated_map_changes.tsv")
    params:
        maps=calibrated_map_inputs,
        schema=schema_path("map_calibrated.schema.yaml"),
        n=CALIBRATED_N,
    script:
        "../../scripts/calibrated_map_changes.py"


rule calibrated_map_changes_page:
    input:
        map_calibrated=rules.calibrated_map_changes.output.table,
    output:
        map_calibrated=report_page("map_calibrated", "maps", "maps/calibrated.csv, what the lab's findings change"),
    log:
        res("logs", "report_pages", "map_calibrated.log"),
    benchmark:
        res("benchmarks", "report_pages", "map_calibrated.tsv")
    params:
        schemas={"map_calibrated": schema_path("map_calibrated.schema.yaml")},
    script:
        "../../scripts/report_pages.py"
