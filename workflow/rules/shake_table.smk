# Stage: real shake-table outcomes (issue 16; rocklab.shake_table). Not part
# of `all`: the data live outside the repository (config key shake_table_dir).
# The table motions are read once; each specimen's block is simulated once per
# test at every node of the causes' grid (the job that takes time); every fit,
# fold and resample reads that grid.
from rocklab.shake_table.asu_data import SPECIMENS

ST = config["shake_table"]
ST_DIR = config["shake_table_dir"]
ST_TABLES = ("scores", "predictions", "nominal_errors", "fragility", "parameters", "transfer")


SHAKE_TABLE_OUTPUTS = (
    [res("shake_table", f"{name}.csv") for name in ("motions", *ST_TABLES)]
    + [res("shake_table", f"maps_{s}.nc") for s in SPECIMENS]
    + [res("figures", f"shake_table_{name}.png") for name in ("fragility", "maps")]
)


rule shake_table_motions:
    input:
        shake_table_data,
    output:
        res("shake_table", "motions.csv"),
    log:
        res("logs", "shake_table", "motions.log"),
    benchmark:
        res("benchmarks", "shake_table", "motions.tsv")
    params:
        folder=ST_DIR,
        ground_motions=ST["ground_motions"],
        schema=schema_path("shake_table_motions.schema.yaml"),
    script:
        "../../scripts/shake_table_motions.py"


rule shake_table_outcomes:
    input:
        data=shake_table_data,
        motions=res("shake_table", "motions.csv"),
    output:
        res("shake_table", "outcomes_{specimen}.nc"),
    log:
        res("logs", "shake_table", "outcomes_{specimen}.log"),
    benchmark:
        res("benchmarks", "shake_table", "outcomes_{specimen}.tsv")
    wildcard_constraints:
        specimen="|".join(SPECIMENS),
    threads: ST["threads"]
    params:
        folder=ST_DIR,
    script:
        "../../scripts/shake_table_outcomes.py"


rule shake_table_calibration:
    input:
        data=shake_table_data,
        motions=res("shake_table", "motions.csv"),
        outcomes=[res("shake_table", f"outcomes_{s}.nc") for s in SPECIMENS],
    output:
        **{name: res("shake_table", f"{name}.csv") for name in ST_TABLES},
        docs_summary=res("summaries", "shake_table.json"),
    log:
        res("logs", "shake_table", "calibration.log"),
    benchmark:
        res("benchmarks", "shake_table", "calibration.tsv")
    params:
        folder=ST_DIR,
        folds=ST["folds"],
        n_boot=ST["n_boot"],
        n_boot_cv=ST["n_boot_cv"],
        schemas={name: schema_path(f"shake_table_{name}.schema.yaml") for name in ST_TABLES},
    script:
        "../../scripts/shake_table_calibration.py"


rule shake_table_maps:
    input:
        data=shake_table_data,
        predictions=res("shake_table", "predictions.csv"),
        parameters=res("shake_table", "parameters.csv"),
    output:
        res("shake_table", "maps_{specimen}.nc"),
    log:
        res("logs", "shake_table", "maps_{specimen}.log"),
    benchmark:
        res("benchmarks", "shake_table", "maps_{specimen}.tsv")
    wildcard_constraints:
        specimen="|".join(SPECIMENS),
    threads: ST["threads"]
    params:
        folder=ST_DIR,
        n=ST["map_n"],
    script:
        "../../scripts/shake_table_maps.py"


rule shake_table_figures:
    input:
        predictions=res("shake_table", "predictions.csv"),
        fragility=res("shake_table", "fragility.csv"),
        maps=[res("shake_table", f"maps_{s}.nc") for s in SPECIMENS],
    output:
        fragility=res("figures", "shake_table_fragility.png"),
        maps=res("figures", "shake_table_maps.png"),
    log:
        res("logs", "shake_table", "figures.log"),
    benchmark:
        res("benchmarks", "shake_table", "figures.tsv")
    script:
        "../../scripts/shake_table_figures.py"
