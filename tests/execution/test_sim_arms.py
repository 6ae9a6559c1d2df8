"""Arms in the pybullet world: the tip Jacobian and the steered joints (sim_arms)."""

from __future__ import annotations

import numpy as np
import pytest

from robotplan.execution.scene_world import SceneWorld
from robotplan.scene.loader import load_scene
from tests.conftest import TASKS


@pytest.fixture
def arm_world():
    scene = load_scene(TASKS / "two_arm_handover.yaml")
    with SceneWorld(scene, "box") as world:
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
