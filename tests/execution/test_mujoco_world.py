"""The MuJoCo world of pushing: its bodies are the footprints' outlines, the pusher and the
arms follow their targets, contacts have the push data's friction, and both simulators sit
behind one interface (push_world, SceneWorld)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from robotplan.execution.physics import PHYSICS, SIMULATORS, push_world, simulator_problem
from robotplan.execution.scene_world import SceneWorld
from robotplan.scene.bodies import Body
from robotplan.scene.task import load_task
from robotplan.sdf import Box, Circle, LShape, Polygon
from tests.conftest import TASKS

MUJOCO = replace(PHYSICS, simulator="mujoco")


def test_push_world_opens_the_named_simulator_and_refuses_others() -> None:
    for name in SIMULATORS:
        with push_world(replace(PHYSICS, simulator=name)) as world:
            assert world.physics.simulator == name
    assert "expected one of pybullet, mujoco" in simulator_problem(["pybullet", "bullet3"])
    with pytest.raises(ValueError, match="unknown simulator 'bullet3'"):
        push_world(replace(PHYSICS, simulator="bullet3"))


def test_contacts_have_the_product_of_the_bodies_frictions() -> None:
    assert PHYSICS.friction("pusher", "object") == pytest.approx(0.15)
    assert PHYSICS.friction("object", "table") == pytest.approx(0.5)
    with push_world(MUJOCO) as world:
        world.reset(Box((0.1, 0.1)), 0.05, (0.0, 0.0, 0.0), 0.01, (-0.2, 0.0))
        world.step((-0.2, 0.0))
        model = world.model
        # MuJoCo takes the friction of the geom of higher priority in each pair
        table = int(np.argmax(model.geom_priority == 1))
        pusher = int(np.argmax(model.geom_priority == 2))
        assert model.geom_friction[table, 0] == pytest.approx(0.5)
        assert model.geom_friction[pusher, 0] == pytest.approx(0.15)
        assert model.body_mass[world.body_ids[0]] == pytest.approx(PHYSICS.object_mass)


@pytest.mark.parametrize("shape", [
    Polygon(((-0.12, 0.1), (-0.12, 0.04), (-0.03, 0.04), (-0.03, -0.12), (0.03, -0.12),
             (0.03, 0.04), (0.12, 0.04), (0.12, 0.1))),  # a T: concave
    Circle(0.07),
    LShape((0.24, 0.16), 0.06),
])
def test_footprints_are_simulated_as_their_outlines(shape, rng) -> None:
    """MuJoCo's distance from the body to a probe sphere around it and inside its
    concavities matches the SDF to 2 mm, and the body rests where it was placed."""
    import mujoco
    import torch

    pose, height, radius = (0.1, -0.05, 0.7), 0.06, 0.005
    body = Body("o", "object", shape, pose, 0.0, height)
    with push_world(MUJOCO) as world:
        world.reset(shape, height, pose, None)
        probe = world.spec.worldbody.add_body(name="probe", mocap=True)
        probe.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[radius, 0, 0], contype=0,
                       conaffinity=0)
        assert np.abs(world.object_pose()[0] - pose).max() < 2e-3
        model, data = world.model, world.data
        ball = model.body("probe").geomadr[0]
        geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] == world.body_ids[0]]
        points = rng.uniform(-0.2, 0.2, (40, 2)) + np.array(pose[:2])
        phi = body.sdf(torch.tensor(points), torch.tensor(pose, dtype=torch.float64)).numpy()
        for p, d in zip(points, phi, strict=True):
            if d < 0.003:  # distances are only reported outside the body
                continue
            data.mocap_pos[0] = [p[0], p[1], height / 2]
            mujoco.mj_kinematics(model, data)
            gap = min(mujoco.mj_geomDistance(model, data, g, ball, 0.5, None)
                      for g in geoms) + radius
            assert abs(gap - d) < 2e-3, (p, gap, d)


def test_a_centred_push_moves_the_box_alike_in_both_worlds() -> None:
    """A pusher driven 10 cm into the middle of a box's face at the data's speeds: the
    pusher tracks its path to 2 mm, the box slides ahead of it with little turn, in pybullet
    and MuJoCo alike (to 1 cm)."""
    ends = {}
    for name in SIMULATORS:
        with push_world(replace(PHYSICS, simulator=name)) as world:
            world.reset(Box((0.1, 0.06)), 0.05, (0.0, 0.0, 0.0), 0.01, (-0.08, 0.0))
            touched = False
            for k in range(1, 241):
                target = (-0.08 + 0.15 * k / 240, 0.0)
                touched |= world.step(target)
            assert touched
            assert np.hypot(*(world.pusher_position() - target)) < 5e-3
            pose, tilt = world.object_pose()
            assert tilt < 0.05 and abs(pose[2]) < 0.1 and abs(pose[1]) < 0.01
            ends[name] = pose
    assert ends["mujoco"][0] > 0.05
    assert abs(ends["mujoco"][0] - ends["pybullet"][0]) < 0.01


@pytest.fixture
def mujoco_arms():
    task = load_task(TASKS / "two_arm_handover.yaml")
    with SceneWorld(task, MUJOCO) as world:
        world.observe()
        yield world


def test_arm_tip_jacobian_matches_finite_differences(mujoco_arms) -> None:
    """The tip's Jacobian (float64) against central differences of MuJoCo's own forward
    kinematics of the tip sphere."""
    import mujoco

    arm = mujoco_arms.arms["left"]
    world = mujoco_arms.world
    q = arm.joint_angles() + np.linspace(-0.2, 0.2, len(arm.qpos))

    def tip(angles: np.ndarray) -> np.ndarray:
        data = mujoco.MjData(world.model)
        data.qpos[arm.qpos] = angles
        mujoco.mj_kinematics(world.model, data)
        return data.geom_xpos[arm.tip].copy()

    h = 1e-6
    numeric = np.stack([(tip(q + h * e) - tip(q - h * e)) / (2 * h)
                        for e in np.eye(len(q))], axis=1)
    J = arm.tip_jacobian(q)
    assert J.shape == (3, len(q))
    np.testing.assert_allclose(J, numeric, atol=1e-6)
    shift = np.array([0.01, -0.006, 0.0])
    moved = tip(arm.steered(q, shift)) - tip(q)
    assert np.linalg.norm(moved - shift) < 0.05 * np.linalg.norm(shift)


def test_arms_follow_their_joint_targets(mujoco_arms) -> None:
    """A 5 cm move of the left tip over half a second: the joints end within 0.01 rad of
    their targets and the tip within 5 mm of where it was sent; the idle right arm holds."""
    world = mujoco_arms
    start = world.observe()
    left = world.arms["left"]
    goal = left.steered(start.joints["left"], np.array([0.05, 0.0, 0.0]))
    world.run_step(start.joints, {**start.joints, "left": goal}, 120)
    end = world.observe()
    assert np.abs(end.joints["left"] - goal).max() < 0.01
    assert np.linalg.norm(end.tips["left"] - start.tips["left"] - [0.05, 0.0, 0.0]) < 5e-3
    assert np.abs(end.joints["right"] - start.joints["right"]).max() < 1e-3
