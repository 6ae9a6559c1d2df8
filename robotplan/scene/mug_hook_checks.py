"""Checks of a hang scene: one mug object, one hook obstacle, the goal naming them, both on
the table inside the workspace and apart at the start."""

from __future__ import annotations

import math

import numpy as np

from robotplan.scene.meshes import MeshSolid
from robotplan.scene.reader import SchemaError, show
from robotplan.scene.schema import HangGoal, HookShape, MugShape, Scene

__all__ = ["check_hang_scene"]


def _is(shape, procedural: type, role: str) -> bool:
    return isinstance(shape, procedural) or (isinstance(shape, MeshSolid) and shape.role == role)


def _mug_sizes(shape) -> tuple[float, float]:
    """The mug's radius on the table and how far its handle reaches beyond it (m)."""
    if isinstance(shape, MeshSolid):
        vertices = shape.solid().mesh.vertices
        return float(np.linalg.norm(vertices[:, :2], axis=1).max()), 0.0
    return shape.radius, shape.handle_reach + 2 * shape.handle_radius


def check_hang_scene(scene: Scene) -> None:
    """Raises SchemaError naming the field."""
    goal = scene.goal
    assert isinstance(goal, HangGoal)
    if len(scene.objects) != 1 or not _is(scene.objects[0].shape, MugShape, "mug"):
        raise SchemaError("objects", "a hang scene has one object, a mug (shape type mug or "
                          "mesh)")
    if len(scene.obstacles) != 1 or not _is(scene.obstacles[0].shape, HookShape, "hook"):
        raise SchemaError("obstacles", "a hang scene has one obstacle, a hook (shape type hook "
                          "or mesh)")
    if scene.pushers or scene.robots:
        raise SchemaError("pushers" if scene.pushers else "robots",
                          "a hang scene places the mug itself; it takes no pushers or robots")
    mug, hook = scene.objects[0], scene.obstacles[0]
    if goal.object != mug.name:
        raise SchemaError("goal.object", f"{show(goal.object)} is not the mug ({show(mug.name)})")
    if goal.on != hook.name:
        raise SchemaError("goal.on", f"{show(goal.on)} is not the hook ({show(hook.name)})")
    x0, x1, y0, y1 = scene.workspace.bounds
    radius, handle = _mug_sizes(mug.shape)
    post = hook.shape.solid().post_radius if isinstance(hook.shape, MeshSolid) \
        else hook.shape.post_radius
    for group, body, reach in (("objects[0]", mug, radius), ("obstacles[0]", hook, post)):
        x, y, _ = body.pose
        if not (x0 + reach <= x <= x1 - reach and y0 + reach <= y <= y1 - reach):
            raise SchemaError(f"{group}.pose", "must lie inside the workspace")
    gap = math.dist(mug.pose[:2], hook.pose[:2]) - radius - post
    if gap < handle:
        raise SchemaError("objects[0].pose", f"the mug stands {gap * 100:.3g} cm from the "
                          f"hook's post; keep at least {handle * 100:.3g} cm (its handle) apart")
    if isinstance(mug.shape, MeshSolid) and gap < 0:
        raise SchemaError("objects[0].pose", "the mug stands on the hook's post")
