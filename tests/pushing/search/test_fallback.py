"""A re-plan's tail and fresh search side by side (robotplan.pushing.search.fallback)."""

from __future__ import annotations

import numpy as np
import pytest

import robotplan
from robotplan.pushing.bench.push_scenes import draw_scene
from robotplan.pushing.program.tail import solution_tail
from robotplan.pushing.search.fallback import side_by_side
from robotplan.pushing.search.request import SearchRequest
from robotplan.scene.loader import parse_scene
from robotplan.scene.task import load_task
from tests.conftest import TASKS


@pytest.fixture(scope="module")
def pose_plan():
    scene = parse_scene(draw_scene(4, 0, "pose"))
    planned = robotplan.plan(scene, workers=2, progress=False, quiet=True)
    assert planned.solved
    return planned


def test_only_a_free_pushers_pose_re_plan_with_two_workers_runs_side_by_side(pose_plan):
    request = SearchRequest(pose_plan.task, pose_plan.options["model"], workers=2,
                            guesses={"tail": None})
    assert side_by_side(request)
    assert not side_by_side(request.but(workers=1))
    assert not side_by_side(request.but(guesses=None))
    assert not side_by_side(request.but(task=load_task(TASKS / "box_push.yaml")))  # a region


@pytest.mark.parametrize(("dx", "turn_deg", "tail_solves"), [(0.008, 5.0, True),
                                                             (0.2, 0.0, False)])
def test_side_by_side_plans_what_the_sequence_plans(pose_plan, dx, turn_deg, tail_solves):
    """Re-planned after its first push from ``dx`` m and ``turn_deg`` off: the tail and
    the fresh search side by side (2 workers) give the plan the tail-then-fresh sequence
    gives (1 worker): the tail's alone where it solves, else the fresh search's too."""
    best, obj = pose_plan.best, pose_plan.obj
    T = (len(best.q_obj) - 1) // len(best.skeleton.phases)
    x, y, yaw = best.q_obj[2 * T]
    observed = pose_plan.task.at(pose_plan.scene.with_state(
        {obj: (x + dx, y, yaw + np.radians(turn_deg))}))
    tail = solution_tail(best, 2 * T)
    warm = robotplan.PushPlan(observed, tail, True)
    both, sequence = (robotplan.plan(observed, workers=w, warm_start=warm, progress=False,
                                     quiet=True, time_budget=20.0, replan=True)
                      for w in (2, 1))
    assert both.solved and sequence.solved
    assert [c.skeleton for c in both.candidates] == [c.skeleton for c in sequence.candidates]
    assert [c.violation for c in both.candidates] == [c.violation for c in sequence.candidates]
    assert both.best.skeleton == sequence.best.skeleton and both.space == sequence.space
    assert (len(both.candidates) == 1) == tail_solves
    assert both.candidates[0].skeleton == tail.skeleton
