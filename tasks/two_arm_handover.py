"""Two iiwa arms hand the box over: the left pushes, then the right.

``python tasks/two_arm_handover.py [--fast] [--out DIR]``
"""

from task_cli import HERE, arguments, out_dir, run

import robotplan

FAST_SKELETON = "left:push@0,right:push@0"

if __name__ == "__main__":
    args = arguments(__doc__.splitlines()[0])
    scene = robotplan.load_scene(HERE / "two_arm_handover.yaml")
    run(scene, out_dir(args, __file__), args.fast, FAST_SKELETON, open_loop=args.open_loop)
