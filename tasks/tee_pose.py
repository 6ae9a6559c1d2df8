"""A T-shaped block pushed to a target pose, moved and turned (Push-T's task).

``python tasks/tee_pose.py [--fast] [--out DIR]``
"""

from task_cli import HERE, arguments, out_dir, run

import robotplan

FAST_SKELETON = "push@1,push@1"

if __name__ == "__main__":
    args = arguments(__doc__.splitlines()[0])
    scene = robotplan.load_scene(HERE / "tee_pose.yaml")
    run(scene, out_dir(args, __file__), args.fast, FAST_SKELETON, open_loop=args.open_loop)
