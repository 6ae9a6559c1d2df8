"""Commands of the mug-hanging task: data hang, train hang, eval hang, bench hang."""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

from robotplan.base.resources import learned_dir
from robotplan.cli.common import (
    EXIT_BAD_INPUT,
    device_name,
    model_folder_problem,
    print_result,
    training_folders_problem,
)
from robotplan.cli.representation_options import representation_fields, representation_problem

__all__ = ["cmd_bench_hang", "cmd_data_hang", "cmd_eval_hang", "cmd_in_hook_hang",
           "cmd_mine_hang", "cmd_train_hang", "solve_hang_scene"]


def cmd_data_hang(args: argparse.Namespace) -> int:
    from robotplan.hanging.training.data import HangDataSpec, generate_hang

    if args.scenes < 1 or args.per_scene < 2:
        print("error: --scenes must be ≥ 1 and --per-scene ≥ 2", file=sys.stderr)
        return EXIT_BAD_INPUT
    t0 = time.time()
    try:
        summary = generate_hang(Path(args.out), args.scenes, args.seed, workers=args.workers,
                                shard_size=args.shard_size,
                                spec=HangDataSpec(per_scene=args.per_scene), ray=args.ray)
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    summary["seconds"] = round(time.time() - t0, 1)
    if summary["made_shards"]:
        summary["scenes_per_second"] = round(
            summary["new_samples"] / args.per_scene / max(summary["seconds"], 1e-9), 3)
    print(json.dumps(summary))
    return 0


def cmd_mine_hang(args: argparse.Namespace) -> int:
    from robotplan.hanging.training.mining import MiningSpec, mine_hang

    model = args.model or str(learned_dir("hang"))
    problem = (f"{args.data}: --data: no such folder" if not Path(args.data).is_dir() else
               model_folder_problem(model) or (
                   "--starts must be ≥ 1" if args.starts < 1 else
                   "--scenes must be ≥ 1" if args.scenes is not None and args.scenes < 1
                   else None))
    return _make_folder(problem, lambda: mine_hang(
        Path(args.data), Path(model), Path(args.out), args.seed, args.scenes,
        MiningSpec(starts=args.starts), workers=args.workers, first=args.first, ray=args.ray))


def cmd_in_hook_hang(args: argparse.Namespace) -> int:
    from robotplan.hanging.training.in_hook import InHookSpec, make_in_hook

    problem = (f"{args.data}: --data: no such folder" if not Path(args.data).is_dir() else
               "--per-scene must be ≥ 1" if args.per_scene < 1 else
               "--scenes must be ≥ 1" if args.scenes is not None and args.scenes < 1 else None)
    return _make_folder(problem, lambda: make_in_hook(
        Path(args.data), Path(args.out), args.seed, args.scenes,
        InHookSpec(per_scene=args.per_scene), workers=args.workers,
        shard_size=args.shard_size, ray=args.ray))


def _make_folder(problem: str | None, make: Callable[[], dict]) -> int:
    """A command that makes a folder from a hang data folder: one line and exit 2 for
    ``problem`` or for what ``make`` refuses, else its summary and seconds as JSON."""
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        return EXIT_BAD_INPUT
    t0 = time.time()
    try:
        summary = make()
    except (ValueError, FileNotFoundError) as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    summary["seconds"] = round(time.time() - t0, 1)
    print(json.dumps(summary))
    return 0


def cmd_train_hang(args: argparse.Namespace) -> int:
    import torch

    from robotplan.hanging.training.train import HangTrainConfig, train_hang

    problem = training_folders_problem(args.data, args.out, args.resume, args.overwrite)
    if not problem and args.test and not Path(args.test).is_dir():
        problem = f"{args.test}: --test: no such folder"
    missing = [m for m in args.mined if not Path(m).is_dir()]
    if not problem and missing:
        problem = f"{missing[0]}: --mined: no such folder"
    if not problem and args.init:
        problem = model_folder_problem(args.init, "--init")
    if not problem and args.mined_repeat < 1:
        problem = "--mined-repeat must be ≥ 1"
    if not problem:
        problem = representation_problem(args)
    if not problem and args.init and representation_fields(args):
        problem = "--representation/--sharpness/--cloud-encoder: the --init model's spec sets them"
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        return EXIT_BAD_INPUT
    torch.set_num_threads(args.threads)
    cfg = HangTrainConfig(data=args.data, out=args.out, test=args.test, steps=args.steps,
                          batch=args.batch, lr=args.lr, seed=args.seed, scenes=args.scenes,
                          minutes=args.minutes, val_every=args.val_every,
                          mined=list(args.mined), mined_repeat=args.mined_repeat,
                          init=args.init, device=device_name(args.device),
                          anneal_by_time=args.anneal_by_time, spec=representation_fields(args),
                          command=" ".join(["robotplan", *sys.argv[1:]]))
    if args.resume:  # the run's settings come from its checkpoint; only the budget may change
        ckpt = Path(args.out) / "checkpoint.pt"
        saved = json.loads(torch.load(ckpt, weights_only=True)["config"])
        cfg = HangTrainConfig(**{**saved, "steps": args.steps or saved["steps"],
                                 "minutes": args.minutes, "out": args.out,
                                 "data": args.data, "device": device_name(args.device)})
    print(json.dumps(train_hang(cfg, resume=args.resume)))
    return 0


def cmd_eval_hang(args: argparse.Namespace) -> int:
    import numpy as np
    import torch

    from robotplan.hanging.models.hang_model import load_hang_model
    from robotplan.hanging.training.train import HangSamples, hang_metrics

    for path, what in ((args.model, "--model"), (args.data, "--data")):
        if not Path(path).is_dir():
            print(f"error: {path}: {what}: no such folder", file=sys.stderr)
            return EXIT_BAD_INPUT
    torch.set_num_threads(args.threads)
    try:
        model = load_hang_model(args.model)
    except (FileNotFoundError, ValueError) as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    samples = HangSamples(args.data, model.spec, args.scenes)
    result = hang_metrics(model, samples, np.arange(len(samples)))
    if args.record:
        from robotplan.training.loop import write_json

        path = Path(args.model) / "metrics.json"
        metrics = json.loads(path.read_text()) if path.is_file() else {}
        metrics["heldout"] = {"data": str(args.data), **result}
        write_json(path, metrics)
    print_result(result, args.json)
    return 0


def cmd_bench_hang(args: argparse.Namespace) -> int:
    from robotplan.hanging.bench.bench import CLOSED_LOOP, METHODS, run_bench_hang
    from robotplan.hanging.execution.worlds import hang_simulator_problem
    from robotplan.hanging.program.problem import HANG_DEFAULTS

    model = args.model or str(learned_dir("hang"))
    check = (None if args.check == "none" else args.check or str(learned_dir("hang_check")))
    methods = tuple(args.methods.split(",")) if args.methods else METHODS
    pool = HANG_DEFAULTS.start_pool if args.start_pool is None else args.start_pool
    approach = (HANG_DEFAULTS.approach_iterations if args.approach_iterations is None
                else args.approach_iterations)
    robust = (HANG_DEFAULTS.robust_samples if args.robust_samples is None
              else args.robust_samples)
    unknown = [m for m in methods if m not in (*METHODS, CLOSED_LOOP)]
    sims = tuple(dict.fromkeys(v.strip() for v in args.sim.split(",") if v.strip()))
    sim_problem = hang_simulator_problem(sims) if sims else "no simulator given"
    if sim_problem:
        print(f"error: --sim: {sim_problem}", file=sys.stderr)
        return EXIT_BAD_INPUT
    problem = model_folder_problem(model) or (
        check and model_folder_problem(check, "--check")) or (
        f"--methods: unknown {unknown}; choose from {','.join((*METHODS, CLOSED_LOOP))}"
        if unknown else
        "--scenes must be ≥ 1" if args.scenes < 1 else
        "--evaluations must be ≥ 1" if args.evaluations < 1 else
        "--start-pool must be ≥ 1" if pool < 1 else
        "--approach-iterations must be ≥ 0" if approach < 0 else
        "--robust-samples must be ≥ 0" if robust < 0 else None)
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        return EXIT_BAD_INPUT
    settings = replace(HANG_DEFAULTS, evaluations=args.evaluations,
                       start_pool=pool, robust_samples=robust, approach_iterations=approach,
                       collision=args.collision, threading=args.threading)
    try:
        summary = run_bench_hang(args.scenes, args.seed, Path(args.out), model,
                                 workers=args.workers, methods=methods, settings=settings,
                                 ray=args.ray, check_dir=check,
                                 scene_set="meshes" if args.meshes else "procedural",
                                 simulators=sims)
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.json:
        print(json.dumps(summary))
        return 0
    _print_bench_table(summary, methods, sims)
    if args.evaluations != HANG_DEFAULTS.evaluations:
        print(f"budget: {args.evaluations} functional evaluations per method and scene "
              f"(the paper: {HANG_DEFAULTS.evaluations})")
    if args.collision != "sdf":
        print(f"collision row: {args.collision} (sdf: on the shapes' SDFs; model: on what "
              "the model reads of them; none: H_hang alone)")
    print(f"median seconds (optimisation + sampling): {summary['median_seconds']}")
    if CLOSED_LOOP in summary:
        loop = summary[CLOSED_LOOP]
        print(f"closed loop (each found pose dropped, the search going on while the mug "
              f"falls): median {loop['median_seconds']} s, {loop['median_drops']:g} drops")
    return 0


def _print_bench_table(summary: dict, methods: tuple[str, ...], sims: tuple[str, ...]) -> None:
    """Tab. 3's columns, a row per method and simulator (the simulators side by side)."""
    by_sim = summary.get("by_simulator", {sims[0]: summary})
    print(f"{'method':<14}{'simulator':<10}{'found':>8}{'sim ok':>8}{'coll.free':>10}"
          f"{'total':>8}{'paper total':>13}{'in place':>10}")
    for m in methods:
        paper = summary["paper"].get(m)
        for k, sim in enumerate(sims):
            if m in by_sim[sim]:
                r = by_sim[sim][m]
                print(f"{m if k == 0 else '':<14}{sim:<10}{r['found']:>8.3f}"
                      f"{r['sim_success']:>8.3f}{r['collision_free']:>10.3f}{r['total']:>8.3f}"
                      f"{f'{paper[3]:.3f}' if paper else '—':>13}{r['in_place']:>10.3f}")


def solve_hang_scene(task, out: Path, model: str | None, open_loop: bool = False,
                     sim: str = "pybullet") -> int:
    """``robotplan solve`` of a hang scene: find the pose, drop it in simulator ``sim``
    (closed loop: search on while the mug falls), write the result."""
    from robotplan.hanging.api.planner import solve_hang

    folder = Path(model) if model else learned_dir("hang")
    if not (folder / "spec.json").is_file():
        print(f"error: {folder}: no trained H_hang here (spec.json); train one with "
              "robotplan train hang, or pass --model DIR", file=sys.stderr)
        return EXIT_BAD_INPUT
    doc = solve_hang(task, out, folder, mode="open_loop" if open_loop else "closed_loop",
                     sim=sim)
    ex = doc["execution"]
    fell = f" after {len(ex['replans'])} poses it fell from" if ex["replans"] else ""
    print(f"{doc['status']}: H_hang {doc['h_hang']:.3g}, H_coll {doc['h_coll_cm3']:.3g} cm³ "
          f"after {doc['restarts']} optimisations ({doc['evaluations']} evaluations, "
          f"{doc['plan_seconds']} s); dropped in {ex['simulator']} "
          f"({ex['mode'].replace('_', ' ')}) "
          f"the mug {'hangs' if ex['hung'] else 'falls'}{fell}; wrote {out / 'result.json'} and "
          f"{out / 'playback.html'}")
    return 0 if doc["status"] == "solved" else 1
