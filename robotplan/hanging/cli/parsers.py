"""The options of ``robotplan bench hang``, ``train hang`` and ``eval hang`` (the data
commands' are in :mod:`robotplan.hanging.cli.data_parsers`)."""

from __future__ import annotations

import os

from robotplan.cli.common import add_ray_option
from robotplan.cli.representation_options import add_representation_options
from robotplan.hanging.cli.commands import cmd_bench_hang, cmd_eval_hang, cmd_train_hang

__all__ = ["add_bench_hang_parser", "add_eval_hang_parser", "add_train_hang_parser"]


def add_bench_hang_parser(bsub) -> None:
    """``bench hang`` under the ``bench`` subparsers ``bsub``."""
    bh = bsub.add_parser("hang", help="find hanging poses on random mug-and-hook scenes and "
                         "drop them in pybullet or MuJoCo (paper Tab. 3)")
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
    bh.add_argument("--meshes", action="store_true",
                    help="the mesh mugs and hooks of tasks/meshes/hang/ (3 mugs × 2 hooks, "
                    "scene i the pair i mod 6) in place of procedural ones")
    bh.add_argument("--sim", default="pybullet", metavar="NAMES",
                    help="comma-separated simulators, each dropping the same found poses "
                    "(pybullet, mujoco; default pybullet): the results side by side")
    bh.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    add_ray_option(bh)
    bh.add_argument("--json", action="store_true")
    bh.set_defaults(run=cmd_bench_hang)


def add_train_hang_parser(tsub) -> None:
    """``train hang`` under the ``train`` subparsers ``tsub``."""
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


def add_eval_hang_parser(esub) -> None:
    """``eval hang`` under the ``eval`` subparsers ``esub``."""
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
