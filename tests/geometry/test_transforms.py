import numpy as np
import torch
from scipy.spatial.transform import Rotation

from robotplan.geometry.transforms import (
    carry_with_body,
    planar_to_body,
    planar_to_world,
    quaternion_to_matrix,
    spatial_to_body,
    spatial_to_world,
)


def test_planar_round_trip_and_broadcast(rng):
    pts = torch.from_numpy(rng.uniform(-1, 1, (50, 2)))
    poses = torch.from_numpy(rng.uniform(-1, 1, (7, 3)) * [1, 1, 3])
    body = planar_to_body(pts, poses)
    assert body.shape == (7, 50, 2)
    back = planar_to_world(body, poses)
    assert torch.allclose(back, pts.expand(7, 50, 2), atol=1e-12)


def test_carried_points_keep_their_place_on_the_body(rng):
    """Points carried from X_from to X_to have the same body coordinates at both; a
    quarter turn about the body's origin takes (1, 0) off it to (0, 1)."""
    pts = torch.from_numpy(rng.uniform(-1, 1, (4, 6, 2)))
    X_from = torch.from_numpy(rng.uniform(-1, 1, (4, 3)) * [1, 1, 3])
    X_to = torch.from_numpy(rng.uniform(-1, 1, (4, 3)) * [1, 1, 3])
    moved = carry_with_body(pts, X_from, X_to)
    gap = planar_to_body(moved, X_to) - planar_to_body(pts, X_from)
    assert float(gap.abs().max()) < 1e-12
    quarter = carry_with_body(torch.tensor([[1.0, 0.0]], dtype=torch.float64),
                              torch.zeros(3, dtype=torch.float64),
                              torch.tensor([0.0, 0.0, np.pi / 2], dtype=torch.float64))
    assert float((quarter - torch.tensor([[0.0, 1.0]], dtype=torch.float64)).abs().max()) < 1e-12


def test_planar_matches_rotation_matrix(rng):
    x, y, yaw = 0.3, -0.2, 0.7
    p = rng.uniform(-1, 1, (20, 2))
    R = np.array([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])
    expected = (p - [x, y]) @ R  # R^T (p - t), row-vector form
    got = planar_to_body(torch.from_numpy(p), torch.tensor([x, y, yaw], dtype=torch.float64))
    assert np.abs(got.numpy() - expected).max() < 1e-12


def test_position_only_pose_means_zero_yaw(rng):
    p = torch.from_numpy(rng.uniform(-1, 1, (5, 2)))
    a = planar_to_body(p, torch.tensor([0.1, 0.2], dtype=torch.float64))
    b = planar_to_body(p, torch.tensor([0.1, 0.2, 0.0], dtype=torch.float64))
    assert torch.equal(a, b)


def test_quaternion_matches_scipy(rng):
    q = rng.normal(size=(10, 4))
    R = quaternion_to_matrix(torch.from_numpy(q)).numpy()
    ref = Rotation.from_quat(q[:, [1, 2, 3, 0]]).as_matrix()  # scipy: (x, y, z, w)
    assert np.abs(R - ref).max() < 1e-12


def test_spatial_round_trip(rng):
    pose = torch.from_numpy(np.concatenate([rng.normal(size=(4, 3)), rng.normal(size=(4, 4))], 1))
    pts = torch.from_numpy(rng.normal(size=(4, 30, 3)))
    back = spatial_to_world(spatial_to_body(pts, pose), pose)
    assert torch.allclose(back, pts, atol=1e-12)


def test_wrap_angle():
    import math

    import numpy as np

    from robotplan.geometry.transforms import wrap_angle

    a = np.array([0.0, 3.0, -3.0, 3.5, -3.5, 7.0, 2 * math.pi])
    w = wrap_angle(a)
    assert np.all((w >= -math.pi) & (w < math.pi))
    assert np.allclose(np.cos(w), np.cos(a)) and np.allclose(np.sin(w), np.sin(a))
    assert abs(wrap_angle(3.5) - (3.5 - 2 * math.pi)) < 1e-12
