"""Open-loop execution of a push plan in pybullet (paper §7.2.3): the pusher follows the
planned positions with ``keep_every`` (20) linear interpolation steps between consecutive
ones, in the same world as the push data; the result comes from the simulator alone."""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from robotplan.coverage import coverage
from robotplan.scene import Scene
from robotplan.sim import PHYSICS, Physics, PushWorld

__all__ = ["Execution", "execute_push"]


@dataclass
class Execution:
    object_poses: np.ndarray  # (N+1, 3) at the planned steps
    pusher_positions: np.ndarray  # (N+1, 2)
    final_pose: np.ndarray  # (3,)
    coverage: float | None
    touch_distance: float | None


def execute_push(scene: Scene, obj: str, pusher: str, q_pusher: np.ndarray,
                 physics: Physics = PHYSICS) -> Execution:
    """Run the planned pusher positions ``q_pusher (N+1, 2)`` open loop."""
    body, tool = scene.bodies[obj], scene.bodies[pusher]
    spec = next(o for o in scene.objects if o.name == obj)
    with PushWorld(physics) as world:
        world.reset(body.shape, spec.height, body.pose, tool.shape.radius, tool.pose[:2])
        poses = [world.object_pose()[0]]
        pushers = [world.pusher_position()]
        for a, b in itertools.pairwise(q_pusher):
            for s in range(1, physics.keep_every + 1):
                world.step(tuple(a + (b - a) * s / physics.keep_every))
            poses.append(world.object_pose()[0])
            pushers.append(world.pusher_position())
    final = poses[-1]
    cov = coverage(body, final, scene.goal_region) if scene.goal_region is not None else None
    touch = None
    if scene.goal_region is None:
        import torch

        gap = body.sdf(torch.tensor([pushers[-1]]), torch.tensor(final))
        touch = max(0.0, float(gap[0]) - tool.shape.radius)
    return Execution(np.array(poses), np.array(pushers), final, cov, touch)
