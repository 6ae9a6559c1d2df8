"""robotplan.scene.task: every example scene classified once into its task, and the scenes
the planner does not handle refused naming the field."""

from __future__ import annotations

import copy
from dataclasses import replace

import pytest
import yaml

import robotplan
from robotplan.scene import load_scene, parse_scene
from robotplan.scene.schema import PoseGoal
from robotplan.scene.task import (
    PUSH_CLASSES,
    HangTask,
    PushTask,
    UnsupportedScene,
    family_of,
    load_task,
    make_task,
)
from tests.conftest import TASKS

# scene file → (obj, actors, arms, goal, chained, touch_actor, classes)
PUSH_TASKS = {
    "box_push": ("box", ("pusher",), False, "region", None, None, ()),
    "lshape_push": ("ell", ("pusher",), False, "region", None, None, ()),
    "obstacle_push": ("box", ("pusher",), False, "region", None, None, ("obstacles",)),
    "three_objects": ("red", ("pusher",), False, "region", "blue", None, ("chains",)),
    "two_arm_handover": ("box", ("left", "right"), True, "region", None, None, ("arms",)),
    "two_arm_left_only": ("box", ("left", "right"), True, "region", None, None, ("arms",)),
    "two_arm_touch": ("box", ("left", "right"), True, "touch", None, "right", ("arms",)),
    "mesh_push": ("bracket", ("pusher",), False, "region", None, None, ()),
    "panda_handover": ("box", ("left", "right"), True, "region", None, None, ("arms",)),
    "panda_iiwa_touch": ("box", ("left", "right"), True, "touch", None, "right", ("arms",)),
}
HANG_TASKS = {"mug_hang": ("mug", "hook"), "mesh_mug_hang": ("mug", "hook")}


def _doc(name: str) -> dict:
    return copy.deepcopy(yaml.safe_load((TASKS / f"{name}.yaml").read_text()))


def test_every_task_file_is_classified():
    assert {p.stem for p in TASKS.glob("*.yaml")} == set(PUSH_TASKS) | set(HANG_TASKS)


@pytest.mark.parametrize("name", sorted(PUSH_TASKS))
def test_each_push_task_names_its_object_actors_goal_and_classes(name):
    obj, actors, arms, goal, chained, touch, classes = PUSH_TASKS[name]
    task = load_task(TASKS / f"{name}.yaml")
    assert isinstance(task, PushTask) and task.family == "push"
    assert (task.obj, task.actors, task.arms, task.goal) == (obj, actors, arms, goal)
    assert (task.chained, task.touch_actor, task.classes) == (chained, touch, classes)
    assert set(task.classes) <= set(PUSH_CLASSES)
    assert task.goal_object == (chained or obj) == task.scene.goal.object
    assert task.single == (not arms and chained is None)
    assert task.obstacles == ("obstacles" in classes)
    if arms:
        assert task.pusher is None
        assert task.actors == tuple(r.name for r in task.scene.robots)
    else:
        assert task.pusher is task.scene.pushers[0] and task.pusher.name == actors[0]
    assert (task.region is None) == (goal == "touch")
    assert obj in task.describe()
    assert task == make_task(load_scene(TASKS / f"{name}.yaml"))  # load_task: load, classify
    assert family_of(task.scene) == "push"


def test_the_hang_task_names_its_mug_and_hook():
    task = load_task(TASKS / "mug_hang.yaml")
    assert isinstance(task, HangTask) and task.family == "hang"
    assert (task.mug, task.hook) == HANG_TASKS["mug_hang"]
    assert family_of(task.scene) == "hang"
    assert "mug" in task.describe() and "hook" in task.describe()
    moved = task.scene.with_state({"mug": (0.1, 0.2, 0.3)})
    assert task.at(moved).scene is moved and task.at(moved).mug == task.mug


def test_a_pose_goal_is_in_the_pose_class_and_plans_its_footprint_as_the_region():
    scene = load_scene(TASKS / "obstacle_push.yaml")
    x, y, yaw = scene.objects[0].pose
    task = make_task(replace(scene, goal=PoseGoal("box", (x + 0.3, y, yaw + 0.5))))
    assert task.goal == "pose" and task.classes == ("obstacles", "pose")
    assert task.region is not None and task.region.pose == pytest.approx((x + 0.3, y, yaw + 0.5))


def test_the_task_at_observed_poses_is_the_same_task_in_the_moved_scene():
    task = load_task(TASKS / "three_objects.yaml")
    moved = task.scene.with_state({"red": (0.0, 0.1, 0.2)})
    observed = task.at(moved)
    assert observed.scene is moved and observed.scene.bodies["red"].pose == pytest.approx(
        (0.0, 0.1, 0.2))
    assert (observed.obj, observed.actors, observed.chained, observed.classes) == (
        task.obj, task.actors, task.chained, task.classes)
    assert task.scene.bodies["red"].pose != pytest.approx((0.0, 0.1, 0.2))  # the original stays


def _two_pushers() -> dict:
    doc = _doc("box_push")
    doc["pushers"].append({**doc["pushers"][0], "name": "other", "position": [-0.28, -0.2]})
    return doc


def _free_pusher_touch() -> dict:
    doc = _doc("box_push")
    doc["goal"] = {"type": "touch", "object": "box", "pusher": "pusher"}
    return doc


def _pusher_beside_arms() -> dict:
    doc = _doc("two_arm_handover")
    doc["pushers"] = copy.deepcopy(_doc("box_push")["pushers"])
    return doc


def _two_objects_unchained() -> dict:
    doc = _doc("three_objects")
    del doc["pushers"][0]["touches"]  # the pusher may touch blue itself: no chain
    return doc


def _chain_with_touch_goal() -> dict:
    doc = _doc("three_objects")
    doc["goal"] = {"type": "touch", "object": "blue", "pusher": "pusher"}
    return doc


@pytest.mark.parametrize(("make", "field", "words"), [
    (_two_pushers, "pushers", "only one free pusher"),
    (_free_pusher_touch, "goal", "touch goals are planned for robot arms only"),
    (_pusher_beside_arms, "pushers", "free pushers beside robot arms"),
    (_two_objects_unchained, "objects", "more than one movable object"),
    (_chain_with_touch_goal, "objects", "more than one movable object"),
], ids=["two-pushers", "free-pusher-touch", "pusher-beside-arms", "two-objects-no-chain",
        "chain-with-touch-goal"])
def test_a_valid_scene_the_planner_does_not_handle_is_refused_naming_the_field(
        make, field, words):
    scene = parse_scene(make())  # a valid scene file
    with pytest.raises(UnsupportedScene, match=words) as refused:
        make_task(scene)
    assert str(refused.value).startswith(f"{field}: ")
    assert isinstance(refused.value, ValueError)
    assert family_of(scene) == "push"  # still drawn and checked as a push scene


def test_unsupported_scene_is_one_class_everywhere():
    from robotplan import api

    assert robotplan.UnsupportedScene is UnsupportedScene is api.UnsupportedScene
    assert robotplan.make_task is make_task and robotplan.load_task is load_task
