"""Arms in the pybullet world: the tip Jacobian and the steered joints (pybullet_arms), and an
acting arm steered in the closed loop (steering)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from robotplan.execution.scene_world import SceneWorld
from robotplan.pushing.execution.loop_settings import LoopSettings
from robotplan.pushing.execution.steering import steer_actor
from robotplan.pushing.program.skeleton import Phase, Skeleton
from robotplan.scene.task import load_task
from tests.conftest import TASKS


@pytest.fixture
def arm_world():
    task = load_task(TASKS / "two_arm_handover.yaml")
    with SceneWorld(task) as world:
        yield world


def _tip_at(arm, q: np.ndarray) -> np.ndarray:
    """Where the tip sphere is fixed at joints ``q``, by pybullet's forward kinematics: the
    flange's inertial frame and the fixing constraint's point in it."""
    pb, c = arm.world.pb, arm.world.client
    for j, angle in zip(arm.joints, q, strict=True):
        pb.resetJointState(arm.body, j, float(angle), physicsClientId=c)
    state = pb.getLinkState(arm.body, arm.flange, computeForwardKinematics=True,
                            physicsClientId=c)
    R = np.array(pb.getMatrixFromQuaternion(state[1])).reshape(3, 3)
    constraint = pb.getConstraintInfo(pb.getConstraintUniqueId(0, physicsClientId=c),
                                      physicsClientId=c)
    assert constraint[0] == arm.body and constraint[2] == arm.tip
    return np.asarray(state[0]) + R @ np.asarray(constraint[6])


def test_tip_jacobian_matches_finite_differences(arm_world) -> None:
    arm = arm_world.arms["left"]
    q = arm.joint_angles() + np.linspace(-0.2, 0.2, len(arm.joints))
    J = arm.tip_jacobian(q)
    h = 1e-6
    numeric = np.stack([(_tip_at(arm, q + h * e) - _tip_at(arm, q - h * e)) / (2 * h)
                        for e in np.eye(len(q))], axis=1)
    assert J.shape == (3, len(q))
    np.testing.assert_allclose(J, numeric, atol=1e-6)


def test_steered_joints_move_the_tip_by_the_shift(arm_world) -> None:
    arm = arm_world.arms["left"]
    q = arm.joint_angles() + np.linspace(-0.2, 0.2, len(arm.joints))
    shift = np.array([0.01, -0.006, 0.0])
    moved = _tip_at(arm, arm.steered(q, shift)) - _tip_at(arm, q)
    assert np.linalg.norm(moved - shift) < 2e-4  # first order: 1 cm to within 0.2 mm
    assert np.linalg.norm(moved - shift) < 0.05 * np.linalg.norm(shift)


def _loop_at(mode: str) -> SimpleNamespace:
    """A closed loop's state at the first step of a one-phase plan in which the left arm
    pushes the box 1 cm per step along +x."""
    q_obj = np.array([[-0.45 + 0.01 * t, 0.10, 0.2] for t in range(11)])
    skeleton = Skeleton((Phase(mode, "left", "box", 0),))
    return SimpleNamespace(plan=SimpleNamespace(q_obj=q_obj, skeleton=skeleton), t=0, T=10,
                           drive={})


def test_an_arm_pushing_a_box_turned_too_far_steers_its_tip_against_the_turn(arm_world):
    """The box is 0.2 rad further counter-clockwise than planned: the pushing arm's tip
    moves left of the push (+y) by gain × 0.2 (1 cm), to first order; the other arm and a
    reaching arm are left as planned."""
    left, right = arm_world.arms["left"], arm_world.arms["right"]
    q_left = left.joint_angles() + np.linspace(-0.2, 0.2, len(left.joints))
    planned = {"left": q_left.copy(), "right": right.joint_angles()}
    seen = np.array([-0.45, 0.10, 0.4])
    settings = LoopSettings(steer_gain=0.05)
    target = {k: v.copy() for k, v in planned.items()}
    steer_actor(arm_world, _loop_at("push"), target, seen, settings)
    moved = _tip_at(left, target["left"]) - _tip_at(left, q_left)
    assert np.linalg.norm(moved - np.array([0.0, 0.01, 0.0])) < 3e-4
    np.testing.assert_array_equal(target["right"], planned["right"])
    reaching = {k: v.copy() for k, v in planned.items()}
    steer_actor(arm_world, _loop_at("reach"), reaching, seen, settings)
    np.testing.assert_array_equal(reaching["left"], planned["left"])
