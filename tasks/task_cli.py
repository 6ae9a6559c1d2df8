"""What every task script shares: its command line and the plan → execute → playback run.

A task script loads its scene, may change it in code, and calls :func:`run` with the
scene and the skeleton of its fast variant (``--fast``: that one skeleton, one worker, the
variant the test suite runs; without it the full skeleton search).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import robotplan

HERE = Path(__file__).resolve().parent


def arguments(description: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--out", default=None, metavar="DIR",
                        help="where playback.html goes (default: runs/<script name>)")
    parser.add_argument("--fast", action="store_true",
                        help="plan one given skeleton instead of searching")
    parser.add_argument("--open-loop", action="store_true",
                        help="execute without re-planning, the plan rehearsed in F_q first "
                        "where it can be (default: closed loop, re-planning from the "
                        "observed scene)")
    return parser.parse_args()


def run(scene: robotplan.Scene, out: Path, fast: bool, fast_skeleton: str,
        label: str | None = None, open_loop: bool = False) -> float | None:
    """Plan (``fast``: ``fast_skeleton`` only), execute in pybullet (closed loop unless
    ``open_loop``: then the plan rehearsed in F_q first, as ``robotplan solve --open-loop``
    does), write ``out/playback.html``; print one line and return the coverage
    (touch goals: None)."""
    planned = robotplan.plan(scene, skeleton=fast_skeleton if fast else None,
                             workers=1 if fast else 2, progress=not fast, quiet=fast,
                             rehearse_plan=open_loop)
    name = label or scene.name
    if planned.best is None:
        print(f"{name}: no plan")
        return None
    executed = robotplan.execute(planned, mode="open_loop" if open_loop else "closed_loop")
    out.mkdir(parents=True, exist_ok=True)
    robotplan.write_playback(planned, executed, out / "playback.html")
    print(f"{name}: {'solved' if planned.solved else 'not solved'}, violation "
          f"{planned.best.violation:.3g}, coverage in pybullet {executed.coverage}, touch "
          f"distance {executed.touch_distance} ({executed.mode.replace('_', ' ')}, "
          f"{len(executed.replans)} re-plans); {out / 'playback.html'}")
    return executed.coverage


def out_dir(args: argparse.Namespace, script: str) -> Path:
    return Path(args.out) if args.out else Path("runs") / Path(script).stem


def run_hang(scene_file: Path, args: argparse.Namespace, script: str,
             fast_restarts: int = 3) -> None:
    """Solve the hang scene in ``scene_file`` (``--fast``: at most ``fast_restarts``
    optimisations; ``--open-loop``: drop the first pose found only), write its playback and
    picture, print one line."""
    from robotplan.hanging.api.planner import solve_hang
    from robotplan.scene.task import load_task

    task = load_task(scene_file)
    out = out_dir(args, script)
    doc = solve_hang(task, out, restarts=fast_restarts if args.fast else None,
                     mode="open_loop" if args.open_loop else "closed_loop")
    ex = doc["execution"]
    outcome = ("hangs" + (" in place" if ex["in_place"] else "")) if ex["hung"] else "falls"
    before = f" (it fell from {len(ex['replans'])} poses before)" if ex["replans"] else ""
    print(f"{task.scene.name}: {'solved' if doc['status'] == 'solved' else 'not solved'}, H_hang "
          f"{doc['h_hang']:.3g}, H_coll {doc['h_coll_cm3']:.3g} cm³ after {doc['restarts']} "
          f"optimisations ({doc['plan_seconds']} s); in pybullet the mug {outcome}{before}; "
          f"{out / 'playback.html'}, {out / doc['picture']}")
