"""Mugs and hooks against independent references: trimesh's meshes of the cup (a revolved
profile) and the post, densely sampled centre lines for the tubes, and a dense sampling of
the union's surface for the whole shapes; pose Jacobians in float64 against differences."""

import itertools
import math

import numpy as np
import pytest
import torch
import trimesh
from scipy.spatial import cKDTree

from robotplan.sdf.mug_hook import Hook, Mug, polyline_distance, sdf_at

MUG = Mug(radius=0.04, height=0.1, handle_height=0.55, handle_reach=0.03, handle_span=0.03)
HOOK = Hook(post_height=0.3, lengths=(0.12, 0.04, 0.03),
            angles=(math.radians(10), math.radians(60), math.radians(20)))


def trimesh_sdf(mesh: trimesh.Trimesh, pts: np.ndarray) -> np.ndarray:
    return -trimesh.proximity.signed_distance(mesh, pts)  # trimesh: positive inside


def assert_matches_mesh(got: np.ndarray, ref: np.ndarray) -> None:
    """A 512-gon differs from its circle by r (1 − cos(π/512)) < 1e-6 m; inside, trimesh's
    own closest points are off by up to 1.4e-5 m (checked by hand against the planes)."""
    outside = ref > 0
    assert np.all(np.sign(got) == np.sign(ref))
    assert np.abs(got - ref)[outside].max() < 2e-6
    assert np.abs(got - ref)[~outside].max() < 3e-5


def cup_mesh(mug: Mug, sections: int = 512) -> trimesh.Trimesh:
    """The cup revolved from its half profile (ρ ≥ 0) about z."""
    r, h, w = mug.radius, mug.height, mug.wall
    half = np.array([(0.0, 0.0), (r, 0.0), (r, h), (r - w, h), (r - w, w), (0.0, w)])
    return trimesh.creation.revolve(half, sections=sections)


def test_cup_matches_its_revolved_mesh(rng):
    pts = rng.uniform([-0.07, -0.07, -0.03], [0.07, 0.07, 0.13], (1000, 3))
    ref = trimesh_sdf(cup_mesh(MUG), pts)
    assert_matches_mesh(MUG.cup_sdf(torch.from_numpy(pts)).numpy(), ref)


def test_post_matches_its_cylinder_mesh(rng):
    pts = rng.uniform([-0.05, -0.05, -0.05], [0.05, 0.05, 0.35], (1000, 3))
    post = trimesh.creation.cylinder(HOOK.post_radius, HOOK.post_height, sections=512)
    post.apply_translation([0, 0, HOOK.post_height / 2])
    assert_matches_mesh(HOOK.post_sdf(torch.from_numpy(pts)).numpy(), trimesh_sdf(post, pts))


@pytest.mark.parametrize("line", [MUG.handle_points(), HOOK.arm_points()])
def test_polyline_distance_against_dense_samples(rng, line):
    dense = np.concatenate([a + np.linspace(0, 1, 4000)[:, None] * (b - a)
                            for a, b in itertools.pairwise(line)])
    pts = line.mean(0) + rng.uniform(-0.1, 0.1, (2000, 3))
    ref, _ = cKDTree(dense).query(pts)
    got = polyline_distance(torch.from_numpy(pts), line).numpy()
    assert np.all(got <= ref + 1e-12)  # the samples lie on the polyline
    assert np.abs(got - ref).max() < 3e-5  # spacing ≤ 0.15 mm / 2


def surface_samples(shape, parts: list, n: int, rng) -> np.ndarray:
    """Points on the union's surface: each part's surface samples that are not inside the
    union (the shape's own SDF ≥ −tiny decides)."""
    pts = np.concatenate([trimesh.sample.sample_surface_even(m, n, seed=int(rng.integers(1e9)))[0]
                          for m in parts])
    phi = shape.sdf(torch.from_numpy(pts)).numpy()
    return pts[phi > -1e-6]


def tube_meshes(line: np.ndarray, radius: float) -> list[trimesh.Trimesh]:
    return [trimesh.creation.capsule(height=float(np.linalg.norm(b - a)), radius=radius,
                                     count=[64, 64],
                                     transform=trimesh.geometry.align_vectors([0, 0, 1], b - a)
                                     @ np.eye(4)).apply_translation((a + b) / 2)
            for a, b in itertools.pairwise(line)]


@pytest.mark.parametrize("shape", [MUG, HOOK], ids=["mug", "hook"])
def test_union_is_exact_outside_against_its_sampled_surface(rng, shape):
    if isinstance(shape, Mug):
        parts = [cup_mesh(shape, 128), *tube_meshes(shape.handle_points(), shape.handle_radius)]
    else:
        post = trimesh.creation.cylinder(shape.post_radius, shape.post_height, sections=128)
        post.apply_translation([0, 0, shape.post_height / 2])
        parts = [post, *tube_meshes(shape.arm_points(), shape.rod_radius)]
    surface = surface_samples(shape, parts, 80_000, rng)
    lo, hi = surface.min(0) - 0.05, surface.max(0) + 0.05
    pts = rng.uniform(lo, hi, (2000, 3))
    phi = shape.sdf(torch.from_numpy(pts)).numpy()
    outside = phi > 0.005
    ref, _ = cKDTree(surface).query(pts[outside])
    assert outside.sum() > 1000
    # the meshes are inscribed (128-gons: ≤ r (1 − cos(π/128)) < 2e-5 m inside), and the
    # samples lie ~√(area / n) ≈ 1 mm apart
    assert np.all(ref >= phi[outside] - 2e-5)
    assert np.abs(ref - phi[outside]).max() < 1.5e-3


def test_mug_is_hollow_and_the_handle_is_a_loop():
    p = torch.tensor([[0.0, 0.0, 0.05],  # inside the cup, in the air
                      [MUG.radius - MUG.wall / 2, 0.0, 0.05],  # in the wall
                      [MUG.radius + MUG.handle_reach / 2, 0.0, 0.55 * MUG.height],  # in the loop
                      [MUG.radius + MUG.handle_reach + MUG.handle_radius, 0.0, 0.055]],
                     dtype=torch.float64)
    phi = MUG.sdf(p)
    assert phi[0] > 0.02 and phi[1] < 0 and phi[2] > 0.005 and phi[3] < 0


def test_hook_arm_has_one_to_three_parts():
    with pytest.raises(ValueError, match="one to three"):
        Hook(0.3, (0.1, 0.05, 0.05, 0.05), (0.0, 1.0, 0.5, 0.2))


def random_pose(rng) -> torch.Tensor:
    q = rng.normal(size=4)
    return torch.from_numpy(np.concatenate([rng.uniform(-0.1, 0.1, 3), q / np.linalg.norm(q)]))


@pytest.mark.parametrize("shape", [MUG, HOOK], ids=["mug", "hook"])
def test_pose_jacobian_against_central_differences(rng, shape):
    X = random_pose(rng).requires_grad_(True)
    pts = torch.from_numpy(rng.uniform(-0.15, 0.25, (64, 3)))
    assert torch.autograd.gradcheck(lambda x: sdf_at(shape, pts, x), (X,), eps=1e-7,
                                    atol=1e-6)


def test_posed_sdf_moves_with_the_pose(rng):
    X = random_pose(rng)
    local = torch.from_numpy(rng.uniform(-0.1, 0.15, (500, 3)))
    from robotplan.geometry.transforms import spatial_to_world

    world = spatial_to_world(local, X)
    assert torch.allclose(sdf_at(MUG, world, X), MUG.sdf(local), atol=1e-12)
