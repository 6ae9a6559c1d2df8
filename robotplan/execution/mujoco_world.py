"""The MuJoCo world of table-top pushing: the scene of :mod:`robotplan.execution.physics` built
by our code as a MuJoCo model, with the interface of
:class:`~robotplan.execution.physics.PushSimulator`.

The model is assembled with ``mujoco.MjSpec`` and compiled once the scene is complete (at
the first step, so that arms join it first): the table a box whose top is z = 0; each object
a free body at its footprint's centroid, built of the same solids as in pybullet
(:func:`~robotplan.execution.solids.footprint_solids`: boxes, a cylinder, convex prisms or a
mesh's convex pieces), of ``object_mass`` about its centroid; obstacles the same solids
fixed to the world; the free pusher a sphere on two horizontal slide joints at the height of
its radius. Arms are :mod:`robotplan.execution.mujoco_arms`.

Contacts get pybullet's friction coefficients (the product of the two bodies',
:meth:`Physics.friction`): MuJoCo takes the coefficient of the contact's geom of higher
``priority``, so the table's geoms carry the object–table coefficient at priority 1, the
pusher's and tips' the pusher–object one at priority 2 and objects and links their own
products at priority 0; friction cones are elliptic. The pusher is held to its path by a
stiff critically damped servo of at most ``pusher_max_force`` that also feeds the path's
velocity forward (``SERVO_RATE``); the integrator is MuJoCo's implicit-in-velocity one.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from robotplan.execution.mujoco_model import mujoco_spec, sliding
from robotplan.execution.physics import PHYSICS, Physics
from robotplan.execution.solids import (
    Solid,
    footprint_solids,
    planar_body_pose,
    read_pieces,
    shape_frame_pose,
)
from robotplan.sdf import Shape2D
from robotplan.sdf.footprint import footprint_centroid

if TYPE_CHECKING:
    from robotplan.execution.mujoco_arms import MujocoArm

__all__ = ["OBJECT", "SERVO_RATE", "MujocoPushWorld"]

# contype / conaffinity bits: two geoms collide when one's type meets the other's affinity
OBJECT, TABLE, PUSHER = 1, 2, 4
# rad/s: the pusher servo's natural frequency, critically damped: it lags a 0.36 m/s push by
# under 1 mm and is stable at 240 Hz (docs/experiments.md#mujoco-servo)
SERVO_RATE = 80.0
NEAR = 0.002  # m: object–obstacle pairs closer than this are reported (not pushed apart)
SETTLE_STEPS = 10


class MujocoPushWorld:
    """A MuJoCo world with a table, one object, obstacles, movable objects and a free
    pusher or arms (see the module docstring)."""

    object_bit = OBJECT  # the contype of objects and obstacles, which arms collide with

    def __init__(self, physics: Physics = PHYSICS) -> None:
        import mujoco

        self.mj, self.physics = mujoco, physics
        self.model = self.data = None
        self.spec = None
        self.arms: list[MujocoArm] = []
        self.pusher_radius = 0.0

    def close(self) -> None:
        self.model = self.data = self.spec = None

    def __enter__(self) -> MujocoPushWorld:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def reset(self, shape: Shape2D, height: float, pose, pusher_radius: float | None,
              pusher_xy=(0.0, 0.0), obstacles=(), movable=()) -> None:
        """A fresh scene (:meth:`~robotplan.execution.physics.PushSimulator.reset`)."""
        mj, ph = self.mj, self.physics
        spec = self.spec = mujoco_spec(ph.timestep, ph.gravity)
        spec.option.iterations = ph.solver_iterations
        self.model = self.data = None
        self.arms = []
        half = ph.table_size / 2
        spec.worldbody.add_geom(type=mj.mjtGeom.mjGEOM_BOX, size=[half, half, 0.05],
                                pos=[0, 0, -0.05], contype=TABLE, conaffinity=0, priority=1,
                                friction=sliding(ph.friction("table", "object")))
        self._bodies = [self._footprint_body("object", shape, height, pose, True)]
        self._coms = [footprint_centroid(shape)]
        for k, (o_shape, o_height, o_pose) in enumerate(obstacles):
            body = self._footprint_body(f"obstacle{k}", o_shape, o_height, o_pose, False)
            for geom in body.geoms:
                geom.margin, geom.gap = NEAR, NEAR
        for k, (o_shape, o_height, o_pose) in enumerate(movable):
            self._bodies.append(self._footprint_body(f"other{k}", o_shape, o_height, o_pose,
                                                     True))
            self._coms.append(footprint_centroid(o_shape))
        self._target = self._last_target = None
        if pusher_radius is not None:
            self.pusher_radius = pusher_radius
            body = spec.worldbody.add_body(name="pusher", pos=[0, 0, pusher_radius])
            for k, axis in enumerate(([1, 0, 0], [0, 1, 0])):
                body.add_joint(name=f"pusher_{'xy'[k]}", type=mj.mjtJoint.mjJNT_SLIDE,
                               axis=axis, ref=0.0)
            body.add_geom(type=mj.mjtGeom.mjGEOM_SPHERE, size=[pusher_radius, 0, 0],
                          mass=1.0, contype=PUSHER, conaffinity=OBJECT, priority=2,
                          friction=sliding(ph.friction("pusher", "object")))
            self._start = np.asarray(pusher_xy, dtype=float)[:2]
        self._has_pusher = pusher_radius is not None

    def _footprint_body(self, name: str, shape: Shape2D, height: float, pose, free: bool):
        """A footprint extruded to ``height`` at planar ``pose``, its frame at the centroid;
        a free body of ``object_mass`` or fixed to the world."""
        ph = self.physics
        centre, yaw = planar_body_pose(pose, shape)
        body = self.spec.worldbody.add_body(
            name=name, pos=[centre[0], centre[1], height / 2 + 1e-4],
            quat=[np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)])
        if free:
            body.add_freejoint()
        mu = ph.friction("object", "object")
        common = dict(contype=OBJECT, conaffinity=OBJECT | TABLE, friction=sliding(mu))
        for solid in footprint_solids(shape, height):
            self._add_solid(name, body, solid, common)
        return body

    def _add_solid(self, name: str, body, solid: Solid, common: dict) -> None:
        mj = self.mj
        if solid.kind == "box":
            body.add_geom(type=mj.mjtGeom.mjGEOM_BOX, size=list(solid.half),
                          pos=list(solid.centre), **common)
            return
        if solid.kind == "cylinder":
            body.add_geom(type=mj.mjtGeom.mjGEOM_CYLINDER,
                          size=[solid.radius, solid.length / 2, 0], **common)
            return
        if solid.kind == "pieces":
            hulls = [v * solid.scale + np.asarray(solid.centre) for v in read_pieces(solid.file)]
        else:
            hulls = [np.concatenate([np.column_stack((part, np.full(len(part), z)))
                                     for z in (-solid.length / 2, solid.length / 2)])
                     for part in solid.parts]
        for k, vertices in enumerate(hulls):
            mesh = f"{name}_{len(self.spec.meshes)}_{k}"
            self.spec.add_mesh(name=mesh, uservert=np.asarray(vertices, float).ravel().tolist())
            body.add_geom(type=mj.mjtGeom.mjGEOM_MESH, meshname=mesh, **common)

    def add_arm(self, spec) -> MujocoArm:
        """``spec``'s robot with its tip (:mod:`robotplan.execution.mujoco_arms`); the model is
        compiled at the first step, so every arm joins before it."""
        from robotplan.execution.mujoco_arms import attach_arm

        arm = attach_arm(self, spec, len(self.arms))
        self.arms.append(arm)
        return arm

    def ready(self) -> None:
        """Compile the model once, set its masses and start state and let it settle."""
        if self.data is not None:
            return
        mj, ph = self.mj, self.physics
        self.model = model = self.spec.compile()
        self.data = mj.MjData(model)
        self.body_ids = [model.body(b.name).id for b in self._bodies]
        for body_id in self.body_ids:  # object_mass about the centroid, as pybullet
            scale = ph.object_mass / model.body_mass[body_id]
            model.body_mass[body_id] *= scale
            model.body_inertia[body_id] *= scale
            model.body_ipos[body_id] = 0.0
        mj.mj_setConst(model, self.data)
        self._obstacle_geoms = {g for g in range(model.ngeom)
                                if model.body(model.geom_bodyid[g]).name.startswith("obstacle")}
        self._object_of_geom = {g: i for g in range(model.ngeom)
                                for i, b in enumerate(self.body_ids) if model.geom_bodyid[g] == b}
        if self._has_pusher:
            self._pusher_dofs = [model.joint(f"pusher_{a}").dofadr[0] for a in "xy"]
            self._pusher_q = [model.joint(f"pusher_{a}").qposadr[0] for a in "xy"]
            self._pusher_geom = model.body("pusher").geomadr[0]
            self.data.qpos[self._pusher_q] = self._start
            self._target = self._last_target = self._start.copy()
        for arm in self.arms:
            arm.bind(model, self.data)
        mj.mj_forward(model, self.data)
        for _ in range(SETTLE_STEPS):
            self._step()

    def _step(self) -> None:
        """One time step: the pusher's servo and the arms' controllers, then MuJoCo's."""
        d, ph = self.data, self.physics
        d.qfrc_applied[:] = 0.0
        if self._has_pusher:
            dofs = self._pusher_dofs
            velocity = (self._target - self._last_target) / ph.timestep
            k, c = SERVO_RATE**2, 2.0 * SERVO_RATE
            force = k * (self._target - d.qpos[self._pusher_q]) + c * (velocity - d.qvel[dofs])
            norm = float(np.hypot(*force))
            if norm > ph.pusher_max_force:
                force *= ph.pusher_max_force / norm
            d.qfrc_applied[dofs] = force  # the pusher's mass is 1 kg
            self._last_target = self._target
        for arm in self.arms:
            arm.control()
        self.mj.mj_step(self.model, d)

    def step(self, pusher_target) -> bool:
        """One time step driving the pusher to ``pusher_target``; whether it then touches
        the object."""
        self.ready()
        self._target = np.asarray(pusher_target, dtype=float)[:2]
        self._step()
        return self._pusher_touches(0)

    def advance(self) -> None:
        self.ready()
        self._step()

    def _contacts(self) -> list[tuple[int, int, float]]:
        d = self.data
        n = d.ncon
        return list(zip(d.contact.geom1[:n].tolist(), d.contact.geom2[:n].tolist(),
                        d.contact.dist[:n].tolist(), strict=True))

    def _pusher_touches(self, index: int) -> bool:
        g = self._pusher_geom
        return any((a == g and self._object_of_geom.get(b) == index)
                   or (b == g and self._object_of_geom.get(a) == index)
                   for a, b, dist in self._contacts() if dist <= 0.0)

    def pusher_touches_other(self, index: int) -> bool:
        self.ready()
        return self._pusher_touches(index + 1)

    def touches_obstacle(self, gap: float = 0.0) -> bool:
        """Whether an object is within ``gap`` (m, at most ``NEAR``) of an obstacle."""
        self.ready()
        obstacles, objects = self._obstacle_geoms, self._object_of_geom
        return any(((a in obstacles and b in objects) or (b in obstacles and a in objects))
                   and dist <= gap for a, b, dist in self._contacts())

    def _planar(self, index: int) -> tuple[np.ndarray, float]:
        body = self.body_ids[index]
        R = self.data.xmat[body].reshape(3, 3)
        return shape_frame_pose(self.data.xpos[body], R, self._coms[index])

    def object_pose(self) -> tuple[np.ndarray, float]:
        self.ready()
        return self._planar(0)

    def other_poses(self) -> list[np.ndarray]:
        self.ready()
        return [self._planar(i)[0] for i in range(1, len(self.body_ids))]

    def pusher_position(self) -> np.ndarray:
        self.ready()
        return np.array(self.data.qpos[self._pusher_q], dtype=float)
