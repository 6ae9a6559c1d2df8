"""Rigid transforms of SDFs: T(q)[φ](x) = φ(R(q)ᵀ (x − r(q))) (paper §4).

Two pose parametrisations are used:

* planar ``X_WB = (x, y, yaw)`` for bodies on the table, shape ``(..., 3)``;
  a position-only pose ``(x, y)`` of shape ``(..., 2)`` means ``yaw = 0``;
* spatial ``X_WB = (x, y, z, qw, qx, qy, qz)``, shape ``(..., 7)``: translation plus a
  unit quaternion (normalised here, so any non-zero quaternion is accepted).

Points carry their own leading batch dimensions and broadcast against the pose's:
``points (..., N, d)`` with ``pose (..., k)`` gives ``(..., N, d)``.
"""

from __future__ import annotations

import math

import numpy as np
import torch
from torch import Tensor

__all__ = [
    "planar_to_body",
    "planar_to_world",
    "quaternion_to_matrix",
    "spatial_to_body",
    "spatial_to_world",
    "uniform_poses",
    "wrap_angle",
]


def _planar_parts(pose: Tensor) -> tuple[Tensor, Tensor, Tensor]:
    """Translation ``(..., 1, 2)`` and cos/sin of yaw ``(..., 1)`` of a planar pose."""
    if pose.shape[-1] == 2:
        zero = torch.zeros_like(pose[..., :1])
        return pose[..., None, :], torch.ones_like(zero), zero
    if pose.shape[-1] != 3:
        raise ValueError(f"planar pose must have 2 or 3 entries, got shape {tuple(pose.shape)}")
    return pose[..., None, :2], torch.cos(pose[..., 2:3]), torch.sin(pose[..., 2:3])


def planar_to_body(points_W: Tensor, X_WB: Tensor) -> Tensor:
    """Express table-frame points in the body frame: ``p_B = R(yaw)ᵀ (p_W − t)``.

    Args:
        points_W: ``(..., N, 2)`` points in the table (world) frame.
        X_WB: ``(..., 3)`` pose ``(x, y, yaw)`` or ``(..., 2)`` position of the body.
    Returns:
        ``(..., N, 2)`` the same points in the body frame.
    """
    t, c, s = _planar_parts(X_WB)
    d = points_W - t
    dx, dy = d[..., 0], d[..., 1]
    return torch.stack((c * dx + s * dy, c * dy - s * dx), dim=-1)


def planar_to_world(points_B: Tensor, X_WB: Tensor) -> Tensor:
    """Inverse of :func:`planar_to_body`: ``p_W = R(yaw) p_B + t``. Shapes as there."""
    t, c, s = _planar_parts(X_WB)
    x, y = points_B[..., 0], points_B[..., 1]
    return torch.stack((c * x - s * y, s * x + c * y), dim=-1) + t


def quaternion_to_matrix(quat: Tensor) -> Tensor:
    """Rotation matrices ``(..., 3, 3)`` of quaternions ``(..., 4)`` ordered ``(w, x, y, z)``.

    The quaternion is normalised first, so the result is always a rotation.
    """
    q = quat / torch.linalg.vector_norm(quat, dim=-1, keepdim=True)
    w, x, y, z = q.unbind(-1)
    rows = (
        1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
        2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
        2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y),
    )
    return torch.stack(rows, dim=-1).reshape(*q.shape[:-1], 3, 3)


def spatial_to_body(points_W: Tensor, X_WB: Tensor) -> Tensor:
    """``p_B = Rᵀ (p_W − t)`` for points ``(..., N, 3)`` and poses ``(..., 7)``."""
    R = quaternion_to_matrix(X_WB[..., 3:])
    d = points_W - X_WB[..., None, :3]
    # p_B[n, i] = sum_j R[j, i] d[n, j]
    return torch.einsum("...ji,...nj->...ni", R, d)


def spatial_to_world(points_B: Tensor, X_WB: Tensor) -> Tensor:
    """``p_W = R p_B + t`` for points ``(..., N, 3)`` and poses ``(..., 7)``."""
    R = quaternion_to_matrix(X_WB[..., 3:])
    return torch.einsum("...ij,...nj->...ni", R, points_B) + X_WB[..., None, :3]


def uniform_poses(rng: np.random.Generator, centre: np.ndarray, size: float,
                  n: int) -> np.ndarray:
    """``n`` spatial poses ``(n, 7)``: positions uniform in the cube of edge ``size`` about
    ``centre (3,)``, orientations uniform on SO(3) (normalised Gaussian quaternions, w ≥ 0)."""
    pos = np.asarray(centre) + rng.uniform(-size / 2, size / 2, (n, 3))
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)
    return np.concatenate([pos, q], axis=1)


def wrap_angle(a: float) -> float:
    """An angle (rad) wrapped to [−π, π), e.g. the difference of two yaws; elementwise on
    numpy arrays and tensors."""
    return (a + math.pi) % (2 * math.pi) - math.pi
