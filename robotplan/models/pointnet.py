"""The point-cloud baselines of the paper's app. A.2 (eq. 12, Tabs. 5, 6): each object's
boundary as the vertices marching squares puts on the edges of X_h where its SDF changes
sign, encoded by a PointNet (a shared per-point MLP, max-pooled) or a PointNet++ (local
PointNets about farthest-point centroids first).

The encoder reads the same grids ``(M, C, H, W)`` as the SDF encoder and makes the clouds
itself, so training and evaluation of F_q take it unchanged; planning needs the SDF
encoder's reverse pass and does not take it.
"""

from __future__ import annotations

import torch
from torch import Tensor, nn

from robotplan.models.spec import DynamicsSpec

__all__ = ["PointNet2Encoder", "PointNetEncoder", "boundary_clouds", "boundary_points",
           "cloud_encoder", "farthest_points", "per_point_mlp"]


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


def per_point_mlp(width: int, widths: tuple[int, ...]) -> tuple[nn.Sequential, int]:
    """Linear + ReLU layers of ``widths`` from inputs of ``width`` features, applied to
    every point alike, and their output width."""
    layers: list[nn.Module] = []
    for w in widths:
        layers += [nn.Linear(width, w), nn.ReLU()]
        width = w
    return nn.Sequential(*layers), width


def farthest_points(clouds: Tensor, k: int) -> Tensor:
    """Indices ``(G, k)`` of ``k`` points of each of ``clouds (G, n, 2)`` by farthest-point
    sampling from the cloud's first point: each next point is the one farthest from those
    taken (the first of equals), so the picks spread over the whole boundary."""
    g, n, _ = clouds.shape
    rows = torch.arange(g, device=clouds.device)
    taken = torch.zeros((g, k), dtype=torch.long, device=clouds.device)
    gap = torch.full((g, n), torch.inf, dtype=clouds.dtype, device=clouds.device)
    last = torch.zeros(g, dtype=torch.long, device=clouds.device)
    for i in range(k):
        taken[:, i] = last
        gap = torch.minimum(gap, (clouds - clouds[rows, last][:, None]).square().sum(-1))
        last = gap.argmax(1)
    return taken


class PointNetEncoder(nn.Module):
    """Grids ``(M, C, H, W)`` → features ``(M, C · sdf_features)``: per channel the
    boundary cloud of ``spec.cloud_points`` points (:func:`boundary_clouds`), in the table
    frame scaled by ``spec.sdf_scale``, through the shared MLP ``spec.cloud_widths``
    (ReLU), max-pooled, and a linear layer to ``spec.sdf_features``."""

    def __init__(self, spec: DynamicsSpec) -> None:
        super().__init__()
        self.spec = spec
        self.register_buffer("points", spec.workspace().points(), persistent=False)
        self.mlp, width = per_point_mlp(self.point_width(), spec.cloud_widths)
        self.linear = nn.Linear(width, spec.sdf_features)

    def point_width(self) -> int:
        """Features per point the shared MLP reads: its coordinates."""
        return 2

    def clouds(self, grids: Tensor) -> Tensor:
        """The fixed-size boundary clouds ``(M, C, n, 2)`` of grids ``(M, C, H, W)``, m."""
        m, c, h, w = grids.shape
        clouds = boundary_clouds(grids.reshape(m * c, h, w), self.points.to(grids.dtype),
                                 self.spec.cloud_points)
        return clouds.reshape(m, c, -1, 2)

    def point_features(self, grids: Tensor) -> Tensor:
        """What the shared MLP reads of each point, ``(M, C, n, point_width)``."""
        return self.clouds(grids) * self.spec.sdf_scale

    def forward(self, grids: Tensor) -> Tensor:
        pooled = self.mlp(self.point_features(grids)).amax(2)  # (M, C, width)
        return self.linear(pooled).flatten(1)


class PointNet2Encoder(PointNetEncoder):
    """PointNet++ (the paper's Tabs. 5, 6 row): one set-abstraction level before the global
    PointNet. Per cloud, ``spec.cloud_centroids`` points by :func:`farthest_points`; each
    with its ``spec.cloud_neighbours`` nearest cloud points, their offsets from it (m,
    times ``spec.cloud_local_scale``) through the local MLP ``spec.cloud_local_widths``,
    max-pooled; the centroids (scaled by ``spec.sdf_scale``) with those local features are
    the points of :class:`PointNetEncoder`'s shared MLP and max-pool."""

    def __init__(self, spec: DynamicsSpec) -> None:
        super().__init__(spec)
        self.local, _ = per_point_mlp(2, spec.cloud_local_widths)

    def point_width(self) -> int:
        return 2 + self.spec.cloud_local_widths[-1]

    def point_features(self, grids: Tensor) -> Tensor:
        clouds = self.clouds(grids)
        m, c, n, _ = clouds.shape
        flat = clouds.reshape(m * c, n, 2)
        rows = torch.arange(m * c, device=grids.device)[:, None]
        centres = flat[rows, farthest_points(flat, self.spec.cloud_centroids)]  # (G, k, 2)
        near = (centres[:, :, None] - flat[:, None]).square().sum(-1).topk(
            self.spec.cloud_neighbours, largest=False).indices  # (G, k, j)
        offsets = (flat[rows[..., None], near] - centres[:, :, None])
        local = self.local(offsets * self.spec.cloud_local_scale).amax(2)  # (G, k, L)
        points = torch.cat((centres * self.spec.sdf_scale, local), -1)
        return points.reshape(m, c, self.spec.cloud_centroids, -1)


def cloud_encoder(spec: DynamicsSpec) -> PointNetEncoder:
    """The point-cloud encoder ``spec.cloud_encoder`` names."""
    return PointNet2Encoder(spec) if spec.cloud_encoder == "pointnet2" else PointNetEncoder(spec)
