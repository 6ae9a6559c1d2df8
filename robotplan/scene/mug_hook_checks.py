"""Checks of a hang scene: one mug object, one hook obstacle, the goal naming them, both on
the table inside the workspace and apart at the start."""

from __future__ import annotations

import math

from robotplan.scene.reader import SchemaError, show
from robotplan.scene.schema import HangGoal, HookShape, MugShape, Scene

__all__ = ["check_hang_scene"]


def check_hang_scene(scene: Scene) -> None:
    """Raises SchemaError naming the field."""
    goal = scene.goal
    assert isinstance(goal, HangGoal)
    if len(scene.objects) != 1 or not isinstance(scene.objects[0].shape, MugShape):
        raise SchemaError("objects", "a hang scene has one object, a mug (shape type mug)")
    if len(scene.obstacles) != 1 or not isinstance(scene.obstacles[0].shape, HookShape):
        raise SchemaError("obstacles", "a hang scene has one obstacle, a hook (shape type hook)")
    if scene.pushers or scene.robots:
        raise SchemaError("pushers" if scene.pushers else "robots",
                          "a hang scene places the mug itself; it takes no pushers or robots")
    mug, hook = scene.objects[0], scene.obstacles[0]
    if goal.object != mug.name:
        raise SchemaError("goal.object", f"{show(goal.object)} is not the mug ({show(mug.name)})")
    if goal.on != hook.name:
        raise SchemaError("goal.on", f"{show(goal.on)} is not the hook ({show(hook.name)})")
    x0, x1, y0, y1 = scene.workspace.bounds
    for group, body, reach in (("objects[0]", mug, mug.shape.radius),
                               ("obstacles[0]", hook, hook.shape.post_radius)):
        x, y, _ = body.pose
        if not (x0 + reach <= x <= x1 - reach and y0 + reach <= y <= y1 - reach):
            raise SchemaError(f"{group}.pose", "must lie inside the workspace")
    gap = math.dist(mug.pose[:2], hook.pose[:2]) - mug.shape.radius - hook.shape.post_radius
    handle = mug.shape.handle_reach + 2 * mug.shape.handle_radius
    if gap < handle:
        raise SchemaError("objects[0].pose", f"the mug stands {gap * 100:.3g} cm from the "
                          f"hook's post; keep at least {handle * 100:.3g} cm (its handle) apart")
