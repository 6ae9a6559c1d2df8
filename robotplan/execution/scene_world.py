"""A whole scene in one simulated world (``physics.simulator``), driven by planned actuation
and observed as a perception system would see it.

The actuation of a plan is one array of states per actor, ``(N+1, d)``: the free pusher's
positions ``(x, y)`` or each arm's joint angles. A planned step runs ``n`` simulation steps
that move every actor's target linearly from one state to the next; the world records
whether an object touched an obstacle and which objects a free pusher touched that it
may not (``touches``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from robotplan.execution.physics import PHYSICS, Physics, push_world
from robotplan.scene import Scene
from robotplan.scene.task import PushTask

__all__ = ["OBSTACLE_GAP", "Observation", "SceneWorld", "actuation", "obstacle_bodies"]

OBSTACLE_GAP = 0.001  # m: closer than this counts as the object touching an obstacle


def obstacle_bodies(scene: Scene) -> list:
    return [(o.shape, o.height, o.pose) for o in scene.obstacles]


def actuation(task: PushTask, q_pusher: np.ndarray, q_joints: dict[str, np.ndarray]
              ) -> dict[str, np.ndarray]:
    """The states the actors are driven along: the arms' joints when arms push, else the
    free pusher's positions ``(N+1, 2)``."""
    if task.arms:
        return {name: np.asarray(q, dtype=float) for name, q in q_joints.items()}
    return {task.actors[0]: np.asarray(q_pusher, dtype=float)[:, :2]}


@dataclass
class Observation:
    """The world's state after a step: every movable object's planar pose ``(x, y, yaw)``,
    the free pusher's position ``(x, y)``, each arm's tip centre ``(x, y, z)`` and joints."""

    poses: dict[str, np.ndarray]
    pusher: np.ndarray | None = None
    tips: dict[str, np.ndarray] = field(default_factory=dict)
    joints: dict[str, np.ndarray] = field(default_factory=dict)


class SceneWorld:
    """``task.scene`` in the world of ``physics.simulator``
    (:class:`~robotplan.execution.physics.PushSimulator`): the task's object first, the other
    objects movable, the obstacles fixed, and either the one free pusher or every arm."""

    def __init__(self, task: PushTask, physics: Physics = PHYSICS) -> None:
        scene, obj = task.scene, task.obj
        self.scene, self.obj = scene, obj
        self.world = world = push_world(physics)
        spec = next(o for o in scene.objects if o.name == obj)
        self.others = [o for o in scene.objects if o.name != obj]
        movable = [(scene.bodies[o.name].shape, o.height, scene.bodies[o.name].pose)
                   for o in self.others]
        self.pusher = task.pusher
        radius = self.pusher.radius if self.pusher is not None else None
        xy = self.pusher.position if self.pusher is not None else (0.0, 0.0)
        world.reset(scene.bodies[obj].shape, spec.height, scene.bodies[obj].pose, radius, xy,
                    obstacle_bodies(scene), movable)
        self.arms = {r.name: world.add_arm(r) for r in scene.robots}
        allowed = self.pusher.touches if self.pusher is not None else None
        self._watch = [i for i, o in enumerate(self.others)
                       if allowed is not None and o.name not in allowed]
        self.obstacle_contact = False
        self.forbidden: set[str] = set()

    def __enter__(self) -> SceneWorld:
        return self

    def __exit__(self, *exc: object) -> None:
        self.world.close()

    def run_step(self, start: dict[str, np.ndarray], end: dict[str, np.ndarray],
                 substeps: int) -> None:
        """One planned step: the actors' targets move from ``start`` to ``end`` (actor →
        state) over ``substeps`` simulation steps."""
        world = self.world
        for s in range(1, substeps + 1):
            u = s / substeps
            if self.pusher is not None:
                a, b = start[self.pusher.name], end[self.pusher.name]
                world.step(tuple(a + (b - a) * u))
            else:
                for name, arm in self.arms.items():
                    arm.drive(start[name] + (end[name] - start[name]) * u)
                world.advance()
            self.obstacle_contact = (self.obstacle_contact
                                     or world.touches_obstacle(OBSTACLE_GAP))
            self.forbidden.update(self.others[i].name for i in self._watch
                                  if world.pusher_touches_other(i))

    def observe(self) -> Observation:
        """The true state of the world (see :func:`robotplan.pushing.execution.perturb.noisy` for
        what a perception system would deliver)."""
        world = self.world
        poses = {self.obj: world.object_pose()[0],
                 **{o.name: p for o, p in zip(self.others, world.other_poses(), strict=True)}}
        return Observation(
            poses, world.pusher_position() if self.pusher is not None else None,
            {name: arm.tip_position() for name, arm in self.arms.items()},
            {name: arm.joint_angles() for name, arm in self.arms.items()})
