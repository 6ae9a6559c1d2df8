"""The point-cloud baseline of the paper's app. A.2 (eq. 12, Tabs. 5, 6): each object's
boundary as the vertices marching squares puts on the edges of X_h where its SDF changes
sign, encoded by a PointNet (a shared per-point MLP, max-pooled).

The encoder reads the same grids ``(M, C, H, W)`` as the SDF encoder and makes the clouds
itself, so training and evaluation of F_q take it unchanged; planning needs the SDF
encoder's reverse pass and does not take it.
"""

from __future__ import annotations

import torch
from torch import Tensor, nn

from robotplan.models.spec import DynamicsSpec

__all__ = ["PointNetEncoder", "boundary_points", "fixed_size_cloud"]


def boundary_points(phi: Tensor, points: Tensor) -> Tensor:
    """Where ``phi (H, W)`` changes sign between neighbouring grid points ``points (H, W,
    2)``: the zero of the linear interpolation on each such edge, ``(n, 2)`` (rows'
    edges first, then columns'; each in row-major order). These are the vertices of the
    marching-squares contour of φ = 0 (eq. 12)."""
    out = []
    for a, b, pa, pb in ((phi[:, :-1], phi[:, 1:], points[:, :-1], points[:, 1:]),
                         (phi[:-1], phi[1:], points[:-1], points[1:])):
        cross = (a < 0) != (b < 0)
        fa, fb = a[cross], b[cross]
        t = (fa / (fa - fb))[:, None]
        out.append(pa[cross] + t * (pb[cross] - pa[cross]))
    return torch.cat(out)


def fixed_size_cloud(cloud: Tensor, n: int) -> Tensor:
    """``n`` points of ``cloud (c, 2)`` evenly spaced through its order (repeated where c <
    n; the origin's n copies where c = 0), deterministic: ``(n, 2)``."""
    if len(cloud) == 0:
        return cloud.new_zeros(n, 2)
    return cloud[torch.arange(n) * len(cloud) // n]


class PointNetEncoder(nn.Module):
    """Grids ``(M, C, H, W)`` → features ``(M, C · sdf_features)``: per channel the
    boundary cloud of ``spec.cloud_points`` points (:func:`boundary_points`), in the table
    frame scaled by ``spec.sdf_scale``, through the shared MLP ``spec.cloud_widths``
    (ReLU), max-pooled, and a linear layer to ``spec.sdf_features``."""

    def __init__(self, spec: DynamicsSpec) -> None:
        super().__init__()
        self.spec = spec
        self.register_buffer("points", spec.workspace().points(), persistent=False)
        layers: list[nn.Module] = []
        width = 2
        for w in spec.cloud_widths:
            layers += [nn.Linear(width, w), nn.ReLU()]
            width = w
        self.mlp = nn.Sequential(*layers)
        self.linear = nn.Linear(width, spec.sdf_features)

    def clouds(self, grids: Tensor) -> Tensor:
        """The fixed-size boundary clouds ``(M, C, n, 2)`` of grids ``(M, C, H, W)``."""
        points = self.points.to(grids.dtype)
        n = self.spec.cloud_points
        return torch.stack([torch.stack([fixed_size_cloud(boundary_points(g, points), n)
                                         for g in sample]) for sample in grids])

    def forward(self, grids: Tensor) -> Tensor:
        clouds = self.clouds(grids) * self.spec.sdf_scale  # (M, C, n, 2)
        pooled = self.mlp(clouds).amax(2)  # (M, C, width)
        return self.linear(pooled).flatten(1)
