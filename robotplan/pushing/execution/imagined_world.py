"""A scene whose object moves as the learned rigid-motion model F_q predicts: the world a
plan is rehearsed in before it runs open loop (:mod:`robotplan.pushing.execution.rehearsal`).

It has :class:`~robotplan.execution.scene_world.SceneWorld`'s interface for one free
pusher and one object: a planned step of ``n`` simulation steps is ``n / keep_every`` steps
of F_q (each the pusher's straight move over one kept step of the push data, the step F_q
was trained on), and the pusher reaches its targets exactly. A step where the pusher stays
further than ``CONTACT_GAP`` from the object at both ends and in between leaves the object
where it is: without contact a quasi-static object does not move, and F_q's small motion
of untouched objects would add up over a long reach.
"""

from __future__ import annotations

import numpy as np
import torch

from robotplan.execution.physics import PHYSICS, Physics
from robotplan.execution.scene_world import Observation
from robotplan.geometry.transforms import planar_to_world
from robotplan.pushing.functionals.rigid_dynamics import RigidDynamics
from robotplan.pushing.models.rigid import RigidMotion, moved_pose
from robotplan.scene.task import PushTask

__all__ = ["CONTACT_GAP", "ImaginedWorld", "rigid_step"]

CONTACT_GAP = 0.01  # m between the pusher's rim and the object below which F_q is asked


def rigid_step(pose: np.ndarray, delta: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """The pose ``X_WB (3,)`` after F_q's step ``delta = (Δx, Δy, Δα)``: T(Δq) about the
    pivot (the footprint's centroid ``centre`` in the body frame) applied to the body's
    origin, the heading turned by Δα."""
    X = torch.as_tensor(pose, dtype=torch.float64)
    d = torch.as_tensor(delta, dtype=torch.float64)[None]
    pivot = planar_to_world(torch.as_tensor(centre, dtype=torch.float64)[None], X)
    return moved_pose(X[None], pivot, d)[0].numpy()


class ImaginedWorld:
    """``task.scene`` with its one object driven by F_q (see the module docstring)."""

    def __init__(self, task: PushTask, model: RigidMotion, physics: Physics = PHYSICS) -> None:
        if not task.single:
            raise ValueError("a rehearsal needs one free pusher and one object")
        scene, obj = task.scene, task.obj
        self.scene, self.obj, self.physics = scene, obj, physics
        self.pusher = task.pusher
        self.body = scene.bodies[obj]
        self.dynamics = RigidDynamics(model, self.body, scene.bodies[self.pusher.name])
        self.centre = self.dynamics.centre.double().numpy()
        self.pose = np.asarray(self.body.pose, dtype=float)
        self.position = np.asarray(self.pusher.position, dtype=float)[:2]
        self.obstacle_contact = False
        self.forbidden: set[str] = set()

    def __enter__(self) -> ImaginedWorld:
        return self

    def __exit__(self, *exc: object) -> None:
        return None

    def _gap(self, points: np.ndarray) -> float:
        """The least distance (m) between the pusher's rim at ``points (K, 2)`` and the
        object."""
        phi = self.body.sdf(torch.as_tensor(points, dtype=torch.float64),
                            torch.as_tensor(self.pose, dtype=torch.float64))
        return float(phi.min()) - self.pusher.radius

    def run_step(self, start: dict[str, np.ndarray], end: dict[str, np.ndarray],
                 substeps: int) -> None:
        """One planned step: the pusher moves from ``start`` to ``end`` in ``substeps``
        simulation steps, F_q moving the object once per kept step."""
        a = np.asarray(start[self.pusher.name], dtype=float)[:2]
        b = np.asarray(end[self.pusher.name], dtype=float)[:2]
        steps = max(1, round(substeps / self.physics.keep_every))
        for k in range(steps):
            p0, p1 = a + (b - a) * (k / steps), a + (b - a) * ((k + 1) / steps)
            between = p0 + (p1 - p0) * np.linspace(0.0, 1.0, 5)[:, None]
            if self._gap(between) < CONTACT_GAP:
                X1 = torch.as_tensor(np.stack((self.pose, self.pose)))
                X2 = torch.as_tensor(np.stack((p0, p1)))
                delta = self.dynamics.predict(X1, X2)[0].double().numpy()
                self.pose = rigid_step(self.pose, delta, self.centre)
        self.position = b

    def observe(self) -> Observation:
        return Observation({self.obj: self.pose.copy()}, self.position.copy())
