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
    "carry_with_body",
    "perturbed_poses",
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


def carry_with_body(points_W: Tensor, X_from: Tensor, X_to: Tensor) -> Tensor:
    """Table-frame points ``(..., N, 2)`` moved rigidly with a body from ``X_from`` to
    ``X_to`` ``(..., 3)``: they keep their place in the body's frame."""
    return planar_to_world(planar_to_body(points_W, X_from), X_to)


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


def perturbed_poses(rng: np.random.Generator, X: np.ndarray, shift: float, turn: float,
                    n: int) -> np.ndarray:
    """``n`` spatial poses ``(n, 7)`` about ``X (7,)``: the position offset by a Gaussian of
    standard deviation ``shift`` (m) per axis, the orientation turned (in the body frame) by a
    rotation vector with standard deviation ``turn`` (rad) per axis; quaternions with w ≥ 0."""
    pos = np.asarray(X[:3]) + rng.normal(0.0, shift, (n, 3))
    v = rng.normal(0.0, turn, (n, 3))
    angle = np.linalg.norm(v, axis=1, keepdims=True)
    axis = v / np.maximum(angle, 1e-12)
    dq = np.concatenate([np.cos(angle / 2), axis * np.sin(angle / 2)], axis=1)
    w0, x0, y0, z0 = np.asarray(X[3:]) / np.linalg.norm(X[3:])
    w1, x1, y1, z1 = dq.T
    q = np.stack([w0 * w1 - x0 * x1 - y0 * y1 - z0 * z1,
                  w0 * x1 + x0 * w1 + y0 * z1 - z0 * y1,
                  w0 * y1 - x0 * z1 + y0 * w1 + z0 * x1,
                  w0 * z1 + x0 * y1 - y0 * x1 + z0 * w1], axis=1)
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)
    return np.concatenate([pos, q], axis=1)


def wrap_angle(a: float) -> float:
    """An angle (rad) wrapped to [−π, π), e.g. the difference of two yaws; elementwise on
    numpy arrays and tensors."""
    return (a + math.pi) % (2 * math.pi) - math.pi
