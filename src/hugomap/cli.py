"""Command line: ``hugomap <command> ...`` (also ``python -m hugomap``).

User commands check a config, follow a sweep, export an MD checkpoint to LAMMPS and draw
figures; the workflow's stages are the commands the Snakemake rules call, each with the
scene's resolved config as JSON (``--scene-json``), so a job needs no other file than its
inputs. The stages keep their top-level names (``hugomap piston ...``) rather than moving
under a ``stage`` verb: the rules' shell commands are part of what Snakemake records for
every output, and changing them would make it rerun every finished point of an existing
results folder. The help lists the two groups apart.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import textwrap

USER_COMMANDS = ("check-config", "status", "export-lammps", "figures", "history", "profile",
                 "replicas")  # fmt: skip
STAGE_COMMANDS = (
    "prepare", "load", "piston", "reference", "window", "amw", "mw", "dichotomy-state",
    "dichotomy-trial", "dichotomy-point", "shockframe", "aggregate", "campaign",
)  # fmt: skip


def _scene(args) -> dict:
    scene = json.loads(args.scene_json)
    scene.setdefault("name", args.scene_name or "")
    return scene


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit status."""
    from . import __version__

    ap = argparse.ArgumentParser(
        prog="hugomap", usage="hugomap [-h] [--version] <command> ...",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Shock Hugoniots from molecular dynamics (numba LJ, LAMMPS) and contact SPH.",
    )  # fmt: skip
    ap.add_argument("--version", action="version", version=f"hugomap {__version__}")
    sub = ap.add_subparsers(dest="cmd", metavar="<command>", help=argparse.SUPPRESS)
    helps: dict[str, str] = {}

    def add(name: str, help: str) -> argparse.ArgumentParser:
        helps[name] = help
        return sub.add_parser(name, help=help, description=help)

    def stage(name: str, help: str):
        p = add(name, help)
        p.add_argument("--scene-json", required=True, help="resolved scene config (JSON)")
        p.add_argument("--scene-name", default="")
        p.add_argument("--out", required=True)
        return p

    stage("prepare", "prepare a sample and measure its pole")
    p = stage("load", "piston run until the front reaches the target; checkpoint")
    p.add_argument("--sample", required=True)
    p.add_argument("--u-p", type=float, required=True)
    p = stage("piston", "continue the piston run and measure the Hugoniot point")
    p.add_argument("--loaded", required=True)
    p.add_argument("--u-p", type=float, required=True)
    p = stage("reference", "the scene's reference Hugoniot (computed, or copied from a shared one)")
    p.add_argument("--shared", default=None, help="copy this reference made for the same inputs")
    p.add_argument("--sample", default=None,
                   help="the prepared sample whose measured pole the reference is computed at "
                        "(backends with reference_from_sample: MD)")  # fmt: skip
    p = stage("window", "cut the moving window out of the loading checkpoint")
    p.add_argument("--loaded", required=True)
    p.add_argument("--u-p", type=float, required=True)
    for name in ("amw", "mw"):
        p = stage(name, f"{name.upper()} point from the window checkpoint")
        p.add_argument("--window", required=True)
        p.add_argument("--u-p", type=float, required=True)
    p = stage("dichotomy-state", "iteration k of the dichotomy's loop state (JSON)")
    p.add_argument("--window", required=True)
    p.add_argument("--k", type=int, required=True)
    p.add_argument("--previous", default=None)
    p.add_argument("trials", nargs="*")
    p = stage("dichotomy-trial", "one dichotomy trial at u_out = state.pending[index]")
    p.add_argument("--window", required=True)
    p.add_argument("--state", required=True)
    p.add_argument("--index", type=int, required=True)
    p = stage("dichotomy-point", "final refinement at the bisection's root")
    p.add_argument("--window", required=True)
    p.add_argument("--u-p", type=float, required=True)
    p.add_argument("--state", required=True)
    p.add_argument("trials", nargs="*")
    p = stage("shockframe", "msst or nphug point from the sample's pole (solver lammps)")
    p.add_argument("--sample", required=True)
    p.add_argument("--u-p", type=float, required=True)
    p.add_argument("--scheme", required=True, choices=("msst", "nphug"))
    p = add("aggregate", help="join a scene's points into one dataset")
    p.add_argument("--config-json", required=True)
    p.add_argument("--scene-name", required=True)
    p.add_argument("--reference", default=None)
    p.add_argument("--out", required=True)
    p.add_argument("points", nargs="+")
    p = add("figures", help="P-V and D-u_p figures of an aggregate")
    p.add_argument("aggregate")
    p.add_argument("--pv", required=True)
    p.add_argument("--dup", required=True)
    p = add("campaign", help="join a campaign's aggregates; draw the chart and the stability map")
    p.add_argument("--config-json", required=True, help="the config without its scenes")
    p.add_argument("--out", required=True, help="the campaign dataset (netCDF)")
    p.add_argument("--chart", required=True, help="speed-accuracy chart (PNG)")
    p.add_argument("--map", required=True, help="stability map (PNG)")
    p.add_argument("--pulls", help="every point's pull against its reference (PNG)")
    p.add_argument("aggregates", nargs="+", help="results/hugoniot/<scene>.nc of its scenes")
    p = add("replicas", help="do the errors hold? a replica campaign's chi-square and pulls")
    p.add_argument("campaign", help="results/campaign/<name>.nc of a replica study")
    p = add("history", help="history figure of one window point")
    p.add_argument("point")
    p.add_argument("--out", required=True)
    p = add("profile", help="the shock's profile in the front's frame from a piston checkpoint "
                            "(loaded.nc): density, velocity, stresses, temperature")  # fmt: skip
    p.add_argument("checkpoint", help="results/<scene>/up<u>/loaded.nc")
    p.add_argument("--out", required=True, help="the figure (PNG)")
    p.add_argument("--samples", type=int, default=10, help="last samples averaged (default 10)")
    p.add_argument("--merge", type=int, default=2, help="bins per point (default 2)")
    p = add("check-config", help="validate a YAML config")
    p.add_argument("config")
    p = add("status", help="a sweep's progress: points done, running, failed, pending per scene")
    p.add_argument("--results", default=None,
                   help="results folder (default: the --config's `results`, else results)")  # fmt: skip
    p.add_argument(
        "--config",
        default=None,
        help="the sweep's config (default: the config the results were made with, as "
        "recorded in them; before anything has run, config/config.yaml if present, else the "
        "scenes found under --results)",
    )
    p.add_argument("--json", action="store_true", help="machine-readable JSON output")
    p.add_argument(
        "--full",
        action="store_true",
        help="never cut the detail column (by default it is cut to the terminal's width, "
        "$COLUMNS if set; output to a file or pipe is never cut)",
    )
    p = add(
        "export-lammps",
        "write an MD checkpoint (sample, loaded, partial piston, window) as a LAMMPS data "
        "file (units lj, atom_style atomic; frozen atoms type 2)",
    )
    p.add_argument("checkpoint", help="an MD checkpoint (.nc)")
    p.add_argument("out", help="the data file to write (e.g. sample.data)")
    assert set(helps) == set(USER_COMMANDS) | set(STAGE_COMMANDS)
    width = max(map(len, helps)) + 2

    def group(title: str, names: tuple[str, ...]) -> str:
        rows = [
            textwrap.fill(helps[n], 88, initial_indent=f"  {n:<{width}}",
                          subsequent_indent=" " * (width + 2))
            for n in names
        ]  # fmt: skip
        return title + ":\n" + "\n".join(rows)

    ap.epilog = "\n\n".join([
        group("user commands", USER_COMMANDS),
        group("workflow stages (called by the Snakemake rules)", STAGE_COMMANDS),
        "'hugomap <command> --help' describes a command.",
    ])  # fmt: skip
    args = ap.parse_args(argv)
    if args.cmd is None:
        ap.print_help()
        return 0
    from .io.atomic import mpi_rank

    # the ranks of an MPI stage log the same lines: rank 0's progress, every rank's warnings
    level = logging.INFO if mpi_rank() == 0 else logging.WARNING
    logging.basicConfig(level=level, format="%(asctime)s %(levelname)s %(message)s")

    if args.cmd == "status":  # reads files only: no solver imports
        from .config import ConfigError
        from .status import run_status

        try:
            return run_status(args.results, args.config, as_json=args.json, full=args.full)
        except ConfigError as exc:
            print(exc, file=sys.stderr)
            return 2

    if args.cmd == "export-lammps":  # reads one checkpoint: no numba
        from .failures import CheckpointError
        from .io.checkpoint import MD_CHECKPOINT, read_checkpoint
        from .md.lammps_data import LammpsDataError, checkpoint_to_data, write_data

        try:
            ds = read_checkpoint(args.checkpoint, kind=MD_CHECKPOINT)
            out = write_data(args.out, checkpoint_to_data(ds))
        except (CheckpointError, LammpsDataError, OSError) as exc:
            print(f"export-lammps: {exc}", file=sys.stderr)
            return 2
        print(f"wrote {out} ({ds.sizes['atom']} atoms)")
        return 0

    from . import stages

    if args.cmd == "prepare":
        stages.prepare_sample(_scene(args), args.out)
    elif args.cmd == "load":
        stages.load_to_target(args.sample, _scene(args), args.u_p, args.out)
    elif args.cmd == "piston":
        stages.piston_point(args.loaded, _scene(args), args.u_p, args.out)
    elif args.cmd == "reference":
        stages.reference_stage(_scene(args), args.out, args.shared, args.sample)
    elif args.cmd == "window":
        stages.window_start(args.loaded, _scene(args), args.u_p, args.out)
    elif args.cmd in ("amw", "mw"):
        stages.control_point(args.window, _scene(args), args.u_p, args.out, args.cmd)
    elif args.cmd == "dichotomy-state":
        stages.dichotomy_state(args.window, _scene(args), args.k, args.previous, args.trials,
                               args.out)  # fmt: skip
    elif args.cmd == "dichotomy-trial":
        stages.dichotomy_trial(args.window, _scene(args), args.state, args.index, args.out)
    elif args.cmd == "dichotomy-point":
        stages.dichotomy_point(args.window, _scene(args), args.u_p, args.state, args.trials,
                               args.out)  # fmt: skip
    elif args.cmd == "shockframe":
        stages.shock_frame_point(args.sample, _scene(args), args.scheme, args.u_p, args.out)
    elif args.cmd == "aggregate":
        stages.aggregate(
            args.points, args.reference, json.loads(args.config_json), args.scene_name, args.out
        )
    elif args.cmd == "figures":
        from .figures import hugoniot_figures

        hugoniot_figures(args.aggregate, args.pv, args.dup)
    elif args.cmd == "campaign":
        import xarray as xr

        from .campaign import write_campaign
        from .config import validate_config
        from .figures import pulls_figure, speed_accuracy_figure, stability_map_figure

        cfg = validate_config(json.loads(args.config_json))  # expands the campaign's scenes
        out = write_campaign(cfg, args.aggregates, args.out)
        with xr.open_dataset(out, engine="netcdf4") as ds:
            ds = ds.load()
        speed_accuracy_figure(ds, args.chart)
        stability_map_figure(ds, args.map)
        if args.pulls:
            pulls_figure(ds, args.pulls)
    elif args.cmd == "replicas":
        import xarray as xr

        with xr.open_dataset(args.campaign, engine="netcdf4") as ds:
            reps = json.loads(ds.attrs.get("replicas", "{}"))
        if not reps:
            print(f"{args.campaign}: no replica study (a case whose resolutions set only "
                  "sample.seed)", file=sys.stderr)  # fmt: skip
            return 2
        for case, r in reps.items():
            # against the reference, then each window scheme against the piston
            for against, block in (("reference", r), ("piston", r.get("vs_piston", {}))):
                for which in ("usable", "ok"):
                    if which not in block:
                        continue
                    s = block[which]
                    head = {"case": case, "against": against, "points": which}
                    print(json.dumps({**head, **{k: v for k, v in s.items() if k != "groups"}}))
                    for g in s["groups"]:
                        print(json.dumps({**head, **g}))
    elif args.cmd == "history":
        from .figures import window_history_figure

        window_history_figure(args.point, args.out)
    elif args.cmd == "profile":
        from .figures import profile_figure
        from .stages.profile import front_profile

        try:
            prof = front_profile(args.checkpoint, args.samples, args.merge)
        except ValueError as exc:
            print(exc, file=sys.stderr)
            return 2
        profile_figure(prof, args.out)
    elif args.cmd == "check-config":
        from .config import ConfigError, load_config

        try:
            load_config(args.config)
        except ConfigError as exc:
            print(exc, file=sys.stderr)
            return 2
        print("config ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
