"""The point-cloud baselines of the paper's app. A.2 (eq. 12, Tabs. 3, 5, 6): each object's
boundary as the vertices marching squares (on 3D grids marching cubes) puts on the edges of
X_h where its SDF changes sign, encoded by a PointNet (a shared per-point MLP, max-pooled)
or a PointNet++ (local PointNets about farthest-point centroids first).

The encoder reads the same grids ``(M, C, *S)`` as the SDF encoders and makes the clouds
itself, so training and evaluation take it unchanged; the clouds are differentiable in the
grid values, so a functional on it is differentiated by autograd.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Protocol

import torch
from torch import Tensor, nn

from robotplan.models.spec import DynamicsSpec

__all__ = ["CloudSpec", "PointNet2Encoder", "PointNetEncoder", "boundary_clouds", "boundary_points",
           "cloud_encoder", "farthest_points", "grid_edges", "per_point_mlp"]


class CloudSpec(Protocol):
    """The fields of a model's spec the point-cloud encoders read (``DynamicsSpec`` and
    ``HangSpec`` have them)."""

    sdf_scale: float
    cloud_points: int
    cloud_widths: tuple[int, ...]
    cloud_encoder: str
    cloud_centroids: int
    cloud_neighbours: int
    cloud_local_widths: tuple[int, ...]
    cloud_local_scale: float


def boundary_points(phi: Tensor, points: Tensor) -> Tensor:
    """Where ``phi (*S)`` changes sign between neighbouring grid points ``points (*S, D)``
    (a 2D or 3D grid): the zero of the linear interpolation on each such edge, ``(n, D)``, in
    :func:`grid_edges` order. These are the vertices of the marching-squares (marching-cubes)
    mesh of φ = 0 (eq. 12)."""
    first, second = grid_edges(tuple(phi.shape), phi.device)
    flat, where = phi.reshape(-1), points.reshape(-1, points.shape[-1])
    cross = (flat[first] < 0) != (flat[second] < 0)
    a, b = first[cross], second[cross]
    t = (flat[a] / (flat[a] - flat[b]))[:, None]
    return where[a] + t * (where[b] - where[a])


@lru_cache(maxsize=8)
def grid_edges(shape: tuple[int, ...], device: torch.device) -> tuple[Tensor, Tensor]:
    """The flat indices ``(E,)`` of the two points of every edge of a grid of ``shape``: the
    last axis's edges first, then the axis before it, …; each axis's in row-major order of
    the edge's first point (for a 2D grid: rows' edges, then columns')."""
    index = torch.arange(math.prod(shape), device=device).reshape(shape)
    first, second = [], []
    for axis in reversed(range(len(shape))):
        first.append(index.narrow(axis, 0, shape[axis] - 1).reshape(-1))
        second.append(index.narrow(axis, 1, shape[axis] - 1).reshape(-1))
    return torch.cat(first), torch.cat(second)


def boundary_clouds(grids: Tensor, points: Tensor, n: int) -> Tensor:
    """Fixed-size boundary clouds of many grids at once: for each grid of ``grids (G, *S)``
    on ``points (*S, D)``, ``n`` of its :func:`boundary_points` evenly spaced through their
    order (the i-th is vertex ⌊i c / n⌋ of the grid's c, so short clouds repeat points; a
    grid without a sign change gives n copies of the origin), deterministic: ``(G, n, D)``.
    One batched pass, no per-grid loop and no host synchronisation, so the clouds of a
    training batch are made where the batch lives. Differentiable in the grid values (each
    vertex interpolates its edge's two values)."""
    g = grids.shape[0]
    first, second = grid_edges(tuple(grids.shape[1:]), grids.device)
    flat = grids.reshape(g, -1)
    inside = flat < 0
    cross = inside[:, first] ^ inside[:, second]  # (G, E)
    running = cross.to(torch.int32).cumsum(1, dtype=torch.int32)
    count = running[:, -1:]  # (G, 1)
    rank = torch.arange(n, device=grids.device, dtype=torch.int32) * count // n  # (G, n)
    # the edge of each wanted crossing: the first edge where the running count passes rank
    edge = torch.searchsorted(running, rank + 1).clamp(max=cross.shape[1] - 1)
    a, b = first[edge], second[edge]
    fa, fb = flat.gather(1, a), flat.gather(1, b)
    t = (fa / torch.where(cross.gather(1, edge), fa - fb, 1.0))[..., None]
    where = points.reshape(-1, points.shape[-1])
    pa, pb = where[a], where[b]
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
    """Indices ``(G, k)`` of ``k`` points of each of ``clouds (G, n, D)`` by farthest-point
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
    """Grids ``(M, C, *S)`` → features ``(M, C · features)``: per channel the boundary cloud
    of ``spec.cloud_points`` points (:func:`boundary_clouds`), scaled by ``spec.sdf_scale``,
    through the shared MLP ``spec.cloud_widths`` (ReLU), max-pooled, and a linear layer to
    ``features``. ``points (*S, D)`` are the grid points (default: the table grid X_h of a
    :class:`DynamicsSpec`, D = 2), ``features`` defaults to ``spec.sdf_features``."""

    def __init__(self, spec: CloudSpec | DynamicsSpec, points: Tensor | None = None,
                 features: int | None = None) -> None:
        super().__init__()
        self.spec = spec
        self.register_buffer("points", spec.workspace().points() if points is None
                             else points, persistent=False)
        self.mlp, width = per_point_mlp(self.point_width(), spec.cloud_widths)
        self.linear = nn.Linear(width, spec.sdf_features if features is None else features)

    @property
    def dims(self) -> int:
        """D, the dimension of the grid's points."""
        return self.points.shape[-1]

    def point_width(self) -> int:
        """Features per point the shared MLP reads: its coordinates."""
        return self.dims

    def clouds(self, grids: Tensor) -> Tensor:
        """The fixed-size boundary clouds ``(M, C, n, D)`` of grids ``(M, C, *S)``, m."""
        m, c = grids.shape[:2]
        clouds = boundary_clouds(grids.flatten(0, 1), self.points.to(grids.dtype),
                                 self.spec.cloud_points)
        return clouds.reshape(m, c, -1, self.dims)

    def point_features(self, grids: Tensor) -> Tensor:
        """What the shared MLP reads of each point, ``(M, C, n, point_width)``."""
        return self.clouds(grids) * self.spec.sdf_scale

    def forward(self, grids: Tensor) -> Tensor:
        pooled = self.mlp(self.point_features(grids)).amax(2)  # (M, C, width)
        return self.linear(pooled).flatten(1)


class PointNet2Encoder(PointNetEncoder):
    """PointNet++ (the paper's Tabs. 3, 5, 6 rows): one set-abstraction level before the
    global PointNet. Per cloud, ``spec.cloud_centroids`` points by :func:`farthest_points`;
    each with its ``spec.cloud_neighbours`` nearest cloud points, their offsets from it (m,
    times ``spec.cloud_local_scale``) through the local MLP ``spec.cloud_local_widths``,
    max-pooled; the centroids (scaled by ``spec.sdf_scale``) with those local features are
    the points of :class:`PointNetEncoder`'s shared MLP and max-pool."""

    def __init__(self, spec: CloudSpec | DynamicsSpec, points: Tensor | None = None,
                 features: int | None = None) -> None:
        super().__init__(spec, points, features)
        self.local, _ = per_point_mlp(self.dims, spec.cloud_local_widths)

    def point_width(self) -> int:
        return self.dims + self.spec.cloud_local_widths[-1]

    def point_features(self, grids: Tensor) -> Tensor:
        clouds = self.clouds(grids)
        m, c, n, d = clouds.shape
        flat = clouds.reshape(m * c, n, d)
        rows = torch.arange(m * c, device=grids.device)[:, None]
        centres = flat[rows, farthest_points(flat, self.spec.cloud_centroids)]  # (G, k, D)
        near = (centres[:, :, None] - flat[:, None]).square().sum(-1).topk(
            self.spec.cloud_neighbours, largest=False).indices  # (G, k, j)
        offsets = (flat[rows[..., None], near] - centres[:, :, None])
        local = self.local(offsets * self.spec.cloud_local_scale).amax(2)  # (G, k, L)
        points = torch.cat((centres * self.spec.sdf_scale, local), -1)
        return points.reshape(m, c, self.spec.cloud_centroids, -1)


def cloud_encoder(spec: CloudSpec | DynamicsSpec, points: Tensor | None = None,
                  features: int | None = None) -> PointNetEncoder:
    """The point-cloud encoder ``spec.cloud_encoder`` names (arguments as
    :class:`PointNetEncoder`'s)."""
    cls = PointNet2Encoder if spec.cloud_encoder == "pointnet2" else PointNetEncoder
    return cls(spec, points, features)
