"""Lint every robot folder (Menagerie-style): schema, files, limits, tip link, kinematics."""

import numpy as np
import pytest
import yaml

from robotplan.scene.reader import read
from robotplan.scene.robots import ROBOTS_DIR, available_models, load_robot_model

MODELS = available_models()


def test_there_is_at_least_the_iiwa():
    assert "iiwa" in MODELS


@pytest.mark.parametrize("name", MODELS)
def test_robot_folder_is_complete(name):
    folder = ROBOTS_DIR / name
    model = load_robot_model(name)
    assert model.name == name, "robot.yaml name must match its folder"
    assert model.urdf_path.is_file()
    assert model.within_limits(model.home)
    assert all(v > 0 for v in model.velocity_limits)
    text = (folder / "robot.yaml").read_text()
    assert read(type(model), yaml.safe_load(text)) == model


@pytest.mark.parametrize("name", MODELS)
def test_tip_forward_kinematics_moves_with_the_base(name):
    model = load_robot_model(name)
    a = model.tip_position(model.home, (0.0, 0.0, 0.0, 0.0))
    b = model.tip_position(model.home, (0.3, -0.2, 0.1, np.pi / 2))
    expected = np.array([-a[1] + 0.3, a[0] - 0.2, a[2] + 0.1])
    assert np.abs(b - expected).max() < 1e-9
    assert a[2] > 0.1, "the home pose keeps the tip above the table"


@pytest.mark.parametrize("name", MODELS)
def test_drake_and_pybullet_tip_kinematics_agree(name):
    """Drake's MultibodyPlant and pybullet load the same URDF: the tip centre agrees to
    1e-6 m on random configurations and bases, and Drake's Jacobian matches differences."""
    from robotplan.scene.robots import DrakeArm

    model = load_robot_model(name)
    rng = np.random.default_rng(0)
    lo, hi = np.array(model.joint_lower), np.array(model.joint_upper)
    for base in ((0.0, 0.0, 0.0, 0.0), (0.55, -0.3, 0.02, 2.5)):
        arm = DrakeArm(model, base)
        for _ in range(10):
            q = rng.uniform(lo, hi)
            p_drake = arm.tip_position(q)
            p_bullet = model.tip_position(tuple(q), base)
            assert np.abs(p_drake - p_bullet).max() < 1e-6, (q, p_drake, p_bullet)
    q = rng.uniform(lo, hi)
    J = arm.tip_jacobian(q)
    h = 1e-6
    fd = np.stack([(arm.tip_position(q + h * e) - arm.tip_position(q - h * e)) / (2 * h)
                   for e in np.eye(model.dof)], axis=1)
    assert J.shape == (3, model.dof) and np.abs(J - fd).max() < 1e-6


def test_a_folder_must_name_its_check_links_and_real_fixed_joints(tmp_path):
    from dataclasses import replace

    from robotplan.scene.reader import SchemaError
    from robotplan.scene.robots import RobotModel, welded_urdf

    data = yaml.safe_load((ROBOTS_DIR / "panda" / "robot.yaml").read_text())
    data.pop("check_links")
    with pytest.raises(SchemaError, match="check_links"):
        read(RobotModel, data)
    model = load_robot_model("panda")
    with pytest.raises(ValueError, match="no joint named 'finger'"):
        welded_urdf(model.source_urdf, ("finger",))
    assert replace(model, fixed_joints=()).urdf_path == model.source_urdf
