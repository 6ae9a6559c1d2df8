"""robotplan.pushing.program.solve: what a skeleton's solve checks before any program is built."""

from dataclasses import replace

import numpy as np
import pytest

from robotplan.pushing.program.settings import DEFAULT_SETTINGS
from robotplan.pushing.program.skeleton import Phase, Skeleton, space_for
from robotplan.pushing.program.solve import solve_skeleton
from robotplan.scene.task import load_task
from tests.conftest import TASKS


def test_a_guess_of_another_length_is_refused_before_any_program_is_built():
    """A warm-start guess whose states do not fit the skeleton's steps: a clear error
    instead of a failed size check inside Drake."""
    task = load_task(TASKS / "box_push.yaml")
    skeleton = Skeleton((Phase("reach", "pusher", "box", 0), Phase("push", "pusher", "box", 0)))
    space = space_for(task)
    with pytest.raises(ValueError, match="states"):
        solve_skeleton(task, skeleton, None, space, DEFAULT_SETTINGS,
                       guess={"q_obj": np.zeros((2 * space.steps_per_phase + 5, 3))})


def test_without_the_learned_stage_the_kinematic_plan_is_the_plan():
    """The analytic-model baseline (paper Fig. 6): no learned model is evaluated, and the
    quasi-static plan moves the box."""
    task = load_task(TASKS / "box_push.yaml")
    skeleton = Skeleton((Phase("reach", "pusher", "box", 0), Phase("push", "pusher", "box", 0)))
    settings = replace(DEFAULT_SETTINGS, learned_stage=False, warm_iterations=100)
    sol = solve_skeleton(task, skeleton, None, space_for(task), settings)
    assert sol.dynamics_mm2.size == 0 and "warm_start" not in sol.timings
    assert sol.violation < 0.1 and np.linalg.norm(sol.q_obj[-1, :2] - sol.q_obj[0, :2]) > 0.05
