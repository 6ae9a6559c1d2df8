"""The ``robotplan`` command line: ``check``, ``render``, ``solve``, ``bench``, ``data``,
``train``, ``eval``, ``reproduce``.

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
)
from robotplan.cli.hang_commands import cmd_bench_hang, cmd_eval_hang, cmd_train_hang
from robotplan.cli.hang_data_parsers import add_hang_data_parsers
from robotplan.cli.model_commands import (
    cmd_bench,
    cmd_bench_contact_push,
    cmd_bench_functional,
    cmd_bench_push,
    cmd_data_push,
    cmd_eval_push,
)
from robotplan.cli.representation_options import add_representation_options
from robotplan.cli.reproduce_commands import add_reproduce_parser
from robotplan.cli.scene_commands import cmd_check, cmd_diagnose, cmd_render, cmd_solve, cmd_view
from robotplan.cli.train_push_parser import add_train_push_parser
from robotplan.models.symmetry import VIEW_COUNTS
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
    add_loop_option(bp)
    add_rehearse_option(bp)
    add_program_option(bp)
    bp.set_defaults(run=cmd_bench_push)
    bh = bsub.add_parser("hang", help="find hanging poses on random mug-and-hook scenes and "
                         "drop them in pybullet (paper Tab. 3)")
    bh.add_argument("--scenes", type=int, default=150)
    bh.add_argument("--seed", type=int, default=2)
    bh.add_argument("--out", required=True, metavar="DIR",
                    help="rows.jsonl per scene (continues a partial run) and summary.json")
    bh.add_argument("--model", default=None, metavar="DIR", help="default: learned/hang")
    bh.add_argument("--methods", default=None,
                    help="comma-separated subset of opt_sampling, opt_only, sampling_k1, "
                    "sampling_k2, sampling_k3 (default: all), and closed_loop")
    bh.add_argument("--evaluations", type=int, default=20_000,
                    help="functional evaluations per method and scene (the paper: 20,000)")
    bh.add_argument("--start-pool", type=int, default=None, metavar="N",
                    help="each optimisation starts from the best of N random poses (default: "
                    "the planner's, HangSettings.start_pool)")
    bh.add_argument("--robust-samples", type=int, default=None, metavar="N",
                    help="a found pose ends a scene's restarts only where H_hang's median "
                    "over N poses about it (1 cm, 5°) is ≤ 0.1 (default 0: off; "
                    "HangSettings.robust_samples)")
    bh.add_argument("--approach-iterations", type=int, default=None, metavar="N",
                    help="SNOPT iterations without the H_hang row before each whole program "
                    "(0: none, the paper's; default: HangSettings.approach_iterations)")
    bh.add_argument("--no-threading", dest="threading", action="store_false",
                    help="uniform random starts and no H_thread row (the paper's); default: "
                    "starts threaded on the arm, kept threaded (HangSettings.threading)")
    bh.add_argument("--check", default=None, metavar="DIR|none",
                    help="a second H_hang whose value a found pose of the optimisation rows "
                    "must keep ≤ 0.2 too, else the restarts go on (default: "
                    "learned/hang_check; none: the paper's one network; not the closed loop)")
    bh.add_argument("--collision", choices=["sdf", "model", "none"], default="sdf",
                    help="H_coll on the shapes' SDFs, on what the model reads (ψ: the "
                    "paper's occupancy rows) or none (its point-cloud rows)")
    bh.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    add_ray_option(bh)
    bh.add_argument("--json", action="store_true")
    bh.set_defaults(run=cmd_bench_hang)

    add_reproduce_parser(sub)

    default_model = str(learned_dir("push_flow"))
    so = sub.add_parser("solve", help="plan a scene, execute it in pybullet, write the result")
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

    d = sub.add_parser("data", help="generate training data")
    dsub = d.add_subparsers(dest="what", required=True)
    dp = dsub.add_parser("push", help="push data from pybullet (boxes and L-shapes, or "
                         "unseen footprints)")
    add_data_options(dp, shard_size=50)
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
    th = tsub.add_parser("hang", help="train H_hang, the mug-hanging success model (eq. 21)")
    th.add_argument("--data", required=True, metavar="DIR")
    th.add_argument("--out", required=True, metavar="DIR", help="e.g. learned/hang")
    th.add_argument("--test", default=None, metavar="DIR",
                    help="held-out data to validate on (default: 5 %% of the scenes)")
    th.add_argument("--mined", action="append", default=[], metavar="DIR",
                    help="also train on the labelled poses in DIR (robotplan data hang-mine "
                         "or hang-in-hook); repeat for several folders")
    th.add_argument("--mined-repeat", type=int, default=1,
                    help="each mined sample this many times per epoch")
    th.add_argument("--init", default=None, metavar="DIR",
                    help="start from this model's weights (fine-tuning)")
    add_representation_options(th, 1000.0, "the boundary's marching-cubes vertices through "
                               "a PointNet")
    th.add_argument("--steps", type=int, default=20_000)
    th.add_argument("--batch", type=int, default=32)
    th.add_argument("--lr", type=float, default=1e-4)
    th.add_argument("--scenes", type=int, default=None, help="use only the first N scenes")
    th.add_argument("--seed", type=int, default=0)
    th.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    th.add_argument("--device", default="cpu", help="cpu, cuda or auto (the network's; grids "
                    "are rendered on the CPU)")
    th.add_argument("--minutes", type=float, default=None, help="stop after this wall time")
    th.add_argument("--anneal-by-time", action="store_true",
                    help="with --minutes: the learning rate reaches its floor when the "
                         "minutes run out")
    th.add_argument("--val-every", type=int, default=1000)
    th.add_argument("--resume", action="store_true", help="continue from checkpoint.pt")
    th.add_argument("--overwrite", action="store_true", help="start over in a used folder")
    th.set_defaults(run=cmd_train_hang)

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
    eh = esub.add_parser("hang", help="H_hang on held-out hanging data: loss (eq. 21) and "
                         "accuracy at the paper's thresholds κ1–κ3")
    eh.add_argument("--model", required=True, metavar="DIR")
    eh.add_argument("--data", required=True, metavar="DIR")
    eh.add_argument("--scenes", type=int, default=None)
    eh.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    eh.add_argument("--json", action="store_true")
    eh.add_argument("--record", action="store_true",
                    help="store the result in the model's metrics.json")
    eh.set_defaults(run=cmd_eval_hang)
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
