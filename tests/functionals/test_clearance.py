"""Clearance of a planned object motion from the obstacles (robotplan.functionals.clearance)."""

import math

import numpy as np
import pytest

from robotplan import load_scene
from robotplan.functionals.clearance import densify, obstacle_clearance
from tests.conftest import ROOT

SCENE = ROOT / "tasks" / "obstacle_push.yaml"  # box 0.12 × 0.12; wall 0.06 × 0.30 at x = 0.05


def test_densify_keeps_the_poses_and_bounds_the_steps():
    poses = np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.2], [0.1, 0.0, 0.2], [0.1, 0.03, 0.0]])
    dense = densify(poses, 0.02)
    assert np.linalg.norm(np.diff(dense[:, :2], axis=0), axis=1).max() <= 0.02 + 1e-12
    for pose in poses:
        assert np.isclose(dense, pose).all(axis=1).any()
    assert np.isclose(dense[3], [0.06, 0.0, 0.12]).all()  # yaw interpolated with x


def test_clearance_of_a_box_passing_over_the_wall():
    scene = load_scene(SCENE)
    xs = np.linspace(-0.25, 0.35, 7)
    # the box's lower face at y − 0.06; the wall's top at 0.15
    for y, expected in ((0.25, 0.04), (0.23, 0.02), (0.20, -0.01)):
        poses = np.column_stack((xs, np.full(7, y), np.zeros(7)))
        assert obstacle_clearance(scene, "box", poses) == pytest.approx(expected, abs=1e-9)
    # a turned box reaches down by its half-diagonal's projection: 0.06·(cos θ + sin θ)
    theta = 0.3
    poses = np.column_stack((xs, np.full(7, 0.25), np.full(7, theta)))
    reach = 0.06 * (math.cos(theta) + math.sin(theta))
    assert obstacle_clearance(scene, "box", poses) == pytest.approx(0.10 - reach, abs=1e-9)


def test_a_thin_wall_between_two_poses_is_seen():
    scene = load_scene(SCENE)
    # straight through the wall: both ends clear it, the motion does not
    poses = np.array([[-0.25, 0.0, 0.0], [0.35, 0.0, 0.0]])
    assert obstacle_clearance(scene, "box", poses[:1]) > 0.1
    assert obstacle_clearance(scene, "box", poses) < 0.0


def test_no_obstacles_no_limit():
    scene = load_scene(ROOT / "tasks" / "box_push.yaml")
    assert obstacle_clearance(scene, "box", np.zeros((3, 3))) == math.inf
