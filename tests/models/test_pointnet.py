"""The point-cloud baseline (paper app. A.2, eq. 12): boundary clouds from SDF grids and the
PointNet encoder of F_q."""

import pytest
import torch

from robotplan.models.pointnet import (
    PointNet2Encoder,
    PointNetEncoder,
    boundary_clouds,
    boundary_points,
    farthest_points,
)
from robotplan.models.spec import DynamicsSpec
from robotplan.pushing.functionals.rigid_dynamics import RigidDynamics
from robotplan.pushing.models.rigid import RigidMotion
from robotplan.scene.bodies import Body
from robotplan.sdf import Box, Circle, Workspace

F64 = torch.float64
SPEC = {"kind": "rigid", "encoder": "joint", "representation": "pointcloud",
        "cloud_points": 32, "cloud_widths": (8, 16), "sdf_features": 8, "hidden": (16,)}


def disc_sdf(points: torch.Tensor, centre, radius: float) -> torch.Tensor:
    return (points - torch.tensor(centre, dtype=points.dtype)).norm(dim=-1) - radius


def test_the_boundary_points_lie_on_the_zero_level():
    points = Workspace().points(F64)
    cloud = boundary_points(disc_sdf(points, (0.1234, -0.2071), 0.1), points)
    gap = ((cloud - torch.tensor([0.1234, -0.2071], dtype=F64)).norm(dim=1) - 0.1).abs()
    # the disc's distance is linear along a cell edge up to its curvature: < 1 mm here
    assert gap.max() < 1e-3
    # one vertex per crossed edge: about 4 per cell of the diameter along each axis
    assert 60 <= len(cloud) <= 100


def test_fixed_size_clouds_pick_evenly_through_each_grid_boundary():
    points = Workspace().points(F64)
    torch.manual_seed(0)
    grids = torch.stack([disc_sdf(points, (0.1234, -0.2071), 0.1),
                         disc_sdf(points, (-0.2, 0.1), 0.006),  # a few crossings only
                         disc_sdf(points, (0.0, 0.0), 0.05) + 1.0,  # no sign change
                         torch.randn(points.shape[:2], dtype=F64)])
    for n in (5, 40, 300):
        clouds = boundary_clouds(grids, points, n)
        assert clouds.shape == (4, n, 2)
        for grid, cloud in zip(grids, clouds, strict=True):
            every = boundary_points(grid, points)
            if len(every) == 0:
                assert not cloud.any()
                continue
            picked = every[torch.arange(n) * len(every) // n]
            assert torch.equal(cloud, picked)


def test_a_shifted_object_shifts_its_cloud():
    enc = PointNetEncoder(DynamicsSpec(**SPEC)).double()
    points = Workspace().points(F64)
    grids = torch.stack((disc_sdf(points, (0.0, 0.0), 0.08),
                         disc_sdf(points, (0.03, -0.05), 0.08)))[:, None]
    a, b = enc.clouds(grids)[:, 0]
    assert torch.allclose(b - a, torch.tensor([0.03, -0.05], dtype=F64), atol=1e-12)


def test_farthest_points_spread_over_the_cloud():
    corners = torch.tensor([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]], dtype=F64)
    cloud = torch.cat((corners, 0.4 + 0.2 * torch.rand(60, 2, dtype=F64)))[None]
    picked = farthest_points(cloud, 4)[0].tolist()
    assert picked[0] == 0 and sorted(picked) == [0, 1, 2, 3]  # the corners, not the middle


def test_pointnet2_features_move_with_the_object_only_through_the_centroids():
    """A shifted object: its centroids shift with it and its local features stay (the
    offsets from each centroid are the same)."""
    enc = PointNet2Encoder(DynamicsSpec(**SPEC, cloud_encoder="pointnet2", cloud_centroids=8,
                                        cloud_neighbours=4, cloud_local_widths=(8,))).double()
    points = Workspace().points(F64)
    def blob(at):  # three discs, no mirror symmetry: no ties among the farthest points
        x, y = at
        return torch.stack([disc_sdf(points, (x + dx, y + dy), r) for dx, dy, r in
                            ((0.0, 0.0, 0.08), (0.07, 0.02, 0.05), (-0.03, 0.08, 0.035))]
                           ).amin(0)

    grids = torch.stack((blob((0.0, 0.0)), blob((0.03, -0.05))))[:, None]
    feats = enc.point_features(grids)[:, 0]  # (2, 8, 2 + 8)
    assert feats.shape == (2, 8, 10)
    shift = torch.tensor([0.03, -0.05], dtype=F64) * enc.spec.sdf_scale
    assert torch.allclose(feats[1, :, :2] - feats[0, :, :2], shift.expand(8, 2), atol=1e-12)
    # the boundary vertices of the shifted grid differ by rounding (~1e-9 m)
    assert torch.allclose(feats[1, :, 2:], feats[0, :, 2:], atol=1e-6)


@pytest.mark.parametrize("encoder", ["pointnet", "pointnet2"])
def test_a_point_cloud_f_q_trains_and_gives_the_planner_its_row(encoder):
    torch.manual_seed(0)
    model = RigidMotion(DynamicsSpec(**SPEC, cloud_encoder=encoder)).double()
    points = Workspace().points(F64)
    grids = torch.stack([torch.stack((disc_sdf(points, (0.01 * k, 0.0), 0.08),
                                      disc_sdf(points, (-0.15, 0.0), 0.02),
                                      disc_sdf(points, (-0.14, 0.0), 0.02)))
                         for k in range(3)])
    delta = model(grids)
    assert delta.shape == (3, 3) and torch.isfinite(delta).all()
    delta.square().sum().backward()
    assert all(p.grad is not None and p.grad.abs().sum() > 0
               for p in model.parameters())
    obj = Body("obj", "object", Box((0.2, 0.12)), (0, 0, 0), 0.0, 0.06)
    pusher = Body("pusher", "pusher", Circle(0.03), (0, 0, 0), 0.0, 0.06)
    X1 = torch.tensor([[0.0, 0.0, 0.0], [0.01, 0.0, 0.02]], dtype=F64)
    X2 = torch.tensor([[-0.128, 0.0017], [-0.118, 0.0017]], dtype=F64)
    H, J1, J2 = RigidDynamics(model, obj, pusher).evaluate(X1, X2)
    assert H.shape == (1,) and J1.shape == (1, 2, 3) and J2.shape == (1, 2, 2)
    assert torch.isfinite(J1).all() and J2.abs().sum() > 0


def test_marching_cubes_vertices_of_a_3d_grid():
    """On a 3D grid (the hang model's X_h) the vertices lie on the sphere's surface, and the
    fixed-size clouds pick evenly through them as in 2D."""
    axis = (torch.arange(20, dtype=F64) + 0.5) * 0.01 - 0.1
    points = torch.stack(torch.meshgrid(axis, axis, axis, indexing="ij"), -1)
    centre = torch.tensor([0.013, -0.021, 0.007], dtype=F64)
    phi = (points - centre).norm(dim=-1) - 0.05
    every = boundary_points(phi, points)
    gap = ((every - centre).norm(dim=1) - 0.05).abs()
    assert gap.max() < 1e-3 and every.shape[1] == 3
    # about 6 crossings per cell of the sphere's area (one per crossed edge, 3 axes)
    assert 0.5 < len(every) / (4 * torch.pi * 5.0**2) / 3 < 2.0
    grids = torch.stack((phi, phi + 1.0))
    clouds = boundary_clouds(grids, points, 50)
    assert clouds.shape == (2, 50, 3)
    assert torch.equal(clouds[0], every[torch.arange(50) * len(every) // 50])
    assert not clouds[1].any()
