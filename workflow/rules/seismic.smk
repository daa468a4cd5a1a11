# Stage: overturning maps of Sect. 5 (Figs. 21-23): the maps of each record,
# then the indices of Fig. 22 with the reductions between models, and the
# figures; the calibrated walls of the campaign's diagnosis beside them.
from rocklab.seismic.accelerograms import accelerogram_dir, read_manifest
from rocklab.seismic import calibrated
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


def map_outputs():
    return [res("maps", name) for name in ("summary.csv", "reductions.csv", "comparison.csv")] + [
        res("figures", f"fig{n}.png") for n in (21, 22, 23)
    ] + [res("report", f"{name}.html") for name in ("map_summary", "map_reductions", "map_comparison")]


def map_path(record, model):
    return res("maps", f"{record}__{model}.nc")


def calibrated_outputs():
    return [res("maps", "calibrated.csv"), res("report", "map_calibrated.html")]


def calibrated_map_inputs(wildcards):
    """The maps of the paper's e-alone models and the folders of the calibrated
    ones, for the boundaries the campaign's diagnosis (a checkpoint) calibrates."""
    names = calibrated.model_names(checkpoints.diagnosis.get().output.json)
    boundaries = {calibrated.parse_name(n)[0] for n in names}
    e_alone = [calibrated.E_ALONE[b] for b in calibrated.PREFIX if b in boundaries]
    return [map_path(r, m) for r in MAP_RECORDS for m in e_alone] + [
        res("maps", "calibrated", r) for r in MAP_RECORDS if names
    ]


def record_path(record):
    """The shipped file of a record, so that replacing it recomputes its maps."""
    return recorded_path(accelerogram_dir() / MANIFEST.set_index("record").loc[record, "file"])


# The maps of several records per job (maps.records_per_job): a job's
# start-up (imports, the numba kernel's cache) is 1.5-2 s, as much as the
# maps of a short record, and 16 records x 2 rules as separate jobs spent
# about a fifth of the maps' time starting.  Each record keeps its own log.
MAP_BATCHES = [
    MAP_RECORDS[i : i + MAPS["records_per_job"]] for i in range(0, len(MAP_RECORDS), MAPS["records_per_job"])
]

for k, batch in enumerate(MAP_BATCHES, 1):

    rule:
        name:
            f"overturning_maps_{k}"
        priority: PRIORITY["maps"]
        input:
            records=[record_path(r) for r in batch],
        output:
            [map_path(r, m) for r in batch for m in MODELS],
        params:
            records=batch,
            models=list(MODELS),
            **MAP_PARAMS,
        threads: MAPS["threads"]
        resources:
            mem_mb=1000,
            runtime=20 * len(batch),
            cpus_per_task=MAPS["threads"],
        log:
            [res("logs", "maps", f"{r}.log") for r in batch],
        benchmark:
            res("benchmarks", "maps", f"batch{k}.tsv")
        script:
            "../../scripts/overturning_maps.py"

    # The calibrated walls (rocklab.seismic.calibrated) are named by the
    # campaign's diagnosis, a checkpoint: their maps of a record go to one folder.
    rule:
        name:
            f"calibrated_maps_{k}"
        priority: PRIORITY["maps"]
        input:
            records=[record_path(r) for r in batch],
            diagnosis=res("diagnosis.json"),
        output:
            [directory(res("maps", "calibrated", r)) for r in batch],
        params:
            records=batch,
            **{**MAP_PARAMS, "n": CALIBRATED_N},
        threads: MAPS["threads"]
        resources:
            mem_mb=1000,
            runtime=30 * len(batch),
            cpus_per_task=MAPS["threads"],
        log:
            [res("logs", "maps_calibrated", f"{r}.log") for r in batch],
        benchmark:
            res("benchmarks", "maps_calibrated", f"batch{k}.tsv")
        script:
            "../../scripts/overturning_maps.py"


rule map_summary:
    input:
        maps=[map_path(r, m) for r in MAP_RECORDS for m in MODELS],
    output:
        summary=res("maps", "summary.csv"),
        reductions=res("maps", "reductions.csv"),
        comparison=res("maps", "comparison.csv"),
        docs_summary=res("summaries", "maps.json"),
    params:
        summary_schema=schema_path("map_summary.schema.yaml"),
        reductions_schema=schema_path("map_reductions.schema.yaml"),
        comparison_schema=schema_path("map_comparison.schema.yaml"),
    log:
        res("logs", "map_summary.log"),
    benchmark:
        res("benchmarks", "map_summary.tsv")
    script:
        "../../scripts/map_summary.py"


rule map_figures:
    input:
        summary=res("maps", "summary.csv"),
        two_sided=[map_path(MAP_FIG_RECORD, m) for m in ("2s-housner", "2s-0.95")],
        one_sided=[map_path(MAP_FIG_RECORD, m) for m in ("1s-zero", "1s-1.05", "1s-eq17")],
    output:
        fig21=report_figure("21", "maps", "two-sided maps"),
        fig22=report_figure("22", "maps", "indices record by record"),
        fig23=report_figure("23", "maps", "one-sided maps"),
    log:
        res("logs", "map_figures.log"),
    benchmark:
        res("benchmarks", "map_figures.tsv")
    script:
        "../../scripts/map_figures.py"


# The report's pages of the three tables: sortable, filterable, columns described.
rule map_pages:
    input:
        map_summary=res("maps", "summary.csv"),
        map_reductions=res("maps", "reductions.csv"),
        map_comparison=res("maps", "comparison.csv"),
    output:
        map_summary=report_page("map_summary", "maps", "maps/summary.csv, the indices of every map"),
        map_reductions=report_page("map_reductions", "maps", "maps/reductions.csv, from one model to another"),
        map_comparison=report_page(
            "map_comparison", "maps", "maps/comparison.csv, record by record against Table 4 and the paper"
        ),
    params:
        schemas={
            "map_summary": schema_path("map_summary.schema.yaml"),
            "map_reductions": schema_path("map_reductions.schema.yaml"),
            "map_comparison": schema_path("map_comparison.schema.yaml"),
        },
    log:
        res("logs", "report_pages", "maps.log"),
    benchmark:
        res("benchmarks", "report_pages", "maps.tsv")
    script:
        "../../scripts/report_pages.py"


# The lab's findings on the maps (issue 13, item 4): the calibrated walls of
# the campaign's diagnosis on every record, against the paper's e alone.
rule map_calibrated:
    input:
        maps=calibrated_map_inputs,
        diagnosis=res("diagnosis.json"),
    output:
        table=res("maps", "calibrated.csv"),
        docs_summary=res("summaries", "calibrated.json"),
    params:
        schema=schema_path("map_calibrated.schema.yaml"),
        n=CALIBRATED_N,
    log:
        res("logs", "map_calibrated.log"),
    benchmark:
        res("benchmarks", "map_calibrated.tsv")
    script:
        "../../scripts/map_calibrated.py"


rule map_calibrated_page:
    input:
        map_calibrated=res("maps", "calibrated.csv"),
    output:
        map_calibrated=report_page("map_calibrated", "maps", "maps/calibrated.csv, what the lab's findings change"),
    params:
        schemas={"map_calibrated": schema_path("map_calibrated.schema.yaml")},
    log:
        res("logs", "report_pages", "map_calibrated.log"),
    benchmark:
        res("benchmarks", "report_pages", "map_calibrated.tsv")
    script:
        "../../scripts/report_pages.py"
