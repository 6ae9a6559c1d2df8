"""The world that F_q moves: its step against pybullet's on a real push, no motion without
contact, and its rigid step in float64."""

import itertools
import math

import numpy as np
import pytest

from robotplan.base.resources import learned_dir
from robotplan.execution.scene_world import SceneWorld
from robotplan.pushing.execution.imagined_world import ImaginedWorld, rigid_step
from robotplan.pushing.models.loading import load_dynamics
from robotplan.scene.task import load_task
from tests.conftest import TASKS


@pytest.fixture(scope="module")
def fq():
    return load_dynamics(learned_dir("push_rigid"))


def _box_task(pusher_xy):
    """box_push with its box at the origin, unturned, and the pusher at ``pusher_xy``."""
    task = load_task(TASKS / "box_push.yaml")
    return task.at(task.scene.with_state({"box": (0.0, 0.0, 0.0), "pusher": (*pusher_xy, 0.0)}))


def _pivot(pose, centre):
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return pose[:2] + np.array([[c, -s], [s, c]]) @ centre


def test_a_rigid_step_turns_about_the_pivot_then_shifts_it():
    rng = np.random.default_rng(0)
    for _ in range(20):
        pose, centre = rng.normal(size=3), rng.normal(size=2) * 0.05
        delta = rng.normal(size=3) * [0.01, 0.01, 0.1]
        after = rigid_step(pose, delta, centre)
        shift = _pivot(after, centre) - _pivot(pose, centre)
        assert np.abs(shift - delta[:2]).max() < 1e-15
        assert after[2] == pytest.approx(pose[2] + delta[2], abs=1e-15)


def test_without_contact_the_object_stays_where_it_is(fq):
    """A long reach round the box, 10 cm from it all the way: not a hair of motion."""
    task = _box_task((-0.25, 0.0))
    with ImaginedWorld(task, fq) as world:
        start = world.observe().poses["box"]
        for a, b in [((-0.25, 0.0), (-0.25, 0.19)), ((-0.25, 0.19), (0.25, 0.19))]:
            world.run_step({"pusher": np.array(a)}, {"pusher": np.array(b)}, 400)
        seen = world.observe()
    assert np.array_equal(seen.poses["box"], start)
    assert np.allclose(seen.pusher, (0.25, 0.19))


def test_a_push_moves_the_box_as_pybullet_does(fq):
    """The pusher starts 1 cm behind the box's short face, 2 cm off its axis, and pushes
    along it 12 steps of 1.5 cm: F_q's box ends within 1.5 cm of pybullet's, having moved
    more than 9 cm, and turned the same way by within a quarter of pybullet's turn (over
    10°)."""
    task = _box_task((-0.14, 0.02))
    path = [np.array((-0.14 + 0.015 * k, 0.02)) for k in range(13)]
    ends = []
    for world_of in (SceneWorld, lambda t: ImaginedWorld(t, fq)):
        with world_of(task) as world:
            for a, b in itertools.pairwise(path):
                world.run_step({"pusher": a}, {"pusher": b}, 20)
            ends.append(world.observe().poses["box"])
    simulated, imagined = ends
    assert simulated[0] > 0.09
    assert np.hypot(*(imagined[:2] - simulated[:2])) < 0.015
    assert abs(simulated[2]) > math.radians(10.0)
    assert abs(imagined[2] - simulated[2]) < 0.25 * abs(simulated[2])


def test_a_scene_f_q_cannot_stand_in_for_is_refused(fq):
    for name in ("three_objects", "two_arm_left_only"):
        with pytest.raises(ValueError, match="one free pusher and one object"):
            ImaginedWorld(load_task(TASKS / f"{name}.yaml"), fq)
