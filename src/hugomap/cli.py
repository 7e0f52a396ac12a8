"""Command line: ``python -m hugomap <stage> ...`` (what the Snakemake rules call).

Every stage takes the scene's resolved config as JSON (``--scene-json``), so a job needs no
other file than its inputs; ``check-config`` validates a YAML config and prints the problems.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys


def _scene(args) -> dict:
    scene = json.loads(args.scene_json)
    scene.setdefault("name", args.scene_name or "")
    return scene


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit status."""
    ap = argparse.ArgumentParser(prog="hugomap", description=__doc__)
    sub = ap.add_subparsers(dest="cmd", required=True)

    def stage(name: str, help: str):
        p = sub.add_parser(name, help=help)
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
    stage("reference", "equilibrium-MD reference Hugoniot")
    p = sub.add_parser("aggregate", help="join a scene's points into one dataset")
    p.add_argument("--config-json", required=True)
    p.add_argument("--scene-name", required=True)
    p.add_argument("--reference", default=None)
    p.add_argument("--out", required=True)
    p.add_argument("points", nargs="+")
    p = sub.add_parser("figures", help="P-V and D-u_p figures of an aggregate")
    p.add_argument("aggregate")
    p.add_argument("--pv", required=True)
    p.add_argument("--dup", required=True)
    p = sub.add_parser("check-config", help="validate a YAML config")
    p.add_argument("config")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(message)s")

    from . import pipeline

    if args.cmd == "prepare":
        pipeline.prepare_sample(_scene(args), args.out)
    elif args.cmd == "load":
        pipeline.load_to_target_stage(args.sample, _scene(args), args.u_p, args.out)
    elif args.cmd == "piston":
        pipeline.piston_point(args.loaded, _scene(args), args.u_p, args.out)
    elif args.cmd == "reference":
        pipeline.reference_stage(_scene(args), args.out)
    elif args.cmd == "aggregate":
        pipeline.aggregate(
            args.points, args.reference, json.loads(args.config_json), args.scene_name, args.out
        )
    elif args.cmd == "figures":
        from .figures import hugoniot_figures

        hugoniot_figures(args.aggregate, args.pv, args.dup)
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
