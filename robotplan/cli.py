"""The ``robotplan`` command line: ``check``, ``render``, ``bench``, ``data``, ``train``, ``eval``.

Exit status: 0 success, 1 failure of the work itself, 2 bad input (one line on stderr naming
the file and the field, no traceback).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

from robotplan.memory import keep_freed_memory
from robotplan.scene import SceneError, load_scene

EXIT_BAD_INPUT = 2


def _print_result(result: dict, as_json: bool) -> None:
    """One JSON object (``--json``), or aligned ``key: value`` lines for a person."""
    if as_json:
        print(json.dumps(result))
        return
    width = max(map(len, result), default=0)
    for k, v in result.items():
        print(f"{k:>{width}}: {v}")


def _not_a_model(folder: str) -> bool:
    """True (after the one-line error) when ``--model`` is not a model folder."""
    if (Path(folder) / "spec.json").is_file():
        return False
    print(f"error: {folder}: --model: not a model folder (no spec.json)", file=sys.stderr)
    return True


def _cmd_check(args: argparse.Namespace) -> int:
    status = 0
    for f in args.files:
        try:
            scene = load_scene(f)
        except SceneError as err:
            print(f"error: {err}", file=sys.stderr)
            status = EXIT_BAD_INPUT
            continue
        print(f"ok {f}: {scene.summary()}")
    return status


def _cmd_render(args: argparse.Namespace) -> int:
    from robotplan.render import render_scene_sdf

    scenes = [load_scene(f) for f in args.files]  # refuse bad input before writing anything
    out = Path(args.out)
    targets = [out / f"{Path(f).stem}_sdf.png" for f in args.files]
    if not args.overwrite:
        existing = [str(t) for t in targets if t.exists()]
        if existing:
            print(f"error: {existing[0]}: exists; pass --overwrite to replace it",
                  file=sys.stderr)
            return EXIT_BAD_INPUT
    for scene, target in zip(scenes, targets, strict=False):
        render_scene_sdf(scene, target)
        print(f"wrote {target}")
    return 0


def _cmd_bench(args: argparse.Namespace) -> int:
    import torch

    from robotplan.bench import bench_sdf

    torch.set_num_threads(args.threads)
    scene = load_scene(args.scene)
    dtype = {"float32": torch.float32, "float64": torch.float64}[args.dtype]
    result = bench_sdf(scene, steps=args.steps, repeats=args.repeats, dtype=dtype)
    _print_result(result, args.json)
    return 0


def _cmd_solve(args: argparse.Namespace) -> int:
    from robotplan.solve import UnsupportedScene, solve_scene

    scene = load_scene(args.scene)
    out = Path(args.out)
    if out.exists() and any(out.iterdir()) and not args.overwrite:
        print(f"error: {out}: --out: the folder is not empty; pass --overwrite to replace "
              "its result", file=sys.stderr)
        return EXIT_BAD_INPUT
    if _not_a_model(args.model):
        return EXIT_BAD_INPUT
    out.mkdir(parents=True, exist_ok=True)
    try:
        doc = solve_scene(scene, out, Path(args.model), solver=args.solver,
                          workers=args.workers, skeleton=args.skeleton,
                          max_pushes=args.max_pushes, exhaustive=args.exhaustive,
                          time_budget=args.time_budget)
    except UnsupportedScene as err:
        print(f"error: {args.scene}: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except ValueError as err:  # a bad --skeleton
        print(f"error: --skeleton: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    ex = doc.get("execution") or {}
    print(f"{doc['status']}: violation {doc['violation']:.3g}, coverage in pybullet "
          f"{ex.get('coverage')}, plan {doc['plan_seconds']} s; wrote {out / 'result.json'}"
          + (f" and {out / 'playback.html'}" if "playback" in doc else ""))
    return 0 if doc["status"] == "solved" else 1


def _cmd_diagnose(args: argparse.Namespace) -> int:
    from robotplan.diagnose import check_steps, summarize, table, to_json

    path = Path(args.dir) / "result.json"
    if not path.is_file():
        print(f"error: {path}: no result.json (run robotplan solve first)", file=sys.stderr)
        return EXIT_BAD_INPUT
    if _not_a_model(args.model):
        return EXIT_BAD_INPUT
    scene = load_scene(args.scene)
    try:
        checks = check_steps(scene, json.loads(path.read_text()), args.model)
    except (ValueError, KeyError, StopIteration) as err:
        print(f"error: {path}: {err!s} (is {args.scene} the scene it was solved for?)",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.json:
        print(to_json(checks))
        return 0
    print(table(checks))
    _print_result(summarize(checks), False)
    return 0


def _cmd_view(args: argparse.Namespace) -> int:
    import functools
    import http.server

    folder = Path(args.dir)
    page = folder / "playback.html"
    if not page.is_file():
        print(f"error: {page}: no playback here (run robotplan solve first)", file=sys.stderr)
        return EXIT_BAD_INPUT
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(folder))
    with http.server.ThreadingHTTPServer(("127.0.0.1", args.port), handler) as httpd:
        print(f"playback at http://127.0.0.1:{httpd.server_address[1]}/playback.html "
              "(Ctrl-C to stop)", flush=True)
        try:
            httpd.serve_forever()
        except KeyboardInterrupt:
            pass
    return 0


def _cmd_bench_push(args: argparse.Namespace) -> int:
    from robotplan.bench_push import run_bench_push

    if _not_a_model(args.model):
        return EXIT_BAD_INPUT
    if args.scenes < 1:
        print("error: --scenes: must be at least 1", file=sys.stderr)
        return EXIT_BAD_INPUT
    bad = set(args.shapes.split(",")) - {"box", "lshape", "ood"}
    if bad:
        print(f"error: --shapes: unknown shape type {sorted(bad)[0]!r} (box, lshape, ood)",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    out = Path(args.out)
    summary_path = out / "summary.json"
    if summary_path.exists() and not args.overwrite:
        print(f"error: {out}: --out: holds a finished benchmark; pass --overwrite to redo it",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.overwrite and out.exists():
        for name in ("summary.json", "rows.jsonl", "results.csv", "coverage.png"):
            (out / name).unlink(missing_ok=True)
    summary = run_bench_push(args.scenes, args.seed, out, Path(args.model), args.workers,
                             tuple(args.shapes.split(",")), args.exhaustive, args.time_budget)
    if args.json:
        print(json.dumps(summary))
    else:
        for kind, q in summary["coverage"].items():
            t = summary["plan_seconds"][kind]
            print(f"{kind:>7}: coverage median {q['median']:.3f} (quartiles {q['q1']:.3f}–"
                  f"{q['q3']:.3f}, min {q['min']:.3f}, n={q['n']}); plan time median "
                  f"{t['median']:.1f} s (quartiles {t['q1']:.1f}–{t['q3']:.1f})")
        prof = summary["time_profile"]
        if prof["candidate_seconds"]:
            top = ", ".join(f"{k} {100 * v:.0f} %" for k, v in list(prof["share"].items())[:6])
            print(f"time: {prof['programs']} programs, {prof['candidate_seconds']:.0f} s in "
                  f"their callbacks and solver: {top}")
        print(f"wrote {out / 'results.csv'}, {out / 'coverage.png'}, {summary_path}")
    return 0


def _cmd_bench_functional(args: argparse.Namespace) -> int:
    import torch

    from robotplan.bench_functional import bench_functional

    torch.set_num_threads(args.threads)
    if _not_a_model(args.model):
        return EXIT_BAD_INPUT
    result = bench_functional(args.model, configurations=args.configurations,
                              repeats=args.repeats,
                              naive=not args.no_naive)
    _print_result(result, args.json)
    return 0


def _cmd_data_push(args: argparse.Namespace) -> int:
    from robotplan.learned.push_data import generate

    t0 = time.time()
    try:
        summary = generate(Path(args.out), args.scenes, args.seed, workers=args.workers,
                           shard_size=args.shard_size)
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    seconds = time.time() - t0
    summary["seconds"] = round(seconds, 1)
    if summary["new_samples"]:
        summary["samples_per_second"] = round(summary["new_samples"] / seconds, 1)
    print(json.dumps(summary))
    return 0


def _device(name: str) -> str:
    """``--device``: ``auto`` is the GPU when torch sees one, else the CPU."""
    import torch

    if name == "auto":
        return "cuda" if torch.cuda.is_available() else "cpu"
    return name


def _cmd_train_push(args: argparse.Namespace) -> int:
    import torch

    from robotplan.learned.model_card import write_model_card
    from robotplan.learned.training import TrainConfig, train

    out = Path(args.out)
    if not Path(args.data).is_dir():
        print(f"error: {args.data}: --data: no such folder", file=sys.stderr)
        return EXIT_BAD_INPUT
    ckpt = out / "checkpoint.pt"
    if args.resume and not ckpt.is_file():
        print(f"error: {ckpt}: --resume: no checkpoint to resume from", file=sys.stderr)
        return EXIT_BAD_INPUT
    if not args.resume and out.exists() and any(out.iterdir()) and not args.overwrite:
        print(f"error: {out}: --out: the folder is not empty; --resume it or pass --overwrite",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    device = _device(args.device)
    torch.set_num_threads(args.threads)
    cfg = TrainConfig(data=args.data, out=args.out, kind=args.model, steps=args.steps,
                      batch=args.batch, lr=args.lr, points=args.points, seed=args.seed,
                      scenes=args.scenes, device=device, minutes=args.minutes,
                      val_every=args.val_every, contact_share=args.contact_share,
                      near_share=args.near_share, spec={"encoder": args.encoder},
                      init_weights=args.init_weights,
                      command=" ".join(["robotplan", *sys.argv[1:]]))
    if args.resume:  # the run's settings come from its checkpoint; only the budget may change
        saved = json.loads(torch.load(ckpt, weights_only=True)["config"])
        cfg = TrainConfig(**{**saved, "steps": args.steps or saved["steps"],
                             "minutes": args.minutes, "device": device,
                             "out": args.out, "data": args.data,
                             "contact_share": args.contact_share
                             if args.contact_share is not None
                             else saved.get("contact_share")})
    last = train(cfg, resume=args.resume)
    write_model_card(out)
    print(json.dumps(last))
    return 0


def _cmd_eval_push(args: argparse.Namespace) -> int:
    import torch

    from robotplan.learned.evaluation import evaluate_push

    torch.set_num_threads(args.threads)
    device = _device(args.device)
    for path, what in ((args.model, "--model"), (args.data, "--data")):
        if not Path(path).is_dir():
            print(f"error: {path}: {what}: no such folder", file=sys.stderr)
            return EXIT_BAD_INPUT
    result = evaluate_push(args.model, args.data, scenes=args.scenes,
                           per_scene=args.per_scene or None, seed=args.seed, device=device)
    if args.pose_fit > 0:
        from robotplan.learned.pose_fit import evaluate_pose_fit

        result["pose_fit"] = evaluate_pose_fit(args.model, args.data, samples=args.pose_fit,
                                               seed=args.seed, scenes=args.scenes)
    if args.record:
        from robotplan.learned.model_card import record_heldout

        record_heldout(Path(args.model), result)
    _print_result(result, args.json)
    return 0


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="robotplan", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)

    c = sub.add_parser("check", help="validate scene files; one 'ok' line per good file")
    c.add_argument("files", nargs="+", metavar="FILE")
    c.set_defaults(run=_cmd_check)

    r = sub.add_parser("render", help="render the SDFs of scenes on X_h to PNG")
    r.add_argument("files", nargs="+", metavar="FILE")
    r.add_argument("--out", required=True, metavar="DIR", help="folder for <scene>_sdf.png")
    r.add_argument("--overwrite", action="store_true", help="replace existing pictures")
    r.set_defaults(run=_cmd_render)

    b = sub.add_parser("bench", help="benchmarks (speed targets)")
    bsub = b.add_subparsers(dest="what", required=True)
    bs = bsub.add_parser("sdf", help="render every body of a scene at T steps on X_h")
    default_scene = Path(__file__).resolve().parents[1] / "tasks" / "box_push.yaml"
    bs.add_argument("--scene", default=str(default_scene), metavar="FILE")
    bs.add_argument("--steps", type=int, default=40)
    bs.add_argument("--repeats", type=int, default=20)
    bs.add_argument("--threads", type=int, default=1)
    bs.add_argument("--dtype", choices=["float32", "float64"], default="float32")
    bs.add_argument("--json", action="store_true", help="print one JSON object")
    bs.set_defaults(run=_cmd_bench)
    bf = bsub.add_parser("functional", help="H_F and analytic functionals: speed, accuracy")
    bf.add_argument("--model", default=str(Path(__file__).resolve().parents[1] / "learned"
                                           / "push_flow"), metavar="DIR")
    bf.add_argument("--threads", type=int, default=1)
    bf.add_argument("--configurations", type=int, default=24,
                    help="realistic pushes for the accuracy check")
    bf.add_argument("--repeats", type=int, default=20)
    bf.add_argument("--no-naive", action="store_true", help="skip the slow naive timing")
    bf.add_argument("--json", action="store_true")
    bf.set_defaults(run=_cmd_bench_functional)
    bp = bsub.add_parser("push", help="plan + execute random push scenes (paper Fig. 3)")
    bp.add_argument("--scenes", type=int, default=20, help="scenes per shape type")
    bp.add_argument("--seed", type=int, default=0)
    bp.add_argument("--out", required=True, metavar="DIR",
                    help="scenes, per-scene results, CSV, box plot (continues a partial run)")
    bp.add_argument("--model", default=str(Path(__file__).resolve().parents[1] / "learned"
                                           / "push_flow"), metavar="DIR")
    bp.add_argument("--shapes", default="box,lshape",
                    help="comma-separated: box, lshape, ood (unseen footprints: triangle, "
                    "pentagon, hexagon, circle, T, cross, U, trapezoid)")
    bp.add_argument("--workers", type=int, default=2)
    bp.add_argument("--exhaustive", action="store_true", help="solve every skeleton")
    bp.add_argument("--time-budget", type=float, default=None, metavar="S",
                    help="per scene: start no program after S seconds (best so far wins)")
    bp.add_argument("--overwrite", action="store_true")
    bp.add_argument("--json", action="store_true")
    bp.set_defaults(run=_cmd_bench_push)

    default_model = str(Path(__file__).resolve().parents[1] / "learned" / "push_flow")
    so = sub.add_parser("solve", help="plan a scene, execute it in pybullet, write the result")
    so.add_argument("scene", metavar="SCENE")
    so.add_argument("--out", required=True, metavar="DIR")
    so.add_argument("--model", default=default_model, metavar="DIR")
    so.add_argument("--solver", choices=["snopt", "ipopt"], default="snopt")
    so.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    so.add_argument("--skeleton", default=None, help='one skeleton, e.g. "push@2,push@0"')
    so.add_argument("--max-pushes", type=int, default=2)
    so.add_argument("--overwrite", action="store_true")
    so.add_argument("--exhaustive", action="store_true",
                    help="solve every candidate skeleton (default: stop at the first good one)")
    so.add_argument("--time-budget", type=float, default=None, metavar="S",
                    help="start no program after S seconds; the best so far wins")
    so.set_defaults(run=_cmd_solve)

    dg = sub.add_parser("diagnose", help="a plan's push steps against one-step pybullet and "
                        "the learned model (where plan and physics part)")
    dg.add_argument("dir", metavar="DIR", help="a folder written by robotplan solve")
    dg.add_argument("scene", metavar="SCENE", help="the scene it was solved for")
    dg.add_argument("--model", default=default_model, metavar="DIR")
    dg.add_argument("--json", action="store_true")
    dg.set_defaults(run=_cmd_diagnose)

    vw = sub.add_parser("view", help="serve DIR/playback.html locally")
    vw.add_argument("dir", metavar="DIR")
    vw.add_argument("--port", type=int, default=0, help="0: any free port")
    vw.set_defaults(run=_cmd_view)

    d = sub.add_parser("data", help="generate training data")
    dsub = d.add_subparsers(dest="what", required=True)
    dp = dsub.add_parser("push", help="push data from pybullet (boxes and L-shapes)")
    dp.add_argument("--scenes", type=int, required=True)
    dp.add_argument("--seed", type=int, required=True)
    dp.add_argument("--out", required=True, metavar="DIR")
    dp.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    dp.add_argument("--shard-size", type=int, default=50)
    dp.set_defaults(run=_cmd_data_push)

    t = sub.add_parser("train", help="train learned functionals")
    tsub = t.add_subparsers(dest="what", required=True)
    tp = tsub.add_parser("push", help="train F_flow or F on push data")
    tp.add_argument("--data", required=True, metavar="DIR")
    tp.add_argument("--model", choices=["flow", "direct"], default="flow")
    tp.add_argument("--encoder", choices=["shared", "joint"], default="shared",
                    help="shared: the paper's (one encoder per SDF, shared weights); "
                         "joint: one encoder over the three SDFs stacked as channels")
    tp.add_argument("--out", required=True, metavar="DIR", help="e.g. learned/push_flow")
    tp.add_argument("--steps", type=int, default=60_000, help="total optimiser steps")
    tp.add_argument("--batch", type=int, default=32)
    tp.add_argument("--lr", type=float, default=5e-4)
    tp.add_argument("--points", type=int, default=256, help="query points per sample")
    tp.add_argument("--scenes", type=int, default=None, help="use only the first N scenes")
    tp.add_argument("--seed", type=int, default=0)
    tp.add_argument("--device", default="auto", help="cpu, cuda or auto")
    tp.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    tp.add_argument("--minutes", type=float, default=None, help="stop after this wall time")
    tp.add_argument("--val-every", type=int, default=2000)
    tp.add_argument("--init-weights", default=None, metavar="FILE",
                    help="start from these weights (e.g. a previous run's weights.pt)")
    tp.add_argument("--contact-share", type=float, default=None,
                    help="balanced batches with this share of contact samples")
    tp.add_argument("--near-share", type=float, default=0.25,
                    help="share of the query points drawn within 10 cm of the object (the "
                         "rest uniform on the table); more resolves the object's turning")
    tp.add_argument("--resume", action="store_true", help="continue from checkpoint.pt")
    tp.add_argument("--overwrite", action="store_true", help="start over in a used folder")
    tp.set_defaults(run=_cmd_train_push)

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
    ep.add_argument("--json", action="store_true")
    ep.add_argument("--record", action="store_true",
                    help="store the result in the model's metrics.json and model card")
    ep.set_defaults(run=_cmd_eval_push)
    return p


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    keep_freed_memory()
    try:
        return args.run(args)
    except SceneError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
