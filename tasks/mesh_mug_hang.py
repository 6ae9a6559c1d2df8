"""A mug hung on a hook, both given as mesh files: the handle's opening and the hook's arm
found from their geometry, H_hang reading their SDFs (cached lattices of the meshes), the
pose checked by dropping the meshes in pybullet; closed loop as tasks/mug_hang.py.

``python tasks/mesh_mug_hang.py [--fast] [--open-loop] [--out DIR]`` (``--fast``: at most 3
optimisations; ``--open-loop``: drop the first pose found only, the paper's protocol)
"""

from task_cli import HERE, arguments, out_dir

from robotplan.hanging.api.planner import solve_hang
from robotplan.scene.task import load_task

FAST_RESTARTS = 3

if __name__ == "__main__":
    args = arguments(__doc__.splitlines()[0])
    task = load_task(HERE / "mesh_mug_hang.yaml")
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
