"""Procedural mugs and hooks of the hanging task (paper §7.1, app. H) as exact 3D SDFs.

Both are unions of simple parts, each with an exact SDF; the union's SDF is the least of
the parts' (exact outside the union, a lower bound of the depth inside where parts
overlap). Frames:

* mug ``M``: origin at the centre of the bottom, z up the mug's axis, the handle towards
  +x in the xz-plane;
* hook ``H``: origin at the foot of the post on the ground, z up, the arm leaving the top of
  the post towards +x in the xz-plane.

``sdf(p)`` takes points ``(..., 3)`` in the shape's frame; ``sdf_at(points_W, X_WB)`` takes
world points ``(..., N, 3)`` and a spatial pose ``(..., 7)`` ``(x, y, z, qw, qx, qy, qz)``
and is differentiable in both (the transform T(q) of paper §4).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch
from torch import Tensor

from robotplan.geometry.transforms import spatial_to_body
from robotplan.sdf.closed_form import safe_norm
from robotplan.sdf.shapes3d import Shape3D

__all__ = ["MUG_FIELDS", "Hook", "Mug", "cup_sdf", "handle_points", "mug_sdf",
           "polyline_distance", "sdf_at"]

MUG_FIELDS = ("radius", "height", "handle_height", "handle_reach", "handle_span", "wall",
              "handle_radius")


def polyline_distance(p: Tensor, points: np.ndarray | Tensor) -> Tensor:
    """Euclidean distance ``(..., N)`` of points ``(..., N, 3)`` from the polyline through
    ``points`` ``(K, 3)``, or ``(..., K, 3)`` one per leading index (K ≥ 2): the least distance
    to its segments, exact."""
    pts = torch.as_tensor(points, dtype=p.dtype, device=p.device)
    best: Tensor | None = None
    for k in range(pts.shape[-2] - 1):
        a = pts[..., k:k + 1, :]  # (..., 1, 3)
        e = pts[..., k + 1:k + 2, :] - a
        w = p - a
        t = ((w * e).sum(-1) / (e * e).sum(-1)).clamp(0.0, 1.0)
        d = safe_norm(w - t[..., None] * e)
        best = d if best is None else torch.minimum(best, d)
    assert best is not None, "a polyline has at least two points"
    return best


def _segment_d2(px: Tensor, pz: Tensor, a: tuple[Tensor, Tensor],
                b: tuple[Tensor, Tensor]) -> Tensor:
    """Squared distance of 2D points from segments a–b (endpoints broadcast)."""
    ex, ez = b[0] - a[0], b[1] - a[1]
    wx, wz = px - a[0], pz - a[1]
    t = ((wx * ex + wz * ez) / (ex * ex + ez * ez)).clamp(0.0, 1.0)
    dx, dz = wx - ex * t, wz - ez * t
    return dx * dx + dz * dz


def _planar_polyline_d2(px: Tensor, pz: Tensor, xs: Tensor, zs: Tensor) -> Tensor:
    """Least squared distance of 2D points ``(..., N)`` from polylines ``xs, zs (..., K)``."""
    best: Tensor | None = None
    for k in range(xs.shape[-1] - 1):
        d2 = _segment_d2(px, pz, (xs[..., k:k + 1], zs[..., k:k + 1]),
                         (xs[..., k + 1:k + 2], zs[..., k + 1:k + 2]))
        best = d2 if best is None else torch.minimum(best, d2)
    assert best is not None, "a polyline has at least two points"
    return best


def _sqrt(d2: Tensor) -> Tensor:
    return (d2 + 1e-30).sqrt() - 1e-15  # gradient 0, not NaN, at 0; value exact to 1e-15


def cup_sdf(params: Tensor, p: Tensor) -> Tensor:
    """Exact SDF ``(..., N)`` of open cups at points ``(..., N, 3)``; ``params (..., 7)`` in
    :data:`MUG_FIELDS` order (radius, height and wall used). In the meridian half-plane
    (ρ, z), ρ ≥ 0, the cup is a U: the bottom slab and the wall; its distance is the least
    distance to the U's boundary (the axis is not part of it), its sign from containment."""
    r, h, w = (params[..., i:i + 1] for i in (0, 1, 5))
    rho, z = safe_norm(p[..., :2]), p[..., 2]
    zero = torch.zeros_like(r)
    xs = torch.cat((zero, r, r, r - w, r - w, zero), dim=-1)
    zs = torch.cat((zero, zero, h, h, w, w), dim=-1)
    d = _sqrt(_planar_polyline_d2(rho, z, xs, zs))
    inside = (z >= 0) & (rho <= r) & ((z <= w) | ((z <= h) & (rho >= r - w)))
    return torch.where(inside, -d, d)


def handle_points(params: Tensor, segments: int) -> Tensor:
    """The handles' centre lines ``(..., segments + 1, 3)`` (see :class:`Mug`)."""
    r, h, hh, reach, span, _, hr = params.unbind(-1)
    s = torch.linspace(-math.pi / 2, math.pi / 2, segments + 1, dtype=params.dtype,
                       device=params.device)
    x = (r - hr)[..., None] + (reach + hr)[..., None] * torch.cos(s)
    z = (hh * h)[..., None] - span[..., None] * torch.sin(s)
    return torch.stack((x, torch.zeros_like(x), z), dim=-1)


def mug_sdf(params: Tensor, p: Tensor, segments: int = 8) -> Tensor:
    """SDF ``(..., N)`` of mugs ``params (..., 7)`` (one per leading index) at points
    ``(..., N, 3)`` of their own frames: the cup and the handle's tube. The handle's centre
    line lies in the plane y = 0, so its squared distance is y² plus the in-plane one."""
    line = handle_points(params, segments)
    x, y, z = p.unbind(-1)
    d2 = _planar_polyline_d2(x, z, line[..., 0], line[..., 2]) + y * y
    return torch.minimum(cup_sdf(params, p), _sqrt(d2) - params[..., 6:7])


@dataclass(frozen=True)
class Mug(Shape3D):
    """A mug: an open cylindrical cup and a handle.

    ``radius`` (outer) and ``height`` of the cup, wall and bottom ``wall`` thick; the handle
    is a tube of radius ``handle_radius`` around a half-ellipse in the xz-plane whose ends
    sit on the cup's outer wall: centred at ``handle_height`` (a fraction of ``height``),
    reaching ``handle_reach`` out from the wall and spanning ``handle_span`` up and down."""

    radius: float
    height: float
    handle_height: float
    handle_reach: float
    handle_span: float
    wall: float = 0.006
    handle_radius: float = 0.005
    handle_segments: int = 8

    def params(self, dtype: torch.dtype = torch.float64) -> Tensor:
        """``(7,)`` in :data:`MUG_FIELDS` order, for the batched :func:`mug_sdf`."""
        return torch.tensor([getattr(self, f) for f in MUG_FIELDS], dtype=dtype)

    def opening(self) -> tuple[float, float, float, float]:
        """The handle's opening in the mug's plane y = 0: the half-ellipse inside the tube,
        ``(x0, z0, a, b)``: its centre ``(x0, z0)`` (on the centre line's axis, inside the
        wall) and semi-axes ``a`` (along x) and ``b`` (along z); the opening is the part of
        that ellipse outside the cup, x ≥ ``radius``."""
        return (self.radius - self.handle_radius, self.handle_height * self.height,
                self.handle_reach, self.handle_span - self.handle_radius)

    @property
    def reach(self) -> float:
        """A bound on the distance of the mug's points from its frame's origin (m)."""
        return float(np.hypot(self.radius + self.handle_reach + self.handle_radius,
                              self.height))

    def handle_points(self) -> np.ndarray:
        """The handle's centre line ``(segments + 1, 3)``: a half-ellipse from the top
        attachment down to the bottom one, its ends ``handle_radius`` inside the wall."""
        return handle_points(self.params(), self.handle_segments).numpy()

    def _batched(self, fn, p_B: Tensor) -> Tensor:
        flat = p_B.reshape(1, -1, 3)
        return fn(self.params(p_B.dtype).to(p_B.device)[None], flat).reshape(p_B.shape[:-1])

    def cup_sdf(self, p_B: Tensor) -> Tensor:
        return self._batched(cup_sdf, p_B)

    def handle_sdf(self, p_B: Tensor) -> Tensor:
        return polyline_distance(p_B, self.handle_points()) - self.handle_radius

    def sdf(self, p_B: Tensor) -> Tensor:
        return self._batched(lambda q, x: mug_sdf(q, x, self.handle_segments), p_B)


@dataclass(frozen=True)
class Hook(Shape3D):
    """A hook: a vertical post of ``post_height`` and ``post_radius`` standing on the ground,
    and an arm of two or three straight parts (a tube of ``rod_radius``) leaving the top of the
    post towards +x; part ``i`` has length ``lengths[i]`` and rises at ``angles[i]`` (rad)
    above the horizontal (negative: falling)."""

    post_height: float
    lengths: tuple[float, ...]
    angles: tuple[float, ...]
    post_radius: float = 0.012
    rod_radius: float = 0.005

    def __post_init__(self) -> None:
        if len(self.lengths) != len(self.angles) or not 1 <= len(self.lengths) <= 3:
            raise ValueError("a hook's arm has one to three parts, a length and an angle each")

    def arm_points(self) -> np.ndarray:
        """The arm's centre line ``(parts + 1, 3)``, starting on the post's axis at its top."""
        pts = [np.array([0.0, 0.0, self.post_height])]
        for length, angle in zip(self.lengths, self.angles, strict=False):
            pts.append(pts[-1] + length * np.array([math.cos(angle), 0.0, math.sin(angle)]))
        return np.stack(pts)

    def aabb(self) -> tuple[np.ndarray, np.ndarray]:
        """The hook's axis-aligned bounding box ``(lo, hi)`` in its frame."""
        arm = self.arm_points()
        r, rr = self.post_radius, self.rod_radius
        lo = np.minimum(arm.min(0) - rr, [-r, -r, 0.0])
        hi = np.maximum(arm.max(0) + rr, [r, r, self.post_height])
        return lo, hi

    def post_sdf(self, p_B: Tensor) -> Tensor:
        radial = safe_norm(p_B[..., :2]) - self.post_radius
        axial = (p_B[..., 2] - self.post_height / 2).abs() - self.post_height / 2
        d = torch.stack((radial, axial), dim=-1)
        return safe_norm(d.clamp_min(0.0)) + d.amax(dim=-1).clamp_max(0.0)

    def arm_sdf(self, p_B: Tensor) -> Tensor:
        return polyline_distance(p_B, self.arm_points()) - self.rod_radius

    def sdf(self, p_B: Tensor) -> Tensor:
        return torch.minimum(self.post_sdf(p_B), self.arm_sdf(p_B))


def sdf_at(shape: Shape3D, points_W: Tensor, X_WB: Tensor) -> Tensor:
    """T(q)[φ](x) = φ(R(q)ᵀ (x − r(q))): the SDF ``(..., N)`` of ``shape`` posed at
    ``X_WB (..., 7)`` at world points ``(..., N, 3)``."""
    return shape.sdf(spatial_to_body(points_W, X_WB))
