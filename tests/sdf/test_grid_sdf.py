"""A mesh's SDF on a lattice: exact at the lattice points, smooth between them, the sign of
overlapping shells their union's, and sampled once per machine."""

from __future__ import annotations

import numpy as np
import pytest
import torch
import trimesh

from robotplan.sdf import Box3D
from robotplan.sdf.grid_sdf import mesh_sdf_lattice


@pytest.fixture
def box_file(tmp_path):
    path = tmp_path / "box.stl"
    trimesh.creation.box([0.1, 0.06, 0.04]).export(str(path))
    return path


def lattice_of(path, step=0.004):
    mesh = trimesh.load_mesh(str(path), force="mesh")
    return mesh_sdf_lattice(mesh, path, 1.0, np.zeros(3), step)


def test_exact_at_the_lattice_points_and_close_between(box_file, rng):
    grid = lattice_of(box_file)
    exact = Box3D((0.1, 0.06, 0.04))
    idx = np.stack([rng.integers(0, n, 300) for n in grid.values.shape], 1)
    at = torch.from_numpy(grid.lo + grid.step * idx)
    assert (grid.sdf(at) - exact.sdf(at)).abs().max() < 1e-9
    between = torch.from_numpy(rng.uniform(grid.lo, grid.hi, (2000, 3)))
    err = (grid.sdf(between) - exact.sdf(between)).abs()
    assert err.max() < grid.step  # a 1-Lipschitz field read trilinearly
    assert ((grid.sdf(between) < 0) == (exact.sdf(between) < 0)).float().mean() > 0.98
    far = torch.tensor([[0.5, 0.0, 0.0]], dtype=torch.float64)
    assert abs(float(grid.sdf(far)[0]) - 0.45) < grid.step  # beyond the box: a lower bound


def test_gradients_match_finite_differences(box_file, rng):
    grid = lattice_of(box_file)
    p = torch.from_numpy(rng.uniform(-0.05, 0.05, (20, 3))).requires_grad_(True)
    (g,) = torch.autograd.grad(grid.sdf(p).sum(), p)
    h = 1e-7
    for axis in range(3):
        e = torch.zeros(3, dtype=torch.float64)
        e[axis] = h
        fd = (grid.sdf(p.detach() + e) - grid.sdf(p.detach() - e)) / (2 * h)
        assert (fd - g[:, axis]).abs().max() < 1e-5


def test_overlapping_shells_count_as_their_union(tmp_path):
    a, b = trimesh.creation.box([0.1, 0.04, 0.04]), trimesh.creation.box([0.04, 0.1, 0.04])
    path = tmp_path / "cross.obj"
    trimesh.util.concatenate([a, b]).export(str(path))
    grid = lattice_of(path, 0.002)
    points = torch.tensor([[0.0, 0.0, 0.0], [0.04, 0.0, 0.0], [0.0, 0.04, 0.0],
                           [0.04, 0.04, 0.0]], dtype=torch.float64)
    phi = grid.sdf(points)
    assert (phi[:3] < 0).all() and phi[3] > 0


def test_the_lattice_is_sampled_once(box_file, monkeypatch):
    lattice_of(box_file)
    import robotplan.sdf.grid_sdf as module

    monkeypatch.setattr(module, "_sample", lambda *a: pytest.fail("sampled again"))
    assert lattice_of(box_file).values.shape[0] > 10
