"""The rest of a plan from one of its states on (what the closed loop re-plans), and an
earlier plan re-anchored at a moved start."""

import numpy as np
import pytest

from robotplan.pushing.program.skeleton import Phase, Skeleton
from robotplan.pushing.program.solution import Solution
from robotplan.pushing.program.solve import warm_guess
from robotplan.pushing.program.tail import solution_tail
from robotplan.scene.task import load_task
from tests.conftest import TASKS

T = 3


@pytest.fixture
def plan() -> Solution:
    """reach, push, reach, push of T = 3 steps: state t has x = t; contact row k has x = k."""
    phases = tuple(Phase(m, "pusher", "box", 0) for m in ("reach", "push", "reach", "push"))
    N = 4 * T
    q = np.stack([np.arange(N + 1.0), np.zeros(N + 1), np.full(N + 1, 0.1)], axis=1)
    contact = np.stack([np.arange(2.0 * T), np.ones(2 * T)], axis=1)
    return Solution(Skeleton(phases), True, "", 0.0, 0.0, 0.0, q, q[:, :2] - 0.5, contact)


def test_the_tail_at_a_phase_end_is_the_rest_of_the_plan(plan):
    tail = solution_tail(plan, 2 * T)
    assert tail.skeleton.phases == plan.skeleton.phases[2:]
    assert np.array_equal(tail.q_obj, plan.q_obj[2 * T:])
    assert np.array_equal(tail.q_pusher, plan.q_pusher[2 * T:])
    assert np.array_equal(tail.contact, plan.contact[T:])  # the second push's rows


def test_a_phase_cut_midway_is_done_again_over_its_full_steps(plan):
    t = T + 1  # one step into the first push
    tail = solution_tail(plan, t)
    assert tail.skeleton.phases == plan.skeleton.phases[1:]
    assert len(tail.q_obj) == 3 * T + 1
    assert np.allclose(tail.q_obj[0], plan.q_obj[t])  # starts where the plan is now
    assert np.allclose(tail.q_obj[T], plan.q_obj[2 * T])  # the phase still ends there
    assert np.all(np.diff(tail.q_obj[:T + 1, 0]) > 0)  # stretched, in order
    assert np.array_equal(tail.q_obj[T:], plan.q_obj[2 * T:])
    first = tail.contact[:T]  # the remaining rows of the first push, stretched to T
    assert len(tail.contact) == 2 * T
    assert first[0, 0] == pytest.approx(1.0) and first[-1, 0] == pytest.approx(T - 1)
    assert solution_tail(plan, 4 * T) is None


def test_warm_guess_starts_at_the_moved_object_and_ends_where_the_plan_did():
    task = load_task(TASKS / "box_push.yaml")
    x, y, yaw = task.scene.bodies["box"].pose
    phases = (Phase("reach", "pusher", "box", 0), Phase("push", "pusher", "box", 0))
    N = 2 * T
    q_obj = np.array([[x, y, yaw]] * (T + 1) + [[x + 0.05 * k, y, yaw] for k in range(1, T + 1)])
    q_pusher = q_obj[:, :2] - [0.15, 0.0]
    contact = q_obj[T + 1:, :2] - [0.1, 0.0]
    sol = Solution(Skeleton(phases), True, "", 0.0, 0.0, 0.0, q_obj, q_pusher, contact)
    moved = task.scene.with_state({"box": (x + 0.03, y - 0.02, yaw + 0.2)})
    guess = warm_guess(task.at(moved), sol)
    assert np.allclose(guess["q_obj"][0], moved.bodies["box"].pose)
    assert np.allclose(guess["q_obj"][N], q_obj[N])  # the correction fades out
    assert np.allclose(guess["q_pusher"][0], moved.bodies["pusher"].pose[:2])
    # a contact point stays where it was on the object: its distance to the object's
    # position is kept (the rigid motion carries both)
    k = 0  # the first push row: state T + 1
    before = np.linalg.norm(contact[k] - q_obj[T + 1, :2])
    after = np.linalg.norm(guess["p"][k] - guess["q_obj"][T + 1, :2])
    assert after == pytest.approx(before)

