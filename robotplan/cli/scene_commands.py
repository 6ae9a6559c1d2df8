"""Commands on scenes and plans: ``check``, ``render``, ``solve``, ``diagnose``, ``view``."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from robotplan.cli.common import (
    EXIT_BAD_INPUT,
    SOLVE_EXIT,
    load_footprint_scene,
    loop_overrides,
    model_folder,
    not_a_model,
    perturbation,
    print_result,
    program_overrides,
    simulators,
)
from robotplan.hanging.cli.commands import solve_hang_scene
from robotplan.scene import SceneError, load_scene
from robotplan.scene.task import UnsupportedScene, family_of, make_task

__all__ = ["cmd_check", "cmd_diagnose", "cmd_render", "cmd_solve", "cmd_view"]


def cmd_check(args: argparse.Namespace) -> int:
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


def cmd_render(args: argparse.Namespace) -> int:
    from robotplan.hanging.api.planner import write_hang_scene_picture
    from robotplan.viz.render import render_scene_sdf

    # refuse bad input before writing anything
    scenes = [load_scene(f) for f in args.files]
    out = Path(args.out)
    targets = [out / f"{Path(f).stem}_{'scene' if family_of(s) == 'hang' else 'sdf'}.png"
               for f, s in zip(args.files, scenes, strict=True)]
    if not args.overwrite:
        existing = [str(t) for t in targets if t.exists()]
        if existing:
            print(f"error: {existing[0]}: exists; pass --overwrite to replace it",
                  file=sys.stderr)
            return EXIT_BAD_INPUT
    for scene, target in zip(scenes, targets, strict=False):
        if family_of(scene) == "hang":  # 3D shapes: a picture of the scene
            write_hang_scene_picture(scene, target)
        else:
            render_scene_sdf(scene, target)
        print(f"wrote {target}")
    return 0


def cmd_solve(args: argparse.Namespace) -> int:
    from robotplan.api import solve

    scene = load_scene(args.scene)
    try:
        task = make_task(scene)
    except UnsupportedScene as err:
        print(f"error: {args.scene}: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    loop, program = loop_overrides(args), program_overrides(args)
    sims = simulators(args.sim)
    if loop is None or program is None or sims is None:
        return EXIT_BAD_INPUT
    if len(sims) > 1:
        print("error: --sim: solve executes in one simulator", file=sys.stderr)
        return EXIT_BAD_INPUT
    out = Path(args.out)
    if out.exists() and any(out.iterdir()) and not args.overwrite:
        print(f"error: {out}: --out: the folder is not empty; pass --overwrite to replace "
              "its result", file=sys.stderr)
        return EXIT_BAD_INPUT
    if task.family == "hang":
        return solve_hang_scene(task, out, args.model, args.open_loop, sims[0])
    args.model = model_folder(args)
    if not_a_model(args.model):
        return EXIT_BAD_INPUT
    out.mkdir(parents=True, exist_ok=True)
    try:
        doc = solve(task, out, args.model, solver=args.solver, workers=args.workers,
                    skeleton=args.skeleton, max_pushes=args.max_pushes,
                    exhaustive=args.exhaustive, time_budget=args.time_budget,
                    mode="open_loop" if args.open_loop else "closed_loop",
                    perturb=perturbation(args.perturb), loop=loop, program=program,
                    rehearse_plan=not args.no_rehearse, sim=sims[0])
    except ValueError as err:  # a bad --skeleton
        print(f"error: --skeleton: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    ex = doc.get("execution") or {}
    loop = (f" ({ex['mode'].replace('_', ' ')}, {len(ex['replans'])} re-plans)" if ex else "")
    plan = "" if doc["status"] == doc["plan_status"] else f" (plan: {doc['plan_status']})"
    violation = "none" if doc["violation"] is None else f"{doc['violation']:.3g}"
    print(f"{doc['status']}{plan}: violation {violation}, coverage in {sims[0]} "
          f"{ex.get('coverage')}{loop}, plan {doc['plan_seconds']} s; "
          f"wrote {out / 'result.json'}"
          + (f" and {out / 'playback.html'}" if "playback" in doc else ""))
    return SOLVE_EXIT[doc["status"]]


def cmd_diagnose(args: argparse.Namespace) -> int:
    from robotplan.pushing.training.diagnose import check_steps, summarize, table, to_json

    path = Path(args.dir) / "result.json"
    if not path.is_file():
        print(f"error: {path}: no result.json (run robotplan solve first)", file=sys.stderr)
        return EXIT_BAD_INPUT
    if not_a_model(args.model):
        return EXIT_BAD_INPUT
    scene = load_footprint_scene(args.scene, "diagnose")
    try:
        checks = check_steps(make_task(scene), json.loads(path.read_text()), args.model)
    except (ValueError, KeyError, StopIteration) as err:
        print(f"error: {path}: {err!s} (is {args.scene} the scene it was solved for?)",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.json:
        print(to_json(checks))
        return 0
    print(table(checks))
    print_result(summarize(checks), False)
    return 0


def cmd_view(args: argparse.Namespace) -> int:
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
