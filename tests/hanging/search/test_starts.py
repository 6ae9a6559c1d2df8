"""Threaded starts of the hanging program: the arm through the handle's opening, and in real
pybullet a threaded pose clear of the hook hangs."""

import numpy as np
import pytest
import torch

from robotplan.hanging.execution.world import HangWorld
from robotplan.hanging.functionals.threading import HandleThreading
from robotplan.hanging.models.hang_model import HangSpec, HangSuccess
from robotplan.hanging.program.problem import HangProblem, HangSettings
from robotplan.hanging.scene.ranges import load_hang_ranges
from robotplan.hanging.search import starts as hang_starts
from robotplan.hanging.search.starts import start_pose, threaded_poses
from tests.conftest import TINY_HANG_SPEC


def scenes(n: int):
    ranges = load_hang_ranges()
    rngs = [np.random.default_rng([11, i]) for i in range(n)]
    return [(ranges.hook.sample(r), ranges.mug.sample(r)) for r in rngs]


@pytest.mark.parametrize("exact", [True, False])
def test_threaded_poses_have_the_arm_through_the_opening(rng, monkeypatch, exact):
    """Without the small turn and shift every pose is threaded on its part; with them (a
    narrow opening leaves a few millimetres) none is far off."""
    if exact:
        monkeypatch.setattr(hang_starts, "THREAD_TURN", 0.0)
        monkeypatch.setattr(hang_starts, "THREAD_SHIFT", 0.0)
    for hook, mug in scenes(4):
        X, parts = threaded_poses(mug, hook, rng, 32)
        assert X.shape == (32, 7) and parts.shape == (32,)
        assert np.allclose(np.linalg.norm(X[:, 3:], axis=1), 1.0) and (X[:, 3] >= 0).all()
        margins = HandleThreading(mug, hook).margins(torch.from_numpy(X)).numpy()
        own = margins[np.arange(32), parts]
        assert (own > 0).all() if exact else (own > -0.015).all() and np.median(own) > -0.002


def test_threaded_poses_clear_of_the_hook_hang_when_dropped(rng):
    """The premise of the threaded starts, in real pybullet: a mug threaded on the arm and
    not inside the hook stays on it after the drop and the kick."""
    clear, hung = 0, 0
    for hook, mug in scenes(3):
        X, _ = threaded_poses(mug, hook, rng, 12)
        with HangWorld(hook, mug) as world:
            for pose in X:
                result = world.drop(pose)
                clear += not result.collision_at_start
                hung += result.hangs and not result.collision_at_start
    assert clear >= 10 and hung >= 0.9 * clear, (clear, hung)


def test_a_threaded_start_is_the_pools_best_within_the_threaded_bound():
    hook, mug = scenes(1)[0]
    torch.manual_seed(0)
    problem = HangProblem(HangSuccess(HangSpec(**TINY_HANG_SPEC)).eval(), mug, hook)
    settings = HangSettings(thread_pool=24)
    pool, parts = threaded_poses(mug, hook, np.random.default_rng(3), 24)
    h, c = problem.evaluate(pool)
    problem.evaluations = 0
    X0, part = start_pose(problem, np.random.default_rng(3), settings)
    i = int(np.nonzero((pool == X0).all(axis=1))[0][0])
    clear = c <= settings.thread_collision_cm3
    assert part == parts[i] and problem.evaluations == 24
    if clear.any():
        assert clear[i] and h[i] == h[clear].min()
    else:
        assert c[i] == c.min()
    plain, none = start_pose(problem, np.random.default_rng(3), HangSettings(threading=False))
    assert none is None and plain.shape == (7,)


@pytest.mark.parametrize("threaded", [True, False])
def test_the_collision_bound_of_threaded_poses_is_their_own(threaded):
    s = HangSettings()
    assert s.collision_bound(threaded) == (s.thread_collision_cm3 if threaded
                                           else s.collision_cm3)
    assert s.thread_collision_cm3 >= s.collision_cm3
