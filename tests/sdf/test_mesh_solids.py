"""Mugs and hooks from mesh files: the handle's opening and the hook's arm found from the
geometry match how the meshes were built (tasks/meshes/make_meshes.py)."""

from __future__ import annotations

import numpy as np
import pytest
import torch
import trimesh

from robotplan.geometry.meshes import read_mesh
from robotplan.sdf.mesh_solids import MeshHook, MeshMug, MeshSolidProblem
from tests.conftest import TASKS

HANG = TASKS / "meshes" / "hang"
STEP = 0.004  # coarser than the default: seconds per mesh


def test_the_square_handles_opening_lies_inside_it():
    """The bracket's opening: x from the wall (0.04) to 0.063, z from 0.03 to 0.08."""
    path = HANG / "mug_square_handle.stl"
    mug = MeshMug(read_mesh(path), path, step=STEP)
    x0, z0, a, b = mug.opening()
    assert 0.04 - 1e-3 <= x0 - a and x0 + a <= 0.063 + 1e-3, (x0, a)
    assert 0.03 - 1e-3 <= z0 - b and z0 + b <= 0.08 + 1e-3, (z0, b)
    assert a > 0.008 and b > 0.015  # most of the opening, not a sliver of it
    ring = np.linspace(0, 2 * np.pi, 32)
    points = torch.tensor(np.stack((x0 + a * np.cos(ring), np.zeros(32), z0 + b * np.sin(ring)),
                                   1))
    assert (mug.sdf(points) > -1e-9).all()  # the ellipse is free of the mug
    assert mug.reach == pytest.approx(np.hypot(0.04, 0.11), abs=1e-6)  # the rim's edge


def test_the_square_rods_arm_is_traced_from_its_post():
    """Built as 0.12 m at 0.15 rad then 0.04 m at 0.9 rad from (0, 0, 0.295), 1 cm bars."""
    path = HANG / "hook_square_rod.stl"
    hook = MeshHook(read_mesh(path), path, step=STEP)
    start = np.array([0.0, 0.0, 0.295])
    bend = start + 0.12 * np.array([np.cos(0.15), 0.0, np.sin(0.15)])
    tip = bend + 0.04 * np.array([np.cos(0.9), 0.0, np.sin(0.9)])
    arm = hook.arm_points()
    assert len(arm) == 3
    assert np.abs(arm - np.stack((start, bend, tip))).max() < 0.006
    assert 0.004 < hook.rod_radius < 0.008 and hook.post_height == pytest.approx(0.295, abs=0.003)
    lo, hi = hook.aabb()
    assert lo[2] == pytest.approx(0.0) and hi[0] > arm[:, 0].max()


def test_a_cup_without_a_handle_is_refused(tmp_path):
    profile = np.array([[0, 0], [0.04, 0], [0.04, 0.1], [0.034, 0.1], [0.034, 0.006],
                        [0, 0.006]])
    path = tmp_path / "cup.obj"
    trimesh.creation.revolve(profile, sections=32).export(str(path))
    with pytest.raises(MeshSolidProblem, match="no opening"):
        MeshMug(read_mesh(path), path, step=0.008)


def test_a_hook_without_an_arm_is_refused(tmp_path):
    post = trimesh.creation.cylinder(0.012, 0.3)
    post.apply_translation([0, 0, 0.15])
    path = tmp_path / "post.stl"
    post.export(str(path))
    with pytest.raises(MeshSolidProblem, match="arm"):
        MeshHook(read_mesh(path), path, step=0.008)
