"""3D shapes against independent references: shapely in the (ρ, z) half-plane for solids of
revolution, trimesh's exact point-to-triangle distance for polyhedra."""

import numpy as np
import pytest
import shapely
import torch
import trimesh

from robotplan.sdf import Box, Box3D, Capsule, Cylinder, Extrusion, LShape, Mesh, Sphere


def radial_coords(pts: np.ndarray) -> np.ndarray:
    return np.stack([np.linalg.norm(pts[:, :2], axis=1), pts[:, 2]], axis=1)


def shapely_sdf(geom, pts2: np.ndarray) -> np.ndarray:
    d = shapely.distance(geom.boundary, shapely.points(pts2))
    return np.where(shapely.contains_xy(geom, pts2[:, 0], pts2[:, 1]), -d, d)


@pytest.fixture
def points(rng):
    return rng.uniform(-0.3, 0.3, (3000, 3))


def test_sphere(points):
    got = Sphere(0.1).sdf(torch.from_numpy(points)).numpy()
    assert np.abs(got - (np.linalg.norm(points, axis=1) - 0.1)).max() < 1e-12


def test_cylinder_against_rectangle_of_revolution(points):
    r, length = 0.08, 0.3
    ref = shapely_sdf(shapely.box(-r, -length / 2, r, length / 2), radial_coords(points))
    got = Cylinder(r, length).sdf(torch.from_numpy(points)).numpy()
    assert np.abs(got - ref).max() <= 1e-6


def test_capsule_against_segment_distance(points):
    r, length = 0.05, 0.2
    seg = shapely.LineString([(0, -length / 2), (0, length / 2)])
    d = shapely.distance(seg, shapely.points(radial_coords(points))) - r
    got = Capsule(r, length).sdf(torch.from_numpy(points)).numpy()
    assert np.abs(got - d).max() <= 1e-6


def trimesh_sdf(mesh: trimesh.Trimesh, pts: np.ndarray) -> np.ndarray:
    return -trimesh.proximity.signed_distance(mesh, pts)  # trimesh: positive inside


def test_box3d_against_trimesh_box(points):
    size = (0.2, 0.12, 0.06)
    ref = trimesh_sdf(trimesh.creation.box(extents=size), points)
    got = Box3D(size).sdf(torch.from_numpy(points)).numpy()
    assert np.abs(got - ref).max() <= 1e-6


def test_extruded_lshape_against_trimesh_extrusion(points):
    shape = LShape((0.24, 0.18), 0.07)
    mesh = trimesh.creation.extrude_polygon(shapely.Polygon(shape.outline()), 0.06)
    ref = trimesh_sdf(mesh, points)
    got = Extrusion(shape, 0.06).sdf(torch.from_numpy(points)).numpy()
    assert np.abs(got - ref).max() <= 1e-6


def test_mesh_sdf_matches_analytic_box_and_is_differentiable(points):
    size = (0.2, 0.12, 0.06)
    mesh = Mesh(trimesh.creation.box(extents=size))
    pts = torch.from_numpy(points[:500]).requires_grad_(True)
    got = mesh.sdf(pts)
    ref = Box3D(size).sdf(pts)
    assert (got - ref).abs().max() <= 1e-6
    (g_mesh,) = torch.autograd.grad(got.sum(), pts)
    (g_ref,) = torch.autograd.grad(Box3D(size).sdf(pts).sum(), pts)
    assert (g_mesh - g_ref).abs().max() < 1e-6


def test_mesh_requires_watertight():
    open_mesh = trimesh.Trimesh(vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0]], faces=[[0, 1, 2]])
    with pytest.raises(ValueError, match="watertight"):
        Mesh(open_mesh)


@pytest.mark.parametrize("shape", [Sphere(0.1), Box3D((0.1, 0.2, 0.3)), Cylinder(0.1, 0.2),
                                   Capsule(0.05, 0.2), Extrusion(Box((0.2, 0.1)), 0.06)])
def test_gradcheck_3d(shape, rng):
    pts = torch.from_numpy(rng.uniform(-0.25, 0.25, (8, 3))).requires_grad_(True)
    assert torch.autograd.gradcheck(shape.sdf, (pts,))


def test_se3_transform_of_an_sdf_against_a_transformed_mesh(rng):
    """T(q)[φ](x) = φ(R(q)ᵀ(x − r(q))) for a spatial pose (translation + unit quaternion)."""
    from scipy.spatial.transform import Rotation

    from robotplan.geometry.transforms import spatial_to_body

    size = (0.2, 0.12, 0.06)
    quat_xyzw = Rotation.from_euler("xyz", [0.3, -0.5, 1.1]).as_quat()
    t = np.array([0.05, -0.02, 0.1])
    X_WB = torch.tensor([*t, quat_xyzw[3], *quat_xyzw[:3]], dtype=torch.float64)
    mesh = trimesh.creation.box(extents=size)
    M = np.eye(4)
    M[:3, :3] = Rotation.from_quat(quat_xyzw).as_matrix()
    M[:3, 3] = t
    mesh.apply_transform(M)
    pts = rng.uniform(-0.3, 0.3, (2000, 3))
    got = Box3D(size).sdf(spatial_to_body(torch.from_numpy(pts), X_WB)).numpy()
    assert np.abs(got - trimesh_sdf(mesh, pts)).max() <= 1e-6
