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

import itertools
import math
from dataclasses import dataclass

import numpy as np
import torch
from torch import Tensor

from robotplan.geometry.transforms import spatial_to_body
from robotplan.sdf.closed_form import polygon_sdf, safe_norm
from robotplan.sdf.shapes3d import Shape3D

__all__ = ["Hook", "Mug", "polyline_distance", "sdf_at"]


def polyline_distance(p: Tensor, points: np.ndarray) -> Tensor:
    """Euclidean distance ``(...)`` of points ``(..., 3)`` from the polyline through
    ``points (K, 3)`` (K ≥ 2): the least distance to its segments, exact."""
    best: Tensor | None = None
    for a, b in itertools.pairwise(points):
        ax = torch.as_tensor(a, dtype=p.dtype, device=p.device)
        e = torch.as_tensor(b - a, dtype=p.dtype, device=p.device)
        w = p - ax
        t = ((w * e).sum(-1) / float(e @ e)).clamp(0.0, 1.0)
        d = safe_norm(w - t[..., None] * e)
        best = d if best is None else torch.minimum(best, d)
    assert best is not None, "a polyline has at least two points"
    return best


def _revolved_sdf(p: Tensor, profile: np.ndarray) -> Tensor:
    """Exact SDF of the solid swept by the meridian polygon ``profile (V, 2)`` in (ρ, z)
    around the z axis. The profile must be mirror-symmetric in ρ (it crosses the axis), so
    that no edge lies on the axis; then the 2D SDF at (|p_xy|, p_z) is the 3D SDF."""
    rho = safe_norm(p[..., :2])
    return polygon_sdf(torch.stack((rho, p[..., 2]), dim=-1), profile)


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

    def profile(self) -> np.ndarray:
        """The cup's meridian polygon ``(8, 2)`` in (ρ, z), mirrored across the axis."""
        r, h, w = self.radius, self.height, self.wall
        return np.array([(-r, 0.0), (r, 0.0), (r, h), (r - w, h), (r - w, w), (w - r, w),
                         (w - r, h), (-r, h)])

    def handle_points(self) -> np.ndarray:
        """The handle's centre line ``(segments + 1, 3)``: a half-ellipse from the top
        attachment down to the bottom one, its ends ``handle_radius`` inside the wall."""
        zc = self.handle_height * self.height
        base = self.radius - self.handle_radius
        s = np.linspace(-math.pi / 2, math.pi / 2, self.handle_segments + 1)
        x = base + (self.handle_reach + self.handle_radius) * np.cos(s)
        z = zc - self.handle_span * np.sin(s)
        return np.stack((x, np.zeros_like(x), z), axis=1)

    def cup_sdf(self, p_B: Tensor) -> Tensor:
        return _revolved_sdf(p_B, self.profile())

    def handle_sdf(self, p_B: Tensor) -> Tensor:
        return polyline_distance(p_B, self.handle_points()) - self.handle_radius

    def sdf(self, p_B: Tensor) -> Tensor:
        return torch.minimum(self.cup_sdf(p_B), self.handle_sdf(p_B))


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
