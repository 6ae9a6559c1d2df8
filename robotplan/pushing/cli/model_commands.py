"""Commands on data, models and benchmarks: ``data``, ``train``, ``eval``, ``bench``."""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

from robotplan.cli.common import (
    EXIT_BAD_INPUT,
    device_name,
    load_footprint_scene,
    not_a_model,
    print_result,
    simulators,
    training_folders_problem,
)
from robotplan.pushing.cli.push_options import architecture, architecture_problem

__all__ = ["cmd_bench", "cmd_bench_contact_push", "cmd_bench_functional",
           "cmd_data_push", "cmd_eval_push", "cmd_train_push"]


def cmd_data_push(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from robotplan.execution.physics import PHYSICS
    from robotplan.pushing.training.push_data import PushDataSpec, generate

    sims = simulators(args.sim)
    if sims is None:
        return EXIT_BAD_INPUT
    if len(sims) > 1:
        print("error: --sim: a data set is made in one simulator", file=sys.stderr)
        return EXIT_BAD_INPUT
    t0 = time.time()
    try:
        summary = generate(Path(args.out), args.scenes, args.seed, workers=args.workers,
                           shard_size=args.shard_size, spec=PushDataSpec(shapes=args.shapes),
                           ray=args.ray, physics=replace(PHYSICS, simulator=sims[0]))
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    seconds = time.time() - t0
    summary["seconds"] = round(seconds, 1)
    if summary["new_samples"]:
        summary["samples_per_second"] = round(summary["new_samples"] / seconds, 1)
    print(json.dumps(summary))
    return 0


def cmd_train_push(args: argparse.Namespace) -> int:
    import torch

    from robotplan.pushing.training.model_card import write_model_card
    from robotplan.pushing.training.train import TrainConfig, train

    out = Path(args.out)
    problem = (training_folders_problem(args.data, args.out, args.resume, args.overwrite)
               or architecture_problem(args))
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        return EXIT_BAD_INPUT
    ckpt = out / "checkpoint.pt"
    device = device_name(args.device)
    torch.set_num_threads(args.threads)
    cfg = TrainConfig(data=args.data, out=args.out, kind=args.model, steps=args.steps,
                      batch=args.batch, lr=args.lr, points=args.points, seed=args.seed,
                      scenes=args.scenes, device=device, minutes=args.minutes,
                      val_every=args.val_every, contact_share=args.contact_share,
                      warmup=args.warmup, rigid_loss=args.rigid_loss,
                      near_share=args.near_share, spec=architecture(args),
                      augment=args.augment, anneal_by_time=args.anneal_by_time,
                      init_weights=args.init_weights,
                      command=" ".join(["robotplan", *sys.argv[1:]]))
    if args.placement_reach is not None:
        cfg = replace(cfg, placement_reach=args.placement_reach)
    if args.resume:  # the run's settings come from its checkpoint; only the budget may change
        saved = json.loads(torch.load(ckpt, weights_only=True)["config"])
        cfg = TrainConfig(**{**saved, "steps": args.steps or saved["steps"],
                             "minutes": args.minutes, "device": device,
                             "out": args.out, "data": args.data,
                             "contact_share": args.contact_share
                             if args.contact_share is not None
                             else saved.get("contact_share")})
    if cfg.kind == "rigid":
        from robotplan.pushing.training.rigid import train_rigid

        last = train_rigid(cfg, resume=args.resume)
    else:
        last = train(cfg, resume=args.resume)
        write_model_card(out)
    print(json.dumps(last))
    return 0


def cmd_eval_push(args: argparse.Namespace) -> int:
    import torch

    from robotplan.pushing.training.evaluation import evaluate_push

    torch.set_num_threads(args.threads)
    device = device_name(args.device)
    for path, what in ((args.model, "--model"), (args.data, "--data")):
        if not Path(path).is_dir():
            print(f"error: {path}: {what}: no such folder", file=sys.stderr)
            return EXIT_BAD_INPUT
    spec = json.loads((Path(args.model) / "spec.json").read_text()) if (
        Path(args.model) / "spec.json").is_file() else {}
    problem = views_problem(args, spec)
    if problem:
        print(f"error: {args.model}: --views: {problem}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if spec.get("kind") == "rigid":
        from robotplan.pushing.training.rigid_evaluation import evaluate_rigid

        if args.pose_fit > 0 or args.record:
            print("note: --pose-fit and --record apply to F_flow and F; F_q predicts Δq "
                  "itself (delta_q_error, turn_gain)", file=sys.stderr)

        print_result(evaluate_rigid(args.model, args.data, scenes=args.scenes,
                                    per_scene=args.per_scene or None, seed=args.seed,
                                    device=device, views=args.views), args.json)
        return 0
    result = evaluate_push(args.model, args.data, scenes=args.scenes,
                           per_scene=args.per_scene or None, seed=args.seed, device=device,
                           views=args.views)
    if args.pose_fit > 0:
        from robotplan.pushing.training.pose_fit import evaluate_pose_fit

        fit = evaluate_pose_fit(args.model, args.data, samples=args.pose_fit, seed=args.seed,
                                scenes=args.scenes)
        result["pose_fit"] = fit
        # the Tab. 5 columns and turn gains as F_q reports them, read through the fit
        if "delta_q_error" in fit:
            result["delta_q_error"] = fit["delta_q_error"]
        result["turn_gain"] = {k: v["turn_gain"] for k, v in fit.items()
                               if isinstance(v, dict) and "turn_gain" in v and k != "all"}
    if args.record:
        from robotplan.pushing.training.model_card import record_heldout

        record_heldout(Path(args.model), result)
    print_result(result, args.json)
    return 0


def views_problem(args: argparse.Namespace, spec: dict) -> str | None:
    """What is wrong with ``eval push --views`` for a model of ``spec`` (None: nothing)."""
    if args.views == 1:
        return None
    if spec.get("representation") == "pointcloud":
        return "a point-cloud F_q reads no grid to turn; give --views 1"
    if args.record or args.pose_fit > 0:
        return "--record and --pose-fit read the network alone; give --views 1"
    if spec.get("frame", "table") == "object" and spec.get("kind") != "rigid":
        return "an object-frame F_flow or F turns its grid with the object; give --views 1"
    return None


def cmd_bench_functional(args: argparse.Namespace) -> int:
    import torch

    from robotplan.pushing.bench.functional import bench_functional

    torch.set_num_threads(args.threads)
    if not_a_model(args.model):
        return EXIT_BAD_INPUT
    result = bench_functional(args.model, configurations=args.configurations,
                              repeats=args.repeats,
                              naive=not args.no_naive)
    print_result(result, args.json)
    return 0


def cmd_bench_contact_push(args: argparse.Namespace) -> int:
    from robotplan.pushing.bench.contact_push import plan_from_contact

    if not_a_model(args.model):
        return EXIT_BAD_INPUT
    result = plan_from_contact(args.model)
    if not args.json:
        result = {k: v for k, v in result.items() if k not in ("q_obj", "q_pusher")}
    print_result(result, args.json)
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    import torch

    from robotplan.bench.sdf import bench_sdf

    torch.set_num_threads(args.threads)
    scene = load_footprint_scene(args.scene, "bench sdf")
    dtype = {"float32": torch.float32, "float64": torch.float64}[args.dtype]
    result = bench_sdf(scene, steps=args.steps, repeats=args.repeats, dtype=dtype)
    print_result(result, args.json)
    return 0
