# Stage: overturning maps of Sect. 5 (Figs. 21-23). One job per (record,
# model) map, since a map is the unit that takes time; then the indices of
# Fig. 22 with the reductions between models, and the figures.
from rocklab.seismic.accelerograms import accelerogram_dir, read_manifest
from rocklab.seismic.overturning import MODELS

MAPS = config["maps"]
MANIFEST = read_manifest()
MAP_RECORDS = MAPS["records"] or list(MANIFEST.record)
MAP_FIG_RECORD = MAPS["figure_record"]
if MAP_FIG_RECORD not in MAP_RECORDS:
    MAP_FIG_RECORD = MAP_RECORDS[0]


def map_outputs():
    return [res("maps", name) for name in ("summary.csv", "reductions.csv", "comparison.csv")] + [
        res("figures", f"fig{n}.png") for n in (21, 22, 23)
    ] + [res("report", f"{name}.html") for name in ("map_summary", "map_reductions", "map_comparison")]


def map_path(record, model):
    return res("maps", f"{record}__{model}.nc")


def record_file(wildcards):
    """The shipped file of the record, so that replacing it recomputes its maps."""
    return recorded_path(accelerogram_dir() / MANIFEST.set_index("record").loc[wildcards.record, "file"])


rule overturning_map:
    input:
        record_file,
    output:
        res("maps", "{record}__{model}.nc"),
    wildcard_constraints:
        record="|".join(map(re.escape, MAP_RECORDS)),
        model="|".join(map(re.escape, MODELS)),
    params:
        n=MAPS["n"],
        lo=MAPS["lo"],
        hi=MAPS["hi"],
        alpha=MAPS["alpha"],
        R=MAPS["R"],
        form=MAPS["form"],
        eq17=MAPS["eq17"],
        polarity=MAPS["polarity"],
        chunks=MAPS["chunks"],
    threads: MAPS["threads"]
    resources:
        mem_mb=1000,
        runtime=20,
    log:
        res("logs", "maps", "{record}__{model}.log"),
    benchmark:
        res("benchmarks", "maps", "{record}__{model}.tsv")
    script:
        "../../scripts/overturning_map.py"


rule map_summary:
    input:
        maps=[map_path(r, m) for r in MAP_RECORDS for m in MODELS],
    output:
        summary=res("maps", "summary.csv"),
        reductions=res("maps", "reductions.csv"),
        comparison=res("maps", "comparison.csv"),
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
