"""robotplan.pushing.search.default_dynamics: the dynamics each task class plans with by default."""

from dataclasses import replace

import robotplan.pushing.search.default_dynamics as defaults
from robotplan.scene import load_scene
from robotplan.scene.schema import PoseGoal
from robotplan.scene.task import load_task, make_task
from tests.conftest import TASKS, assert_each_refused


def test_each_task_class_plans_with_its_own_default_dynamics(tmp_path):
    """skeletons/dynamics.yaml: a single free object takes ``default``; arms, chains,
    obstacles take their own rows; a bad table names its file and field."""
    table = defaults.load_default_dynamics()
    expected = {"box_push": table["default"], "lshape_push": table["default"],
                "three_objects": table["chains"], "two_arm_left_only": table["arms"],
                "obstacle_push": table["obstacles"]}
    for name, kind in expected.items():
        assert defaults.default_dynamics(load_task(TASKS / f"{name}.yaml")) == kind, name
    scene = load_scene(TASKS / "box_push.yaml")
    x, y, yaw = scene.objects[0].pose
    pose = make_task(replace(scene, goal=PoseGoal("box", (x + 0.1, y, yaw + 0.5))))
    assert pose.classes == ("pose",)
    assert defaults.default_dynamics(pose) == table.get("pose", table["default"])
    assert_each_refused(defaults.load_default_dynamics.__wrapped__,
                        tmp_path / "dynamics.yaml", (
        ("arms: flow", "'default'"),
        ("default: flow\npets: flow", "pets: not a task class"),
        ("default: quadratic", "default: 'quadratic' is not a dynamics kind")))
