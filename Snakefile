# rocklab: reduce a free-rocking campaign in the lab's raw format.
# This file only wires the rules; each stage lives in workflow/rules/.
from pathlib import Path

from snakemake.exceptions import WorkflowError
from snakemake.utils import min_version, validate

from rocklab.config import SCHEMA, schema_error

min_version("8.0")


# beside this file, not in the working directory: `--directory` may name any folder
configfile: Path(workflow.basedir, "config", "config.yaml")


# Every key, its meaning and its default: the schema, which fills in what the
# config files and --config leave out; an unknown key stops here, named.
try:
    validate(config, SCHEMA)
except WorkflowError as exc:
    raise schema_error(exc) from None


include: "workflow/rules/common.smk"
include: "workflow/rules/ingest.smk"
include: "workflow/rules/qc.smk"
include: "workflow/rules/dissipation.smk"
include: "workflow/rules/diagnosis.smk"
include: "workflow/rules/figures.smk"
include: "workflow/rules/seismic.smk"
include: "workflow/rules/docs.smk"
include: "workflow/rules/shake_table.smk"


# The targets: `snakemake campaign` for a campaign of one's own, `all` (the
# default) for everything of the paper.
localrules:
    all,
    campaign,
    maps,
    calibrated,
    limestone,
    shake_table,


rule all:
    """Everything: the campaign, the overturning maps, the limestone blocks and the docs pages."""
    default_target: True
    input:
        all_outputs(),
        DOCS_OUTPUTS,


rule campaign:
    """The campaign in raw_dir: reduction, QC, dissipation, diagnosis, figures and report pages."""
    input:
        campaign_outputs(),


rule maps:
    """The overturning maps of Sect. 5 (Figs. 21-23 and their indices)."""
    input:
        MAP_OUTPUTS,


rule calibrated:
    """The calibrated wall of the campaign's diagnosis on the maps (maps/calibrated.csv)."""
    input:
        CALIBRATED_OUTPUTS,


rule limestone:
    """The restitution of the UMinho limestone blocks."""
    input:
        LIMESTONE_OUTPUTS,


rule shake_table:
    """Real shake-table outcomes (shake_table_dir): the block against the PGV threshold and DEM."""
    input:
        SHAKE_TABLE_OUTPUTS,
