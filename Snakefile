# hugomap: Hugoniots of shocked materials, mapped point by point.
# Usage: snakemake --cores 2   (config in config/config.yaml; see README.md)
import sys
from pathlib import Path

from snakemake.utils import min_version

min_version("9.0")


# The workflow profile (workflow/profiles/default: rerun-incomplete, nolock: a killed sweep
# resumes with the same command) for a plain `snakemake --cores 2` too. Snakemake looks for a
# default workflow profile only in profiles/default (beside this Snakefile, or in the working
# directory), and a Snakefile cannot set those options itself: Snakemake 9 hands the workflow
# its DAG and execution settings after this file is read. So a command-line run that names no
# --workflow-profile starts itself again, once, with this profile and the same arguments
# (anything Snakemake printed before it read this file may appear twice). With
# `--workflow-profile none` Snakemake behaves as it does by default; a run through the Python
# API, or a job Snakemake spawns, is left alone.
import os
from snakemake_interface_executor_plugins.settings import ExecMode

_argv = sys.argv
_launch = os.getcwd()
if workflow.overwrite_workdir is not None:
    # --directory: Snakemake has moved to it; the arguments' relative paths are relative to
    # where it started (its WorkdirHandler.olddir); if that is not found, no restart
    _launch = None
    import inspect

    for _frame in inspect.stack(0):
        _handler = getattr(_frame.frame.f_locals.get("self"), "_workdir_handler", None)
        if getattr(_handler, "olddir", None) is not None:
            _launch = str(_handler.olddir)
            break
if (
    (Path(_argv[0]).name == "snakemake" or _argv[0].endswith("snakemake/__main__.py"))
    and not any(a.split("=")[0] == "--workflow-profile" for a in _argv)
    and workflow.exec_mode == ExecMode.DEFAULT
    and _launch
):
    os.chdir(_launch)
    _profile = Path(workflow.basedir) / "workflow" / "profiles" / "default"
    os.execv(
        sys.executable,
        [
            sys.executable,
            "-m",
            "snakemake",
            "--workflow-profile",
            str(_profile),
            *_argv[1:],
        ],
    )

sys.path.insert(0, str(Path(workflow.basedir) / "src"))
from hugomap.config import ConfigError, load_config, load_schema, validate_config
from hugomap.io import sweep_lock
from snakemake.logging import logger


# One sweep at a time in a working directory (the profile turns Snakemake's own lock off, see
# workflow/profiles/default). The main process of a run that starts jobs takes
# .snakemake/hugomap.lock, naming itself (host, pid, start), when Snakemake calls onstart: a
# dry run, --lint, --unlock, "Nothing to be done" and the jobs Snakemake spawns take none. A
# live owner on this host, or one on another host, refuses the run and names the owner; a
# dead owner's lock (a sweep killed hard) is taken over. Released on success, on error and
# at exit (hugomap.io.sweep_lock).
onstart:
    if workflow.exec_mode == ExecMode.DEFAULT:
        try:
            sweep_lock.acquire(log=logger.warning)
        except sweep_lock.SweepLocked as exc:
            raise WorkflowError(str(exc)) from None


onsuccess:
    sweep_lock.release()


onerror:
    sweep_lock.release()


# The default sweep, unless a config was given on the command line (--configfile replaces
# it rather than being merged into it, so a test config runs alone). Snakemake's message for
# a YAML syntax error names neither line nor column: the project's loader reads the file
# again and gives them. (A --configfile is parsed by Snakemake before it reads this file, so
# its syntax errors cannot be caught here: `python -m hugomap check-config FILE` or
# `snakemake --verbose` shows their line and column.)
# (`workflow.configfile` is what the `configfile:` directive runs; the directive cannot stand
# in a try block.)
if not config:
    _default_config = Path(workflow.basedir) / "config" / "config.yaml"
    try:
        workflow.configfile(str(_default_config))
    except WorkflowError:
        try:
            load_config(_default_config)
        except ConfigError as exc:
            raise WorkflowError(str(exc)) from None
        raise


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
include: "workflow/rules/shockframe.smk"
include: "workflow/rules/hugoniot.smk"
include: "workflow/rules/campaign.smk"
include: "workflow/rules/validation_report.smk"


rule all:
    default_target: True
    input:
        all_targets(),
