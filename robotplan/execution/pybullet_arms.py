"""Arms in the pybullet world of :mod:`robotplan.execution.pybullet_world`: each robot
folder's URDF at its base, a tip sphere fixed to its flange, joints under position control.
The world, the object and the tip's friction are those of the push data."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from robotplan.execution.physics import damped_step
from robotplan.scene.robots import load_robot_model
from robotplan.scene.schema import RobotSpec

if TYPE_CHECKING:
    from robotplan.execution.pybullet_world import PushWorld

__all__ = ["Arm", "add_arm"]

JOINT_FORCE = 300.0  # N·m: the iiwa 14's largest joint torques are 320 N·m
# pybullet's default gain (0.1) lags behind a planned reach; 1.0 tracks it at the planned
# speeds (measured: docs/experiments.md#arm-position-gain)
POSITION_GAIN = 1.0


class Arm:
    """One arm in a :class:`PushWorld`: ``drive(q)`` sets its joint targets. ``flange``: the
    link the tip sphere is fixed to, at ``tip_offset`` in that link's (URDF) frame."""

    def __init__(self, world: PushWorld, body: int, joints: list[int], tip: int,
                 flange: int, tip_offset: np.ndarray) -> None:
        self.world, self.body, self.joints, self.tip = world, body, joints, tip
        self.flange, self.tip_offset = flange, np.asarray(tip_offset, dtype=float)

    def drive(self, q: np.ndarray) -> None:
        pb, c = self.world.pb, self.world.client
        pb.setJointMotorControlArray(self.body, self.joints, pb.POSITION_CONTROL,
                                     targetPositions=list(map(float, q)),
                                     forces=[JOINT_FORCE] * len(self.joints),
                                     positionGains=[POSITION_GAIN] * len(self.joints),
                                     velocityGains=[1.0] * len(self.joints),
                                     physicsClientId=c)

    def tip_jacobian(self, q: np.ndarray) -> np.ndarray:
        """``(3, dof)``: the tip centre's linear velocity per joint velocity at joints ``q``."""
        zeros = [0.0] * len(self.joints)
        linear, _ = self.world.pb.calculateJacobian(
            self.body, self.flange, self.tip_offset.tolist(), list(map(float, q)), zeros, zeros,
            physicsClientId=self.world.client)
        return np.asarray(linear, dtype=float)

    def steered(self, q: np.ndarray, shift: np.ndarray) -> np.ndarray:
        """Joint angles near ``q`` that move the tip centre by ``shift (3,)`` m in the world
        frame, to first order: one damped least-squares step on :meth:`tip_jacobian`."""
        return damped_step(self.tip_jacobian(q), q, shift)

    def tip_position(self) -> np.ndarray:
        pos, _ = self.world.pb.getBasePositionAndOrientation(self.tip,
                                                             physicsClientId=self.world.client)
        return np.array(pos)

    def joint_angles(self) -> np.ndarray:
        states = self.world.pb.getJointStates(self.body, self.joints,
                                              physicsClientId=self.world.client)
        return np.array([s[0] for s in states])


def add_arm(world: PushWorld, spec: RobotSpec) -> Arm:
    """Load ``spec``'s robot at its base and start pose, with a tip sphere on its flange."""
    pb, c, ph = world.pb, world.client, world.physics
    model = load_robot_model(spec.model)
    q0 = np.asarray(spec.q0 if spec.q0 is not None else model.home, dtype=float)
    x, y, z, yaw = spec.base
    body = pb.loadURDF(str(model.urdf_path), [x, y, z], pb.getQuaternionFromEuler([0, 0, yaw]),
                       useFixedBase=True, physicsClientId=c)
    joints, links = [], {}
    for j in range(pb.getNumJoints(body, physicsClientId=c)):
        info = pb.getJointInfo(body, j, physicsClientId=c)
        links[info[12].decode()] = j
        if info[2] != pb.JOINT_FIXED:
            joints.append(j)
    for j, angle in zip(joints, q0, strict=True):
        pb.resetJointState(body, j, float(angle), physicsClientId=c)
    flange = links[model.tip.link]
    state = pb.getLinkState(body, flange, computeForwardKinematics=True, physicsClientId=c)
    R = np.array(pb.getMatrixFromQuaternion(state[5])).reshape(3, 3)
    start = np.asarray(state[4]) + R @ np.asarray(model.tip.offset)
    sphere = pb.createCollisionShape(pb.GEOM_SPHERE, radius=spec.tip_radius, physicsClientId=c)
    tip = pb.createMultiBody(0.1, sphere, basePosition=start.tolist(), physicsClientId=c)
    pb.changeDynamics(tip, -1, lateralFriction=ph.pusher_friction,
                      restitution=ph.restitution, physicsClientId=c)
    # constraint frames are the links' inertial frames, not their URDF frames
    info = pb.getDynamicsInfo(body, flange, physicsClientId=c)
    R_in = np.array(pb.getMatrixFromQuaternion(info[4])).reshape(3, 3)
    in_com = R_in.T @ (np.asarray(model.tip.offset) - np.asarray(info[3]))
    fix = pb.createConstraint(body, flange, tip, -1, pb.JOINT_FIXED, [0, 0, 0],
                              in_com.tolist(), [0, 0, 0], physicsClientId=c)
    pb.changeConstraint(fix, maxForce=ph.pusher_max_force, physicsClientId=c)
    for link in [-1, *range(pb.getNumJoints(body, physicsClientId=c))]:
        pb.setCollisionFilterPair(body, tip, link, -1, 0, physicsClientId=c)
        pb.setCollisionFilterPair(body, world.table, link, -1, 0, physicsClientId=c)
    pb.setCollisionFilterPair(tip, world.table, -1, -1, 0, physicsClientId=c)
    arm = Arm(world, body, joints, tip, flange, np.asarray(model.tip.offset))
    arm.drive(q0)
    return arm
