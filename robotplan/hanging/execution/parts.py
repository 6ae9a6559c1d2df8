"""The procedural mug and hook as convex primitives (boxes, cylinders, capsules) in their
frames, built from the same parameters as their SDFs (:mod:`robotplan.sdf.mug_hook`): the
cup's wall a ring of boxes, its bottom a cylinder, the handle and the hook's arm capsules
along their centre lines, the post a cylinder. Cylinders and capsules lie along their
part's z axis; ``length`` is a cylinder's height and a capsule's length between its caps'
centres."""

from __future__ import annotations

import itertools
import math

import numpy as np

from robotplan.hanging.execution.drop import HANG_PHYSICS
from robotplan.sdf.mug_hook import Hook, Mug

__all__ = ["hook_parts", "mug_parts", "part_volume"]


def part_volume(part: dict) -> float:
    """The volume of one part (m³)."""
    if part["kind"] == "box":
        return 8.0 * float(np.prod(part["half"]))
    r, length = part["radius"], part["length"]
    cap = 4.0 / 3.0 * r if part["kind"] == "capsule" else 0.0
    return math.pi * r * r * (length + cap)


def _capsules(points: np.ndarray, radius: float) -> list[dict]:
    """Capsule parts along the segments of a polyline in a frame's xz-plane."""
    parts = []
    for a, b in itertools.pairwise(points):
        d = b - a
        length = float(np.linalg.norm(d))
        tilt = math.atan2(d[0], d[2])  # about y, taking z onto the segment
        parts.append(dict(kind="capsule", radius=radius, length=length, pos=(a + b) / 2,
                          quat=(math.cos(tilt / 2), 0.0, math.sin(tilt / 2), 0.0)))
    return parts


def mug_parts(mug: Mug, wall_boxes: int = HANG_PHYSICS.wall_boxes) -> list[dict]:
    """The mug as convex primitives in its frame (box half extents, cylinder and capsule
    radius and length, pose)."""
    r, h, w = mug.radius, mug.height, mug.wall
    parts = [dict(kind="cylinder", radius=r, length=w, pos=np.array([0.0, 0.0, w / 2]),
                  quat=(1.0, 0.0, 0.0, 0.0))]
    half_width = (r - w / 2) * math.tan(math.pi / wall_boxes) + w / 2
    for k in range(wall_boxes):
        a = 2 * math.pi * k / wall_boxes
        pos = np.array([(r - w / 2) * math.cos(a), (r - w / 2) * math.sin(a), h / 2])
        parts.append(dict(kind="box", half=(w / 2, half_width, h / 2), pos=pos,
                          quat=(math.cos(a / 2), 0.0, 0.0, math.sin(a / 2))))
    return parts + _capsules(mug.handle_points(), mug.handle_radius)


def hook_parts(hook: Hook) -> list[dict]:
    """The hook as convex primitives in its frame."""
    post = dict(kind="cylinder", radius=hook.post_radius, length=hook.post_height,
                pos=np.array([0.0, 0.0, hook.post_height / 2]), quat=(1.0, 0.0, 0.0, 0.0))
    return [post, *_capsules(hook.arm_points(), hook.rod_radius)]
