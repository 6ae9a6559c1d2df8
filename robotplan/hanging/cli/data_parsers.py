"""The options of ``robotplan data hang``, ``data hang-mine`` and ``data hang-in-hook``."""

from __future__ import annotations

import os

from robotplan.cli.common import add_data_options, add_ray_option
from robotplan.hanging.cli.commands import cmd_data_hang, cmd_in_hook_hang, cmd_mine_hang

__all__ = ["add_hang_data_parsers"]


def add_hang_data_parsers(dsub) -> None:
    """The hanging data commands under the ``data`` subparsers ``dsub``."""
    dh = dsub.add_parser("hang", help="mug-hanging data from pybullet: mug poses dropped on "
                         "hooks, labelled hangs or not (paper app. H)")
    add_data_options(dh, shard_size=20)
    dh.add_argument("--per-scene", type=int, default=20,
                    help="labelled configurations kept per scene")
    dh.set_defaults(run=cmd_data_hang)
    dm = dsub.add_parser("hang-mine", help="hard examples for H_hang: the planner's program "
                         "run with a model on the scenes of a hang data folder, its end poses "
                         "dropped in pybullet and labelled")
    dm.add_argument("--data", required=True, metavar="DIR", help="a robotplan data hang folder")
    dm.add_argument("--model", default=None, metavar="DIR", help="default: learned/hang")
    dm.add_argument("--out", required=True, metavar="DIR")
    dm.add_argument("--first", type=int, default=0, help="start at this scene of --data")
    dm.add_argument("--scenes", type=int, default=None,
                    help="mine N scenes (default: all from --first on)")
    dm.add_argument("--starts", type=int, default=2, help="program solves per scene")
    dm.add_argument("--seed", type=int, default=0, help="draws the start poses")
    dm.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    add_ray_option(dm)
    dm.set_defaults(run=cmd_mine_hang)
    di = dsub.add_parser("hang-in-hook", help="failures H_hang should know: mug poses that "
                         "start in collision with the hook, near where the scenes of a hang "
                         "data folder hang (no drop needed)")
    di.add_argument("--data", required=True, metavar="DIR", help="a robotplan data hang folder")
    di.add_argument("--out", required=True, metavar="DIR")
    di.add_argument("--scenes", type=int, default=None,
                    help="the first N scenes of --data (default: all)")
    di.add_argument("--per-scene", type=int, default=10, help="poses kept per scene")
    di.add_argument("--seed", type=int, default=0, help="draws the poses")
    di.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    di.add_argument("--shard-size", type=int, default=50)
    add_ray_option(di)
    di.set_defaults(run=cmd_in_hook_hang)
