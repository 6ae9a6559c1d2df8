"""The drop test in MuJoCo: the bodies of the pybullet world built as a MuJoCo model give the
same labels: a mug dropped clear of the hook falls to the ground, the pose that hangs in
pybullet hangs, a pose through the arm is a collision, and a mesh mug on a mesh hook loads
and hangs; :func:`hang_world` opens either simulator by name."""

import math

import numpy as np
import pytest

from robotplan.hanging.execution.drop import HANG_PHYSICS
from robotplan.hanging.execution.mujoco_world import MujocoHangWorld
from robotplan.hanging.execution.world import HangWorld
from robotplan.hanging.execution.worlds import hang_world
from tests.hanging.execution.test_world import HOOK, MUG, threaded_mesh_pose, threaded_pose


@pytest.fixture(scope="module")
def world():
    with MujocoHangWorld(HOOK, MUG) as w:
        yield w


def test_a_mug_clear_of_the_hook_falls_to_the_ground(world):
    record: list = []
    result = world.drop((0.4, 0.4, 0.3, 1.0, 0.0, 0.0, 0.0), record=record)
    assert result.on_ground and not result.hangs and not result.on_hook
    assert not result.collision_at_start
    assert result.fall_m > 0.2, "it came down most of its 0.3 m"
    assert record[0] == (0.0, (0.4, 0.4, 0.3, 1.0, 0.0, 0.0, 0.0)), "the drop starts there"
    assert len(record) > 3 and record[-1][1][2] < 0.05


def test_the_pose_that_hangs_in_pybullet_hangs_in_mujoco(world):
    with HangWorld(HOOK, MUG) as pybullet:
        assert pybullet.drop(threaded_pose()).hangs, "the pybullet tests' hanging pose"
    assert not world.collides(threaded_pose())
    result = world.drop(threaded_pose())
    assert result.hangs and result.on_hook and not result.on_ground, result
    assert result.X_WM_end[2] > 0.1, "it stays up on the arm"
    assert result.fall_m < 2 * HANG_PHYSICS.in_place_fall, "it comes down onto its handle"
    below = world.drop(threaded_pose(dz=-0.2))
    assert not below.hangs and below.on_ground and not below.collision_at_start


def test_a_mug_through_the_arm_collides(world):
    x, _, z, *_ = threaded_pose()
    # upright, the cup's wall (handle away from the post) across the arm at its height
    through = (x, -(MUG.radius - MUG.wall / 2), z, 1.0, 0.0, 0.0, 0.0)
    assert world.collides(through)
    result = world.drop(through)
    assert result.collision_at_start and not result.hangs


def test_the_mug_weighs_and_rubs_as_in_pybullet(world):
    mug = world.model.body("mug").id
    assert world.model.body_mass[mug] == pytest.approx(HANG_PHYSICS.mug_mass)
    assert np.allclose(world.model.geom_friction[:, 0], HANG_PHYSICS.friction ** 2)
    assert world.model.opt.timestep == HANG_PHYSICS.timestep


def test_a_mesh_mug_loads_hangs_threaded_and_falls_when_clear(mesh_parts):
    mug, hook = mesh_parts
    with MujocoHangWorld(hook, mug) as w:
        body = w.model.body("mug").id
        assert np.allclose(w.model.body_ipos[body], mug.mesh.center_mass)
        assert w.model.nmesh > 10, "a mesh geom per convex piece"
        result = w.drop(threaded_mesh_pose(mug, hook))
        assert result.hangs, result
        clear = w.drop((0.4, 0.4, 0.2, math.cos(0.3), 0.0, 0.0, math.sin(0.3)))
        assert clear.on_ground and not clear.hangs


def test_hang_world_opens_the_named_simulator():
    with hang_world(HOOK, MUG, "mujoco") as w:
        assert isinstance(w, MujocoHangWorld)
    with hang_world(HOOK, MUG) as w:
        assert isinstance(w, HangWorld)
    with pytest.raises(ValueError, match="'bullet'; expected one of pybullet, mujoco"):
        hang_world(HOOK, MUG, "bullet")
