"""Commands on robot folders: ``robot reach`` measures what ``robot.yaml``'s ``reach`` says."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from robotplan.cli.common import EXIT_BAD_INPUT

__all__ = ["add_robot_parser"]


def add_robot_parser(sub) -> None:
    """``robot reach`` under the top-level subparsers ``sub``."""
    r = sub.add_parser("robot", help="robot folders (robots/<model>/robot.yaml)")
    rsub = r.add_subparsers(dest="what", required=True)
    rr = rsub.add_parser("reach", help="measure the tip's horizontal reach at push height "
                         "by inverse kinematics (the value for robot.yaml's reach)")
    rr.add_argument("robot", metavar="FOLDER", help="a robot folder (robots/panda) or a "
                    "model name (panda)")
    rr.add_argument("--tip-height", type=float, default=0.03, metavar="M")
    rr.add_argument("--flange-min", type=float, default=0.07, metavar="M")
    rr.add_argument("--link-min", type=float, default=0.12, metavar="M")
    rr.add_argument("--json", action="store_true")
    rr.set_defaults(run=cmd_robot_reach)


def _model_name(given: str) -> str | None:
    from robotplan.scene.robots import ROBOTS_DIR, available_models

    path = Path(given)
    if path.is_dir():
        if path.resolve().parent != ROBOTS_DIR.resolve():
            return None
        given = path.resolve().name
    return given if given in available_models() else None


def cmd_robot_reach(args: argparse.Namespace) -> int:
    from robotplan.scene.reader import SchemaError
    from robotplan.scene.robots import ROBOTS_DIR, available_models

    name = _model_name(args.robot)
    if name is None:
        print(f"error: {args.robot}: not a robot folder of {ROBOTS_DIR} (models: "
              f"{', '.join(available_models())})", file=sys.stderr)
        return EXIT_BAD_INPUT
    if not 0 < args.tip_height < args.flange_min <= args.link_min:
        print("error: --tip-height, --flange-min, --link-min: must be positive and rise in "
              "that order", file=sys.stderr)
        return EXIT_BAD_INPUT
    from robotplan.functionals.reach import ReachSettings, measure_reach
    from robotplan.scene.robots import load_robot_model

    try:
        model = load_robot_model(name)
    except SchemaError as err:
        print(f"error: {ROBOTS_DIR / name / 'robot.yaml'}: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    settings = ReachSettings(args.tip_height, args.flange_min, args.link_min)
    lo, hi = measure_reach(name, settings)
    if args.json:
        print(json.dumps({"model": name, "reach": [lo, hi], "in_robot_yaml":
                          list(model.reach), "settings": settings.__dict__}))
        return 0
    print(f"{name}: the tip reaches {lo:.2f}–{hi:.2f} m from the base axis with its centre "
          f"{settings.tip_height:g} m up, the flange ≥ {settings.flange_min:g} m and the "
          f"check links ≥ {settings.link_min:g} m (robot.yaml says {model.reach[0]:g}–"
          f"{model.reach[1]:g}); for robot.yaml: reach: [{lo:.2f}, {hi:.2f}]")
    return 0 if lo == lo else 1
