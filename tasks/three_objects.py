"""The pusher may touch red only; red pushes blue into the goal (paper Fig. 9).

``python tasks/three_objects.py [--fast] [--out DIR]``
"""

from task_cli import HERE, arguments, out_dir, run

import robotplan

FAST_SKELETON = "push@1,push@0>blue,push@0>blue"

if __name__ == "__main__":
    args = arguments(__doc__.splitlines()[0])
    scene = robotplan.load_scene(HERE / "three_objects.yaml")
    run(scene, out_dir(args, __file__), args.fast, FAST_SKELETON, open_loop=args.open_loop)
