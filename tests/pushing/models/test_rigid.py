"""F_q's geometry: Δq about the SDF's pivot, the rigid transform of points and SDFs (float64)."""

import math

import numpy as np
import pytest
import torch

from robotplan.models.spec import DynamicsSpec
from robotplan.pushing.models.rigid import (
    RigidMotion,
    load_rigid,
    moved_pivot_delta,
    moved_pose,
    save_rigid,
    sdf_pivot,
    transform_points,
)
from robotplan.pushing.training.samples import object_sdf
from robotplan.sdf import Workspace


@pytest.fixture
def poses():
    rng = np.random.default_rng(11)
    prev = torch.tensor(np.c_[rng.uniform(-0.3, 0.3, (16, 2)), rng.uniform(-3, 3, 16)])
    step = torch.tensor(np.c_[rng.normal(0, 0.02, (16, 2)), rng.normal(0, 0.1, 16)])
    return prev, prev + step


def _to_world(X: torch.Tensor, body: torch.Tensor) -> torch.Tensor:
    c, s = torch.cos(X[:, 2:3]), torch.sin(X[:, 2:3])
    return X[:, None, :2] + torch.stack((c * body[..., 0] - s * body[..., 1],
                                         s * body[..., 0] + c * body[..., 1]), -1)


def test_delta_q_moves_every_point_of_the_body_as_the_poses_do(poses):
    prev, now = poses
    pivot = prev[:, :2] + torch.tensor([0.03, -0.02], dtype=torch.float64)
    delta = moved_pivot_delta(pivot, prev, now)
    body = torch.tensor(np.random.default_rng(2).uniform(-0.1, 0.1, (16, 9, 2)))
    moved = transform_points(_to_world(prev, body), pivot, delta)
    assert torch.allclose(moved, _to_world(now, body), atol=1e-12)
    back = transform_points(moved, pivot, delta, inverse=True)
    assert torch.allclose(back, _to_world(prev, body), atol=1e-12)
    assert torch.all(delta[:, 2].abs() <= math.pi)


def test_moved_pose_undoes_moved_pivot_delta(poses):
    prev, now = poses
    pivot = prev[:, :2] + torch.tensor([-0.04, 0.02], dtype=torch.float64)
    moved = moved_pose(prev, pivot, moved_pivot_delta(pivot, prev, now))
    assert (moved[:, :2] - now[:, :2]).abs().max() < 1e-12
    turn = torch.remainder(moved[:, 2] - now[:, 2] + math.pi, 2 * math.pi) - math.pi
    assert turn.abs().max() < 1e-12


def test_the_next_sdf_is_the_previous_one_through_the_inverse_transform(poses):
    prev, now = poses
    params = torch.tensor([[0.08, 0.05, 0.1]], dtype=torch.float64).expand(16, 3)
    pivot = prev[:, :2]
    delta = moved_pivot_delta(pivot, prev, now)
    x = torch.tensor(np.random.default_rng(4).uniform(-0.5, 0.5, (16, 50, 2)))
    expected = object_sdf(params, now, x)
    got = object_sdf(params, prev, transform_points(x, pivot, delta, inverse=True))
    assert torch.allclose(got, expected, atol=1e-12)


def test_the_pivot_is_the_area_centroid_on_the_grid():
    ws = Workspace((0.0, 0.0), (1.4, 1.4), 0.01)
    grid = ws.points(torch.float64).reshape(-1, 2)
    X = torch.tensor([[0.123, -0.2, 0.4]], dtype=torch.float64)
    box = torch.tensor([[0.1, 0.06, 0.12]], dtype=torch.float64)  # thickness ≥ height: a box
    pivot = sdf_pivot(object_sdf(box, X, grid[None]), grid)
    assert torch.linalg.norm(pivot[0] - X[0, :2]) < 2e-3
    empty = sdf_pivot(torch.ones(1, len(grid), dtype=torch.float64), grid)
    assert torch.allclose(empty[0], grid.mean(0))


def test_outputs_are_scaled_and_the_folder_round_trips(tmp_path):
    spec = DynamicsSpec(kind="rigid", encoder="joint", grid=(35, 35), channels=(2, 2, 2),
                        sdf_features=8, hidden=(16,), out_scale=0.01, turn_scale=0.05)
    torch.manual_seed(0)
    model = RigidMotion(spec)
    inputs = torch.randn(4, 3, 35, 35)
    raw = model.head(model.features(inputs))
    assert torch.allclose(model(inputs), raw * torch.tensor([0.01, 0.01, 0.05]))
    save_rigid(model, tmp_path / "fq")
    again = load_rigid(tmp_path / "fq")
    assert torch.equal(again(inputs), model.eval()(inputs))
    (tmp_path / "flow").mkdir()
    (tmp_path / "flow" / "spec.json").write_text('{"kind": "flow"}')
    (tmp_path / "flow" / "weights.pt").write_bytes(b"")
    with pytest.raises(ValueError, match="kind"):
        load_rigid(tmp_path / "flow")
