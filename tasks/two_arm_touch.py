"""Two iiwa arms: the box is pushed, then the right arm touches it.

``python tasks/two_arm_touch.py [--fast] [--out DIR]``
"""

from task_cli import HERE, arguments, out_dir, run

import robotplan

FAST_SKELETON = "left:push@0,right:touch@0"

if __name__ == "__main__":
    args = arguments(__doc__.splitlines()[0])
    scene = robotplan.load_scene(HERE / "two_arm_touch.yaml")
    run(scene, out_dir(args, __file__), args.fast, FAST_SKELETON, open_loop=args.open_loop)
