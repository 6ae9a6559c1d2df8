"""Arms in the MuJoCo world of :mod:`robotplan.execution.mujoco_world`: each robot folder's
URDF (the file pybullet loads, read by MuJoCo's own URDF reader) attached at its base, a tip
sphere on its flange link, its joints under position control.

The controller is a computed-torque servo: ``τ = M(q)(k e + c ė) + b(q, q̇)``, with ``e`` the
error to the joint targets, ``ė`` to their velocity (the targets' change per step), ``M`` the
mass matrix and ``b`` gravity and Coriolis forces, each joint's torque at most
``JOINT_FORCE``: every joint follows its target as a unit mass on a critically damped spring
of ``SERVO_RATE``, whatever the arm's inertia. As in pybullet an arm does not collide with
itself or the table; its links and tip collide with the objects, the obstacles and the
other arms.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from robotplan.execution.mujoco_model import sliding
from robotplan.execution.physics import damped_step
from robotplan.execution.pybullet_arms import JOINT_FORCE
from robotplan.scene.robots import load_robot_model
from robotplan.scene.schema import RobotSpec

if TYPE_CHECKING:
    from robotplan.execution.mujoco_world import MujocoPushWorld

__all__ = ["MujocoArm", "attach_arm"]

# rad/s: each joint's servo, critically damped; tracks planned reaches at 240 Hz
# (docs/experiments.md#mujoco-servo)
SERVO_RATE = 60.0
FIRST_ARM_BIT = 8  # contype bits from here on, one per arm (the world's are below)


class MujocoArm:
    """One arm: ``drive(q)`` sets its joint targets, :meth:`control` applies the servo."""

    def __init__(self, world: MujocoPushWorld, prefix: str, q0: np.ndarray, flange: str,
                 tip_offset: np.ndarray) -> None:
        self.world, self.prefix = world, prefix
        self.target = self.last = np.asarray(q0, dtype=float)
        self.flange, self.tip_offset = flange, np.asarray(tip_offset, dtype=float)

    def bind(self, model, data) -> None:
        """Find the arm's joints and tip in the compiled model; start at its joints."""
        hinges = [j for j in range(model.njnt) if model.joint(j).name.startswith(self.prefix)]
        if len(hinges) != len(self.target):
            raise ValueError(f"{self.prefix}: MuJoCo reads {len(hinges)} moving joints in the "
                             f"URDF, robot.yaml has {len(self.target)}")
        self.qpos = np.array([model.jnt_qposadr[j] for j in hinges])
        self.dofs = np.array([model.jnt_dofadr[j] for j in hinges])
        self.body = model.body(self.prefix + self.flange).id
        self.tip = model.geom(self.prefix + "tip").id
        data.qpos[self.qpos] = self.target

    def drive(self, q: np.ndarray) -> None:
        self.target = np.asarray(q, dtype=float)

    def control(self) -> None:
        """The servo's joint torques for this step, into ``qfrc_applied``."""
        world = self.world
        mj, model, d = world.mj, world.model, world.data
        velocity = (self.target - self.last) / model.opt.timestep
        self.last = self.target
        full = np.zeros((model.nv, model.nv))
        mj.mj_fullM(model, d, full)
        M = full[np.ix_(self.dofs, self.dofs)]
        k, c = SERVO_RATE**2, 2.0 * SERVO_RATE
        accel = k * (self.target - d.qpos[self.qpos]) + c * (velocity - d.qvel[self.dofs])
        torque = M @ accel + d.qfrc_bias[self.dofs]
        d.qfrc_applied[self.dofs] = np.clip(torque, -JOINT_FORCE, JOINT_FORCE)

    def tip_jacobian(self, q: np.ndarray) -> np.ndarray:
        """``(3, dof)``: the tip centre's linear velocity per joint velocity at joints ``q``."""
        world = self.world
        mj, model = world.mj, world.model
        scratch = mj.MjData(model)
        scratch.qpos[:] = world.data.qpos
        scratch.qpos[self.qpos] = q
        mj.mj_kinematics(model, scratch)
        mj.mj_comPos(model, scratch)
        jacp = np.zeros((3, model.nv))
        mj.mj_jac(model, scratch, jacp, None, scratch.geom_xpos[self.tip], self.body)
        return jacp[:, self.dofs]

    def steered(self, q: np.ndarray, shift: np.ndarray) -> np.ndarray:
        return damped_step(self.tip_jacobian(q), q, shift)

    def tip_position(self) -> np.ndarray:
        self.world.ready()
        return np.array(self.world.data.geom_xpos[self.tip], dtype=float)

    def joint_angles(self) -> np.ndarray:
        self.world.ready()
        return np.array(self.world.data.qpos[self.qpos], dtype=float)


def attach_arm(world: MujocoPushWorld, spec: RobotSpec, index: int) -> MujocoArm:
    """Attach ``spec``'s robot to ``world``'s model as its ``index``-th arm."""
    mj, ph = world.mj, world.physics
    model = load_robot_model(spec.model)
    q0 = np.asarray(spec.q0 if spec.q0 is not None else model.home, dtype=float)
    robot = mj.MjSpec.from_file(str(model.urdf_path))
    x, y, z, yaw = spec.base
    frame = world.spec.worldbody.add_frame(pos=[x, y, z],
                                           quat=[np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)])
    prefix = f"{spec.name}/"
    world.spec.attach(robot, frame=frame, prefix=prefix)
    own = FIRST_ARM_BIT << index
    others = world.object_bit | sum(FIRST_ARM_BIT << k for k in range(8) if k != index)
    link_mu = ph.friction("link", "object")
    for body in world.spec.bodies:
        if not body.name.startswith(prefix):
            continue
        for geom in body.geoms:
            geom.contype, geom.conaffinity = own, others
            geom.friction = sliding(link_mu)
    flange = world.spec.body(prefix + model.tip.link)
    flange.add_geom(name=prefix + "tip", type=mj.mjtGeom.mjGEOM_SPHERE,
                    size=[spec.tip_radius, 0, 0], pos=list(model.tip.offset), mass=0.1,
                    contype=own, conaffinity=others, priority=2,
                    friction=sliding(ph.friction("pusher", "object")))
    return MujocoArm(world, prefix, q0, model.tip.link, np.asarray(model.tip.offset))
