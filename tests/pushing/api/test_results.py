"""A push result's status: solved, reached, missed or no_solution, from the plan's status
and whether the simulator reached the goal by the loop's own bounds."""

import pytest

from robotplan.pushing.api.results import outcome_status
from robotplan.pushing.execution.loop_settings import LoopSettings
from robotplan.scene.task import load_task
from tests.conftest import TASKS


def test_a_region_goal_is_met_at_the_loops_coverage_and_a_touch_goal_within_its_gap():
    settings = LoopSettings()
    region = load_task(TASKS / "box_push.yaml")
    assert settings.goal_met(region, settings.goal_coverage, None)
    assert not settings.goal_met(region, settings.goal_coverage - 0.01, None)
    assert not settings.goal_met(region, None, None)
    touch = load_task(TASKS / "two_arm_touch.yaml")
    assert settings.goal_met(touch, None, settings.touch_gap / 2)
    assert not settings.goal_met(touch, None, 2 * settings.touch_gap)
    assert not settings.goal_met(touch, 1.0, None)


@pytest.mark.parametrize(("plan", "reached", "status"), [
    ("solved", True, "solved"),
    ("solved", None, "solved"),  # planned only
    ("solved", False, "missed"),
    ("no_solution", True, "reached"),
    ("no_solution", False, "missed"),
    ("no_solution", None, "no_solution"),
])
def test_the_status_tells_a_solved_plan_from_a_goal_reached_without_one(plan, reached, status):
    doc = {"plan_status": plan}
    if reached is not None:
        doc["execution"] = {"goal_reached": reached}
    assert outcome_status(doc) == status
