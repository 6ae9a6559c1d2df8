"""A Panda and an iiwa: the Panda pushes the box, then the iiwa touches it.

``python tasks/panda_iiwa_touch.py [--fast] [--out DIR]``
"""

from task_cli import HERE, arguments, out_dir, run

import robotplan

FAST_SKELETON = "left:push@2,right:touch@1"

if __name__ == "__main__":
    args = arguments(__doc__.splitlines()[0])
    scene = robotplan.load_scene(HERE / "panda_iiwa_touch.yaml")
    run(scene, out_dir(args, __file__), args.fast, FAST_SKELETON, open_loop=args.open_loop)
