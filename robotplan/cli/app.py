"""The ``robotplan`` command line: ``check``, ``render``, ``solve``, ``bench``, ``robot``,
``data``, ``train``, ``eval``, ``reproduce``.

Exit status: 0 success, 1 failure of the work itself, 2 bad input (one line on stderr naming
the file and the field, no traceback).
"""

from __future__ import annotations

import argparse
import os
import sys

from robotplan.base.memory import keep_freed_memory
from robotplan.base.resources import learned_dir, tasks_dir
from robotplan.base.units import RayMissing
from robotplan.cli.common import (
    EXIT_BAD_INPUT,
    add_data_options,
    add_dynamics_options,
    add_execution_options,
    add_loop_option,
    add_program_option,
    add_ray_option,
    add_rehearse_option,
    add_sim_option,
)
from robotplan.cli.reproduce_commands import add_reproduce_parser
from robotplan.cli.robot_commands import add_robot_parser
from robotplan.cli.scene_commands import cmd_check, cmd_diagnose, cmd_render, cmd_solve, cmd_view
from robotplan.hanging.cli.data_parsers import add_hang_data_parsers
from robotplan.hanging.cli.parsers import (
    add_bench_hang_parser,
    add_eval_hang_parser,
    add_train_hang_parser,
)
from robotplan.pushing.cli.bench_push_commands import cmd_bench_push
from robotplan.pushing.cli.model_commands import (
    cmd_bench,
    cmd_bench_contact_push,
    cmd_bench_functional,
    cmd_data_push,
    cmd_eval_push,
)
from robotplan.pushing.cli.plan_commands import add_bench_plan_parser
from robotplan.pushing.cli.train_push_parser import add_train_push_parser
from robotplan.pushing.models.symmetry import VIEW_COUNTS
from robotplan.scene import SceneError


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="robotplan", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)

    c = sub.add_parser("check", help="validate scene files; one 'ok' line per good file")
    c.add_argument("files", nargs="+", metavar="FILE")
    c.set_defaults(run=cmd_check)

    r = sub.add_parser("render", help="render the SDFs of scenes on X_h to PNG")
    r.add_argument("files", nargs="+", metavar="FILE")
    r.add_argument("--out", required=True, metavar="DIR", help="folder for <scene>_sdf.png")
    r.add_argument("--overwrite", action="store_true", help="replace existing pictures")
    r.set_defaults(run=cmd_render)

    b = sub.add_parser("bench", help="benchmarks (speed targets)")
    bsub = b.add_subparsers(dest="what", required=True)
    bs = bsub.add_parser("sdf", help="render every body of a scene at T steps on X_h")
    default_scene = tasks_dir() / "box_push.yaml"
    bs.add_argument("--scene", default=str(default_scene), metavar="FILE")
    bs.add_argument("--steps", type=int, default=40)
    bs.add_argument("--repeats", type=int, default=20)
    bs.add_argument("--threads", type=int, default=1)
    bs.add_argument("--dtype", choices=["float32", "float64"], default="float32")
    bs.add_argument("--json", action="store_true", help="print one JSON object")
    bs.set_defaults(run=cmd_bench)
    bf = bsub.add_parser("functional", help="H_F and analytic functionals: speed, accuracy")
    bf.add_argument("--model", default=str(learned_dir("push_flow")), metavar="DIR")
    bf.add_argument("--threads", type=int, default=1)
    bf.add_argument("--configurations", type=int, default=24,
                    help="realistic pushes for the accuracy check")
    bf.add_argument("--repeats", type=int, default=20)
    bf.add_argument("--no-naive", action="store_true", help="skip the slow naive timing")
    bf.add_argument("--json", action="store_true")
    bf.set_defaults(run=cmd_bench_functional)
    bc = bsub.add_parser("contact-push", help="plan one straight push from contact with the "
                         "learned program alone and run it open loop (paper Fig. 5)")
    bc.add_argument("--model", default=str(learned_dir("push_rigid")), metavar="DIR",
                    help="a learned dynamics folder (F_q on grids or point clouds, F_flow "
                         "or F)")
    bc.add_argument("--json", action="store_true")
    bc.set_defaults(run=cmd_bench_contact_push)
    bp = bsub.add_parser("push", help="plan + execute random push scenes (paper Fig. 3)")
    bp.add_argument("--scenes", type=int, default=20, help="scenes per shape type")
    bp.add_argument("--seed", type=int, default=0)
    bp.add_argument("--out", required=True, metavar="DIR",
                    help="scenes, per-scene results, CSV, box plot (continues a partial run)")
    add_dynamics_options(bp, several=True)
    bp.add_argument("--shapes", default="box,lshape",
                    help="comma-separated: box, lshape, ood (unseen footprints: triangle, "
                    "pentagon, hexagon, circle, T, cross, U, trapezoid), pose (a box or a "
                    "T-shape to a target pose turned 30–90°)")
    bp.add_argument("--workers", type=int, default=2)
    add_ray_option(bp)
    bp.add_argument("--exhaustive", action="store_true", help="solve every skeleton")
    bp.add_argument("--time-budget", type=float, default=None, metavar="S",
                    help="per scene: start no program after S seconds (best so far wins)")
    bp.add_argument("--overwrite", action="store_true")
    bp.add_argument("--json", action="store_true")
    bp.add_argument("--perturb", type=int, nargs="?", const=0, default=None, metavar="SEED",
                    help="execute in a perturbed world (friction and mass ±20 %%, observation "
                    "noise 1 mm / 0.5°), drawn per scene from SEED (default 0)")
    add_sim_option(bp, several=True)
    add_loop_option(bp)
    add_rehearse_option(bp)
    add_program_option(bp)
    bp.add_argument("--candidates", default=None, metavar="KIND[,KIND]",
                    help="the kinds of candidates each search may try (skeletons/tiers.yaml: "
                    "pose_fits, region_fits, plain, routes; default every kind); plain: the "
                    "paper's optimiser alone, without pushes fitted in closed form")
    bp.set_defaults(run=cmd_bench_push)
    add_bench_plan_parser(bsub)
    add_bench_hang_parser(bsub)

    add_reproduce_parser(sub)

    default_model = str(learned_dir("push_flow"))
    so = sub.add_parser("solve", help="plan a scene, execute it in pybullet or MuJoCo, write "
                        "the result")
    so.add_argument("scene", metavar="SCENE")
    so.add_argument("--out", required=True, metavar="DIR")
    add_dynamics_options(so)
    so.add_argument("--solver", choices=["snopt", "ipopt"], default="snopt")
    so.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    so.add_argument("--skeleton", default=None, help='one skeleton, e.g. "push@2,push@0"')
    so.add_argument("--max-pushes", type=int, default=2)
    so.add_argument("--overwrite", action="store_true")
    so.add_argument("--exhaustive", action="store_true",
                    help="solve every candidate skeleton (default: stop at the first good one)")
    so.add_argument("--time-budget", type=float, default=None, metavar="S",
                    help="start no program after S seconds; the best so far wins")
    add_execution_options(so)
    add_program_option(so)
    so.set_defaults(run=cmd_solve)

    dg = sub.add_parser("diagnose", help="a plan's push steps against one-step pybullet and "
                        "the learned model (where plan and physics part)")
    dg.add_argument("dir", metavar="DIR", help="a folder written by robotplan solve")
    dg.add_argument("scene", metavar="SCENE", help="the scene it was solved for")
    dg.add_argument("--model", default=default_model, metavar="DIR")
    dg.add_argument("--json", action="store_true")
    dg.set_defaults(run=cmd_diagnose)

    vw = sub.add_parser("view", help="serve DIR/playback.html locally")
    vw.add_argument("dir", metavar="DIR")
    vw.add_argument("--port", type=int, default=0, help="0: any free port")
    vw.set_defaults(run=cmd_view)

    add_robot_parser(sub)

    d = sub.add_parser("data", help="generate training data")
    dsub = d.add_subparsers(dest="what", required=True)
    dp = dsub.add_parser("push", help="push data from pybullet or MuJoCo (boxes and "
                         "L-shapes, or unseen footprints)")
    add_data_options(dp, shard_size=50)
    add_sim_option(dp, role="simulates the pushes")
    dp.add_argument("--shapes", choices=["train", "ood"], default="train",
                    help="train: boxes and L-shapes (the training distribution); ood: "
                    "footprints never trained on (triangle, pentagon, hexagon, circle, T, "
                    "cross, U, trapezoid; scene i draws family i mod 8), for held-out tests "
                    "as the paper's Tab. 6")
    dp.set_defaults(run=cmd_data_push)
    add_hang_data_parsers(dsub)

    t = sub.add_parser("train", help="train learned functionals")
    tsub = t.add_subparsers(dest="what", required=True)
    add_train_push_parser(tsub)
    add_train_hang_parser(tsub)

    e = sub.add_parser("eval", help="evaluate learned functionals")
    esub = e.add_subparsers(dest="what", required=True)
    ep = esub.add_parser("push", help="one-step RMSE (eq. 20) on held-out push data")
    ep.add_argument("--model", required=True, metavar="DIR")
    ep.add_argument("--data", required=True, metavar="DIR")
    ep.add_argument("--scenes", type=int, default=None)
    ep.add_argument("--per-scene", type=int, default=10,
                    help="at most this many random samples of each scene (0: all)")
    ep.add_argument("--seed", type=int, default=0)
    ep.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    ep.add_argument("--device", default="auto", help="cpu, cuda or auto")
    ep.add_argument("--pose-fit", type=int, default=0, metavar="N",
                    help="also fit the pose that minimises H_t on N contact samples and "
                         "report translation and turn errors (~1 s a sample)")
    ep.add_argument("--views", type=int, default=1, choices=VIEW_COUNTS,
                    help="average the model over the scene's quarter turns (4) and mirrors "
                         "(8), exact symmetries of X_h; costs as many network passes")
    ep.add_argument("--json", action="store_true")
    ep.add_argument("--record", action="store_true",
                    help="store the result in the model's metrics.json and model card")
    ep.set_defaults(run=cmd_eval_push)
    add_eval_hang_parser(esub)
    return p


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    keep_freed_memory()
    try:
        return args.run(args)
    except (SceneError, RayMissing) as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
