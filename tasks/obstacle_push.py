"""A box pushed past a wall to its goal (routes around the wall when straight pushes fail).

``python tasks/obstacle_push.py [--fast] [--out DIR]``
"""

from task_cli import HERE, arguments, out_dir, run

import robotplan

FAST_SKELETON = "push@0"

if __name__ == "__main__":
    args = arguments(__doc__.splitlines()[0])
    scene = robotplan.load_scene(HERE / "obstacle_push.yaml")
    run(scene, out_dir(args, __file__), args.fast, FAST_SKELETON, open_loop=args.open_loop)
