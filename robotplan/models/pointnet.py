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

__all__ = ["PointNetEncoder", "boundary_clouds", "boundary_points"]


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


def boundary_clouds(grids: Tensor, points: Tensor, n: int) -> Tensor:
    """Fixed-size boundary clouds of many grids at once: for each grid of ``grids (G, H,
    W)`` on ``points (H, W, 2)``, ``n`` of its :func:`boundary_points` evenly spaced through
    their order (the i-th is vertex ⌊i c / n⌋ of the grid's c, so short clouds repeat
    points; a grid without a sign change gives n copies of the origin), deterministic:
    ``(G, n, 2)``. One batched pass, no per-grid loop and no host synchronisation, so the
    clouds of a training batch are made where the batch lives."""
    g, h, w = grids.shape
    inside = grids < 0
    # every edge of the grid, rows' edges first, then columns', each in row-major order
    cross = torch.cat(((inside[:, :, :-1] ^ inside[:, :, 1:]).reshape(g, -1),
                       (inside[:, :-1] ^ inside[:, 1:]).reshape(g, -1)), 1)
    running = cross.to(torch.int32).cumsum(1, dtype=torch.int32)  # (G, E)
    count = running[:, -1:]  # (G, 1)
    rank = torch.arange(n, device=grids.device, dtype=torch.int32) * count // n  # (G, n)
    # the edge of each wanted crossing: the first edge where the running count passes rank
    edge = torch.searchsorted(running, rank + 1).clamp(max=cross.shape[1] - 1)
    # its two grid points as flat indices into (H · W)
    rows_edges = h * (w - 1)
    along_row = edge < rows_edges
    first = torch.where(along_row, edge // (w - 1) * w + edge % (w - 1), edge - rows_edges)
    second = first + torch.where(along_row, 1, w)
    flat = grids.reshape(g, -1)
    fa, fb = flat.gather(1, first), flat.gather(1, second)
    t = (fa / torch.where(cross.gather(1, edge), fa - fb, 1.0))[..., None]
    pa, pb = points.reshape(-1, 2)[first], points.reshape(-1, 2)[second]
    cloud = pa + t * (pb - pa)
    return torch.where(count[..., None] > 0, cloud, 0.0)


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
        m, c, h, w = grids.shape
        clouds = boundary_clouds(grids.reshape(m * c, h, w), self.points.to(grids.dtype),
                                 self.spec.cloud_points)
        return clouds.reshape(m, c, -1, 2)

    def forward(self, grids: Tensor) -> Tensor:
        clouds = self.clouds(grids) * self.spec.sdf_scale  # (M, C, n, 2)
        pooled = self.mlp(clouds).amax(2)  # (M, C, width)
        return self.linear(pooled).flatten(1)
