"""The solids of a hang scene (one mug object, one hook obstacle, as the scene file's checks
ensure: :mod:`robotplan.scene.mug_hook_checks`)."""

from __future__ import annotations

from robotplan.scene.schema import Scene

__all__ = ["hang_parts"]


def hang_parts(scene: Scene):
    """The mug and hook solids, and their start poses on the table (x, y, yaw)."""
    mug, hook = scene.objects[0], scene.obstacles[0]
    return mug.shape.solid(), hook.shape.solid(), mug.pose, hook.pose
