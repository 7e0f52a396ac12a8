# hugomap: Hugoniots of shocked materials, mapped point by point.
# Usage: snakemake --cores 2   (config in config/config.yaml; see README.md)
import sys
from pathlib import Path

from snakemake.utils import min_version

min_version("9.0")

sys.path.insert(0, str(Path(workflow.basedir) / "src"))
from hugomap.config import ConfigError, load_schema, validate_config

# The default sweep, unless a config was given on the command line (--configfile replaces
# it rather than being merged into it, so a test config runs alone).
if not config:

    configfile: str(Path(workflow.basedir) / "config" / "config.yaml")


# Refuse a bad config before any job starts (schema ranges, unknown keys, cross-key checks).
try:
    validate_config(
        config,
        load_schema(
            Path(workflow.basedir) / "workflow" / "schemas" / "config.schema.json"
        ),
    )
except ConfigError as exc:
    raise WorkflowError(str(exc)) from None


include: "workflow/rules/common.smk"
include: "workflow/rules/piston.smk"
include: "workflow/rules/window.smk"
include: "workflow/rules/hugoniot.smk"
include: "workflow/rules/campaign.smk"


rule all:
    default_target: True
    input:
        all_targets(),
