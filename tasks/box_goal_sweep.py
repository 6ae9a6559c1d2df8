"""A sweep over goal poses: the box_push scene with its goal region moved in code to three
places along the table, each planned, executed and played back.

``python tasks/box_goal_sweep.py [--fast] [--out DIR]``
"""

from dataclasses import replace

from task_cli import HERE, arguments, out_dir, run

import robotplan

FAST_SKELETON = "push@0"
GOAL_OFFSETS = ((0.0, 0.0), (0.0, 0.08), (0.0, -0.08))  # m, added to the file's goal pose

if __name__ == "__main__":
    args = arguments(__doc__.splitlines()[0])
    scene = robotplan.load_scene(HERE / "box_push.yaml")
    region = scene.goal.region
    offsets = GOAL_OFFSETS[:1] if args.fast else GOAL_OFFSETS
    for i, (dx, dy) in enumerate(offsets):
        x, y, yaw = region.pose
        moved = replace(scene, goal=replace(scene.goal, region=replace(
            region, pose=(x + dx, y + dy, yaw))))
        run(moved, out_dir(args, __file__) / f"goal_{i}", args.fast, FAST_SKELETON,
            label=f"goal at ({x + dx:+.2f}, {y + dy:+.2f})", open_loop=args.open_loop)
