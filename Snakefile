# rocklab: reduce a free-rocking campaign in the lab's raw format.
# This file only wires the rules; each stage lives in workflow/rules/.
from snakemake.utils import min_version, validate

min_version("8.0")


configfile: "config/config.yaml"


validate(config, "workflow/schemas/config.schema.yaml")


include: "workflow/rules/common.smk"
include: "workflow/rules/ingest.smk"
include: "workflow/rules/qc.smk"
include: "workflow/rules/dissipation.smk"
include: "workflow/rules/diagnosis.smk"
include: "workflow/rules/figures.smk"
include: "workflow/rules/seismic.smk"


rule all:
    input:
        all_outputs(),
    default_target: True
