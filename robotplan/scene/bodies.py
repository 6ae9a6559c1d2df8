"""Bodies of a scene: every object, obstacle, pusher and robot tip as a posed 2D SDF.

A body's SDF in the table plane is its footprint's SDF moved by its planar pose:
``T(q)[φ](x) = φ(R(q)ᵀ (x − r(q)))`` (paper §4). Pushers and robot tips are discs of their
sphere's radius (the sphere's cross-section at its centre height).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np
import torch
from torch import Tensor

from robotplan.geometry.transforms import planar_to_body
from robotplan.scene.robots import load_robot_model
from robotplan.sdf import Circle, Shape2D

if TYPE_CHECKING:
    from robotplan.scene.schema import PoseGoal, RegionGoal, Scene

__all__ = ["Body", "region_body", "scene_bodies"]

Role = Literal["object", "obstacle", "pusher", "robot", "region"]


@dataclass(frozen=True)
class Body:
    """A footprint ``shape`` at the start pose ``X_WB = (x, y, yaw)``.

    ``bottom``/``top``: the body's vertical extent above the table (objects: 0 to their
    extrusion height; spheres: centre height ∓ radius).
    """

    name: str
    role: Role
    shape: Shape2D
    pose: tuple[float, float, float]
    bottom: float
    top: float

    def sdf(self, points_W: Tensor, X_WB: Tensor | None = None) -> Tensor:
        """φ of the body at table-frame points.

        Args:
            points_W: ``(..., N, 2)`` points (any float dtype).
            X_WB: ``(..., 3)`` poses ``(x, y, yaw)`` or ``(..., 2)`` positions; default the
                start pose. Leading dimensions broadcast with those of the points, so
                ``points (N, 2)`` with ``X_WB (T, 3)`` gives ``(T, N)``.
        Returns:
            ``(..., N)`` signed distances, differentiable in points and pose.
        """
        if X_WB is None:
            X_WB = torch.tensor(self.pose, dtype=points_W.dtype, device=points_W.device)
        return self.shape.sdf(planar_to_body(points_W, X_WB))

    def outline_world(self, X_WB: tuple[float, ...] | np.ndarray | None = None) -> np.ndarray:
        """Boundary polygon ``(V, 2)`` in the table frame at ``X_WB`` (default: start pose)."""
        x, y, yaw = ((*tuple(X_WB), 0.0))[:3] if X_WB is not None else self.pose
        c, s = np.cos(yaw), np.sin(yaw)
        local = self.shape.outline()
        return local @ np.array([[c, s], [-s, c]]) + np.array([x, y])

    @property
    def area(self) -> float:
        return self.shape.area


def scene_bodies(scene: Scene) -> dict[str, Body]:
    """All bodies of ``scene`` by name (objects, obstacles, pushers, robot tips)."""
    bodies: dict[str, Body] = {}
    for spec in scene.objects:
        bodies[spec.name] = Body(spec.name, "object", spec.shape, spec.pose, 0.0, spec.height)
    for spec in scene.obstacles:
        bodies[spec.name] = Body(spec.name, "obstacle", spec.shape, spec.pose, 0.0, spec.height)
    for p in scene.pushers:
        bodies[p.name] = Body(p.name, "pusher", Circle(p.radius), (*p.position, 0.0),
                              0.0, 2 * p.radius)
    for r in scene.robots:
        model = load_robot_model(r.model)
        tip = model.tip_position(r.q0 if r.q0 is not None else model.home, r.base)
        bodies[r.name] = Body(r.name, "robot", Circle(r.tip_radius),
                              (float(tip[0]), float(tip[1]), 0.0),
                              float(tip[2]) - r.tip_radius, float(tip[2]) + r.tip_radius)
    return bodies


def region_body(goal: RegionGoal | PoseGoal, objects: list | None = None) -> Body:
    """The goal region of a region goal, or of a pose goal the object's own footprint at
    the goal pose, as a (flat) body named ``goal``."""
    if goal.type == "pose":
        shape = next(o.shape for o in objects if o.name == goal.object)
        return Body("goal", "region", shape, tuple(goal.pose), 0.0, 0.0)
    return Body("goal", "region", goal.region.shape, goal.region.pose, 0.0, 0.0)
