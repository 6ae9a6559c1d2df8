"""The pybullet world of table-top pushing (:mod:`robotplan.execution.physics`), shared by
data generation and plan execution: the push data's world. The pusher is driven
kinematically along its path by a stiff fixed constraint; arms are
:mod:`robotplan.execution.pybullet_arms`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from robotplan.base.quiet import c_output_silenced, connect_direct, import_pybullet
from robotplan.execution.physics import PHYSICS, Physics
from robotplan.execution.solids import (
    Solid,
    footprint_solids,
    planar_body_pose,
    shape_frame_pose,
)
from robotplan.sdf import Shape2D
from robotplan.sdf.footprint import footprint_centroid

if TYPE_CHECKING:
    from robotplan.execution.pybullet_arms import Arm

__all__ = ["PushWorld"]


def _prism_obj(parts, height: float) -> str:
    """Wavefront OBJ text of convex prisms, one ``o`` group per footprint part: pybullet
    loads each group as one convex hull of a compound shape (concave footprints)."""
    lines, base = [], 1
    for i, part in enumerate(parts):
        n = len(part)
        lines.append(f"o part{i}")
        lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for z in (-height / 2, height / 2)
                  for x, y in part]
        lines.append("f " + " ".join(str(base + k) for k in reversed(range(n))))
        lines.append("f " + " ".join(str(base + n + k) for k in range(n)))
        lines += [f"f {base + k} {base + (k + 1) % n} {base + n + (k + 1) % n} {base + n + k}"
                  for k in range(n)]
        base += 2 * n
    return "\n".join(lines) + "\n"


class PushWorld:
    """A pybullet DIRECT world with a table, one object and one spherical pusher."""

    def __init__(self, physics: Physics = PHYSICS) -> None:
        self.pb = import_pybullet()
        self.physics = physics
        self.client = connect_direct()
        self.object: int | None = None
        self.obstacles: list[int] = []
        self.others: list[tuple[int, np.ndarray]] = []  # movable objects beside the first
        self.pusher: int | None = None
        self.table: int | None = None
        self._constraint: int | None = None
        self._com = np.zeros(2)
        self.pusher_radius = 0.0

    def close(self) -> None:
        with c_output_silenced():
            self.pb.disconnect(physicsClientId=self.client)

    def __enter__(self) -> PushWorld:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def reset(self, shape: Shape2D, height: float, pose: tuple[float, float, float],
              pusher_radius: float | None, pusher_xy: tuple[float, float] = (0.0, 0.0),
              obstacles: list[tuple[Shape2D, float, tuple[float, float, float]]] = (),
              movable: list[tuple[Shape2D, float, tuple[float, float, float]]] = ()
              ) -> None:
        """Place a new object (footprint ``shape``) at ``pose`` and a pusher at ``pusher_xy``
        (none if ``pusher_radius`` is None: arms push, see robotplan.execution.pybullet_arms); fixed
        ``obstacles`` and more ``movable`` objects (same mass and friction) as
        ``(footprint, height, pose)``."""
        pb, c, ph = self.pb, self.client, self.physics
        pb.resetSimulation(physicsClientId=c)  # a clean world: no ids reused across scenes
        pb.setGravity(0, 0, -ph.gravity, physicsClientId=c)
        pb.setTimeStep(ph.timestep, physicsClientId=c)
        pb.setPhysicsEngineParameter(numSolverIterations=ph.solver_iterations, physicsClientId=c)
        half = ph.table_size / 2
        table_shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[half, half, 0.05],
                                              physicsClientId=c)
        self.table = pb.createMultiBody(0, table_shape, basePosition=[0, 0, -0.05],
                                        physicsClientId=c)
        pb.changeDynamics(self.table, -1, lateralFriction=ph.table_friction,
                          restitution=ph.restitution, physicsClientId=c)
        self._com = footprint_centroid(shape)
        self.object = self._footprint_body(shape, height, pose, ph.object_mass)
        self.obstacles = [self._footprint_body(o_shape, o_height, o_pose, 0.0)
                          for o_shape, o_height, o_pose in obstacles]
        self.others = [(self._footprint_body(o_shape, o_height, o_pose, ph.object_mass),
                        footprint_centroid(o_shape)) for o_shape, o_height, o_pose in movable]
        if pusher_radius is None:
            self._settle()
            return
        sphere = pb.createCollisionShape(pb.GEOM_SPHERE, radius=pusher_radius, physicsClientId=c)
        self.pusher_radius = pusher_radius
        start = [pusher_xy[0], pusher_xy[1], pusher_radius]
        self.pusher = pb.createMultiBody(1.0, sphere, basePosition=start, physicsClientId=c)
        pb.changeDynamics(self.pusher, -1, lateralFriction=ph.pusher_friction,
                          restitution=ph.restitution, physicsClientId=c)
        pb.setCollisionFilterPair(self.pusher, self.table, -1, -1, 0, physicsClientId=c)
        self._constraint = pb.createConstraint(self.pusher, -1, -1, -1, pb.JOINT_FIXED,
                                               [0, 0, 0], [0, 0, 0], start,
                                               physicsClientId=c)
        pb.changeConstraint(self._constraint, start, maxForce=ph.pusher_max_force,
                            physicsClientId=c)
        self._settle()

    def _footprint_body(self, shape: Shape2D, height: float, pose, mass: float) -> int:
        """A footprint extruded to ``height`` at planar ``pose`` (mass 0: fixed). Its base
        frame is the footprint's centroid (the centre of mass)."""
        pb, c, ph = self.pb, self.client, self.physics
        col = self._collision_shape(footprint_solids(shape, height))
        com_w, yaw = planar_body_pose(pose, shape)
        body = pb.createMultiBody(mass, col, basePosition=[com_w[0], com_w[1], height / 2 + 1e-4],
                                  baseOrientation=pb.getQuaternionFromEuler([0, 0, yaw]),
                                  physicsClientId=c)
        pb.changeDynamics(body, -1, lateralFriction=ph.object_friction,
                          restitution=ph.restitution, physicsClientId=c)
        return body

    def _collision_shape(self, solids: list[Solid]) -> int:
        """One collision shape of a body's solids (:func:`footprint_solids`): boxes as a
        compound of boxes, a cylinder, mesh pieces from their file, prisms as an OBJ of
        convex groups."""
        pb, c = self.pb, self.client
        kind = solids[0].kind
        if kind == "box":
            return pb.createCollisionShapeArray(
                [pb.GEOM_BOX] * len(solids), halfExtents=[list(s.half) for s in solids],
                collisionFramePositions=[list(s.centre) for s in solids], physicsClientId=c)
        (solid,) = solids
        if kind == "cylinder":
            return pb.createCollisionShape(pb.GEOM_CYLINDER, radius=solid.radius,
                                           height=solid.length, physicsClientId=c)
        if kind == "pieces":
            return pb.createCollisionShape(pb.GEOM_MESH, fileName=str(solid.file),
                                           meshScale=[solid.scale] * 3,
                                           collisionFramePosition=list(solid.centre),
                                           physicsClientId=c)
        import tempfile
        from pathlib import Path

        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "footprint.obj"
            path.write_text(_prism_obj(solid.parts, solid.length))
            return pb.createCollisionShape(pb.GEOM_MESH, fileName=str(path),
                                           physicsClientId=c)

    def touches_obstacle(self, gap: float = 0.0) -> bool:
        """Whether an object (the first or a movable one) is within ``gap`` (m) of any
        obstacle."""
        return any(self.pb.getClosestPoints(body, o, gap, physicsClientId=self.client)
                   for body in (self.object, *(b for b, _ in self.others))
                   for o in self.obstacles)

    def _settle(self) -> None:
        """Let the object settle onto the table."""
        for _ in range(10):
            self.pb.stepSimulation(physicsClientId=self.client)

    def step(self, pusher_target: tuple[float, float]) -> bool:
        """Drive the pusher to ``pusher_target`` for one time step; True if it touches the
        object after the step."""
        pb, c = self.pb, self.client
        target = [pusher_target[0], pusher_target[1], self.pusher_radius]
        pb.changeConstraint(self._constraint, target, maxForce=self.physics.pusher_max_force,
                            physicsClientId=c)
        pb.stepSimulation(physicsClientId=c)
        return bool(pb.getContactPoints(self.pusher, self.object, physicsClientId=c))

    def object_pose(self) -> tuple[np.ndarray, float]:
        """Planar pose ``(x, y, yaw)`` of the shape frame and the tilt (rad) of the object."""
        return self._planar_pose(self.object, self._com)

    def other_poses(self) -> list[np.ndarray]:
        """Planar poses ``(x, y, yaw)`` of the ``movable`` objects, in their order."""
        return [self._planar_pose(body, com)[0] for body, com in self.others]

    def pusher_touches_other(self, index: int) -> bool:
        """Whether the pusher is in contact with the ``index``-th movable object."""
        return bool(self.pb.getContactPoints(self.pusher, self.others[index][0],
                                             physicsClientId=self.client))

    def _planar_pose(self, body: int, com: np.ndarray) -> tuple[np.ndarray, float]:
        pos, quat = self.pb.getBasePositionAndOrientation(body, physicsClientId=self.client)
        R = np.array(self.pb.getMatrixFromQuaternion(quat)).reshape(3, 3)
        return shape_frame_pose(np.asarray(pos), R, com)

    def add_arm(self, spec) -> Arm:
        """``spec``'s robot with its tip (:func:`robotplan.execution.pybullet_arms.add_arm`)."""
        from robotplan.execution.pybullet_arms import add_arm

        return add_arm(self, spec)

    def advance(self) -> None:
        self.pb.stepSimulation(physicsClientId=self.client)

    def pusher_position(self) -> np.ndarray:
        pos, _ = self.pb.getBasePositionAndOrientation(self.pusher, physicsClientId=self.client)
        return np.array(pos[:2])
