"""robotplan.search.scene_classes: a scene's classes and the dynamics each plans with."""

import robotplan.search.scene_classes as classes
from robotplan.scene import load_scene
from tests.conftest import TASKS, assert_each_refused


def test_each_scene_class_plans_with_its_own_default_dynamics(tmp_path):
    """skeletons/dynamics.yaml: a single free object takes ``default``; arms, chains,
    obstacles take their own rows; a bad table names its file and field."""
    table = classes.load_default_dynamics()
    expected = {"box_push": table["default"], "lshape_push": table["default"],
                "three_objects": table["chains"], "two_arm_left_only": table["arms"],
                "obstacle_push": table["obstacles"]}
    for task, kind in expected.items():
        assert classes.default_dynamics(load_scene(TASKS / f"{task}.yaml")) == kind, task
    assert classes.scene_classes(load_scene(TASKS / "three_objects.yaml")) == ("chains",)
    assert classes.scene_classes(load_scene(TASKS / "box_push.yaml")) == ()
    assert_each_refused(classes.load_default_dynamics.__wrapped__,
                        tmp_path / "dynamics.yaml", (
        ("arms: flow", "'default'"),
        ("default: flow\npets: flow", "pets: not a scene class"),
        ("default: quadratic", "default: 'quadratic' is not a dynamics kind")))
