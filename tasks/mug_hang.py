"""A mug hung on a hook (paper §7.1): H_hang and H_coll optimised over the mug's pose,
restarted from random poses, the pose then checked by dropping the mug in pybullet; closed
loop (the default) goes on searching while the mug falls from the poses found.

``python tasks/mug_hang.py [--fast] [--open-loop] [--out DIR]`` (``--fast``: at most 3
optimisations; ``--open-loop``: drop the first pose found only, the paper's protocol)
"""

from task_cli import HERE, arguments, out_dir

from robotplan.hanging.api.planner import solve_hang
from robotplan.scene.task import load_task

FAST_RESTARTS = 3

if __name__ == "__main__":
    args = arguments(__doc__.splitlines()[0])
    task = load_task(HERE / "mug_hang.yaml")
    out = out_dir(args, __file__)
    doc = solve_hang(task, out, restarts=FAST_RESTARTS if args.fast else None,
                     mode="open_loop" if args.open_loop else "closed_loop")
    ex = doc["execution"]
    outcome = ("hangs" + (" in place" if ex["in_place"] else "")) if ex["hung"] else "falls"
    before = f" (it fell from {len(ex['replans'])} poses before)" if ex["replans"] else ""
    print(f"{task.scene.name}: {'solved' if doc['status'] == 'solved' else 'not solved'}, H_hang "
          f"{doc['h_hang']:.3g}, H_coll {doc['h_coll_cm3']:.3g} cm³ after {doc['restarts']} "
          f"optimisations ({doc['plan_seconds']} s); in pybullet the mug {outcome}{before}; "
          f"{out / 'playback.html'}, {out / doc['picture']}")
