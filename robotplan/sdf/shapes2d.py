"""Exact signed-distance functions of 2D footprints (torch, batched, differentiable).

Every shape is a small dataclass that is also its scene-file schema (``shape: {type: box,
size: [w, h]}``). ``shape.sdf(p_B)`` takes points ``(..., 2)`` in the shape's own frame
(origin at the footprint's reference point) and returns φ ``(...)``: negative inside,
zero on the boundary, positive outside, the exact Euclidean distance to the boundary.
Any float dtype works; gradients flow to the points (and hence to poses).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from typing import ClassVar, Literal

import numpy as np
import torch
from torch import Tensor

from robotplan.polygons import as_ccw, signed_area

__all__ = [
    "Box",
    "Circle",
    "LShape",
    "Polygon",
    "Shape2D",
    "lshape_sdf",
    "polygon_sdf",
    "safe_hypot",
    "safe_norm",
]

POSITIVE = {"positive": True}


_EPS = 1e-30  # under the square root: the value moves by at most sqrt(_EPS) = 1e-15 m


def shape_planes(shape: Shape2D, px: Tensor, py: Tensor) -> tuple[Tensor, Tensor, Tensor] | None:
    """``sdf_and_grad_planes`` through our C kernel (:func:`robotplan.native.shape_planes`:
    float32 circles, boxes and L-shapes, no autograd graph), else None."""
    from robotplan import native  # it names these shapes: imported at first use

    return native.shape_planes(shape, px, py)


def safe_hypot(x: Tensor, y: Tensor) -> Tensor:
    """√(x² + y²) whose gradient is 0 (not NaN) at the origin; value exact to 1e-15."""
    return (x * x + y * y + _EPS).sqrt() - _EPS**0.5


def safe_norm(v: Tensor, dim: int = -1) -> Tensor:
    """Euclidean norm along ``dim`` whose gradient is 0 (not NaN) at the zero vector."""
    return ((v * v).sum(dim) + _EPS).sqrt() - _EPS**0.5


class Shape2D:
    """Base class of table footprints. Subclasses are dataclasses with a ``type`` tag."""

    type: str
    kinds: ClassVar[dict[str, type[Shape2D]]] = {}

    def __init_subclass__(cls, **kw: object) -> None:
        super().__init_subclass__(**kw)
        tag = getattr(cls, "type_tag", None)
        if tag:
            Shape2D.kinds[tag] = cls

    def sdf(self, p_B: Tensor) -> Tensor:
        """φ at points ``(..., 2)`` of the shape frame → ``(...)``."""
        raise NotImplementedError

    def sdf_and_grad(self, p_B: Tensor) -> tuple[Tensor, Tensor]:
        """φ ``(...)`` and ∇φ ``(..., 2)`` at points ``(..., 2)`` of the shape frame (not
        differentiable further). Autograd by default; closed forms where cheaper."""
        with torch.enable_grad():
            p = p_B.detach().requires_grad_(True)
            phi = self.sdf(p)
            (g,) = torch.autograd.grad(phi.sum(), p)
        return phi.detach(), g

    def sdf_and_grad_planes(self, px: Tensor, py: Tensor) -> tuple[Tensor, Tensor, Tensor]:
        """:meth:`sdf_and_grad` on coordinate planes ``px, py (...)`` → φ, ∂φ/∂x, ∂φ/∂y, each
        ``(...)`` and contiguous (the fast path of grid rendering)."""
        phi, g = self.sdf_and_grad(torch.stack((px, py), dim=-1))
        return phi, g[..., 0], g[..., 1]

    def outline(self, n_arc: int = 720) -> np.ndarray:
        """Boundary polygon ``(V, 2)`` in the shape frame, counter-clockwise (exact for
        polygonal shapes; ``n_arc`` vertices for a circle)."""
        raise NotImplementedError

    @property
    def area(self) -> float:
        return signed_area(self.outline())

    @property
    def bound_radius(self) -> float:
        """Radius of the smallest origin-centred disc that holds the shape."""
        return float(np.linalg.norm(self.outline(64), axis=1).max())

    def describe(self) -> str:
        raise NotImplementedError


def polygon_sdf(p: Tensor, vertices: Tensor | np.ndarray) -> Tensor:
    """Exact SDF of a simple polygon (convex or not, either winding).

    Args:
        p: ``(..., 2)`` query points.
        vertices: ``(V, 2)`` polygon vertices in order.
    Returns:
        ``(...)`` signed distance: magnitude = distance to the nearest edge, sign from the
        crossing number (negative inside).

    One pass per edge over the points (V is small), keeping a running minimum of the squared
    distance and the parity of crossings of the ray to +x: ~10× faster than materialising
    ``(..., V, 2)`` tensors.
    """
    verts = np.asarray(vertices.tolist() if isinstance(vertices, Tensor) else vertices,
                       dtype=np.float64)
    px, py = p[..., 0], p[..., 1]
    n = len(verts)
    dist2: Tensor | None = None
    inside: Tensor | None = None
    for i in range(n):
        ax, ay = float(verts[i, 0]), float(verts[i, 1])
        bx, by = float(verts[(i + 1) % n, 0]), float(verts[(i + 1) % n, 1])
        ex, ey = bx - ax, by - ay
        wx, wy = px - ax, py - ay
        t = ((wx * ex + wy * ey) * (1.0 / (ex * ex + ey * ey))).clamp(0.0, 1.0)
        dx, dy = wx - ex * t, wy - ey * t
        d2 = dx * dx + dy * dy
        dist2 = d2 if dist2 is None else torch.minimum(dist2, d2)
        if ay != by:  # a horizontal edge never crosses the horizontal ray
            crosses = ((ay <= py) != (by <= py)) & (px < ax + (py - ay) * (ex / ey))
            inside = crosses if inside is None else inside ^ crosses
    assert dist2 is not None and inside is not None, "a polygon has at least 3 vertices"
    dist = (dist2 + _EPS).sqrt() - _EPS**0.5
    return torch.where(inside, -dist, dist)


def _box_sdf(px: Tensor, py: Tensor, cx: float, cy: float, hx: float, hy: float) -> Tensor:
    """Exact SDF of the axis-aligned box ``(cx, cy) ± (hx, hy)`` at points ``(px, py)``."""
    qx = (px - cx).abs() - hx
    qy = (py - cy).abs() - hy
    return safe_hypot(qx.clamp_min(0.0), qy.clamp_min(0.0)) + torch.maximum(qx, qy).clamp_max(0.0)


def _box_sdf_and_grad(px: Tensor, py: Tensor, cx: Tensor | float, cy: Tensor | float,
                      hx: Tensor | float, hy: Tensor | float) -> tuple[Tensor, Tensor, Tensor]:
    """:func:`_box_sdf` and its gradient ``(φ, ∂φ/∂x, ∂φ/∂y)``, branch-free: outside, the
    unit vector from the nearest boundary point; inside, the normal of the nearest face.

    The box parameters may be tensors ``(K, 1, …)`` that broadcast with the points: K boxes
    in one pass, results ``(K, …)`` (the same few kernels for any K)."""
    dx, dy = px - cx, py - cy
    qx, qy = dx.abs() - hx, dy.abs() - hy
    ox, oy = qx.clamp_min(0.0), qy.clamp_min(0.0)
    # not differentiated: no need for safe_hypot; √(ox² + oy²) is 2x faster than hypot here
    out = torch.addcmul(ox * ox, oy, oy).sqrt_()
    inv = out.clamp_min(1e-30).reciprocal()  # ox, oy are 0 wherever out is
    deepest = torch.maximum(qx, qy)
    inner = deepest <= 0
    x_face = (qx > qy) & inner
    gx = (ox * inv + x_face) * dx.sign()  # sign(0) = 0 on a symmetry line, as autograd's
    gy = (oy * inv + (inner ^ x_face)) * dy.sign()
    return out + deepest.clamp_max(0.0), gx, gy


@lru_cache(maxsize=256)
def lshape_boxes(size: tuple[float, float], thickness: float, dtype: torch.dtype
                  ) -> tuple[Tensor, Tensor]:
    """The four boxes of an L-shape's closed form: parameters ``(cx, cy, hx, hy) × (bottom
    strip, left strip, bounding box, notch)`` and the sign of each box's SDF in it."""
    w, h, t = size[0] / 2, size[1] / 2, thickness
    params = torch.tensor([[0.0, t / 2 - w, 0.0, t / 2], [t / 2 - h, 0.0, 0.0, t / 2],
                           [w, t / 2, w, w - t / 2], [t / 2, h, h, h - t / 2]], dtype=dtype)
    return params, torch.tensor([1.0, 1.0, 1.0, -1.0], dtype=dtype)


def lshape_sdf(px: Tensor, py: Tensor, w: Tensor | float, h: Tensor | float,
               t: Tensor | float) -> Tensor:
    """Exact SDF of the L-shape with half sizes ``(w, h)`` and thickness ``t`` (see
    :class:`LShape`) at points ``(px, py)``; the parameters may be tensors that broadcast
    with the points (a batch of different shapes). With ``t = 2h`` it is the box ``2w × 2h``.
    """
    # Per-axis gaps of the bounding box (shared with the strips) and of the other boxes.
    qx, qy = px.abs() - w, py.abs() - h
    qy_bottom = (py + (h - t / 2)).abs() - t / 2
    qx_left = (px + (w - t / 2)).abs() - t / 2
    qx_notch = (px - t / 2).abs() - (w - t / 2)
    qy_notch = (py - t / 2).abs() - (h - t / 2)
    inside = ((qx < 0) & (qy_bottom < 0)) | ((qx_left < 0) & (qy < 0))
    # Outside both strips their SDFs are the plain corner distances.
    outside = torch.minimum(safe_hypot(qx.clamp_min(0.0), qy_bottom.clamp_min(0.0)),
                            safe_hypot(qx_left.clamp_min(0.0), qy.clamp_min(0.0)))
    # Inside the L: inside the bounding box and outside the notch.
    depth = torch.maximum(torch.maximum(qx, qy),
                          -safe_hypot(qx_notch.clamp_min(0.0), qy_notch.clamp_min(0.0)))
    return torch.where(inside, depth, outside)


@dataclass(frozen=True)
class Box(Shape2D):
    """Rectangle with full side lengths ``size = (w, h)``, centred on its frame."""

    size: tuple[float, float] = field(metadata=POSITIVE)
    type: Literal["box"] = "box"
    type_tag: ClassVar[str] = "box"

    def sdf(self, p_B: Tensor) -> Tensor:
        return _box_sdf(p_B[..., 0], p_B[..., 1], 0.0, 0.0, self.size[0] / 2, self.size[1] / 2)

    def sdf_and_grad(self, p_B: Tensor) -> tuple[Tensor, Tensor]:
        phi, gx, gy = self.sdf_and_grad_planes(p_B[..., 0], p_B[..., 1])
        return phi, torch.stack((gx, gy), dim=-1)

    def sdf_and_grad_planes(self, px: Tensor, py: Tensor) -> tuple[Tensor, Tensor, Tensor]:
        return (shape_planes(self, px, py)
                or _box_sdf_and_grad(px, py, 0.0, 0.0, self.size[0] / 2, self.size[1] / 2))

    def outline(self, n_arc: int = 720) -> np.ndarray:
        w, h = self.size[0] / 2, self.size[1] / 2
        return np.array([[-w, -h], [w, -h], [w, h], [-w, h]], dtype=np.float64)

    def describe(self) -> str:
        return f"box {self.size[0]:g}x{self.size[1]:g}"


@dataclass(frozen=True)
class Circle(Shape2D):
    """Disc of ``radius`` centred on its frame."""

    radius: float = field(metadata=POSITIVE)
    type: Literal["circle"] = "circle"
    type_tag: ClassVar[str] = "circle"

    def sdf(self, p_B: Tensor) -> Tensor:
        return safe_hypot(p_B[..., 0], p_B[..., 1]) - self.radius

    def sdf_and_grad(self, p_B: Tensor) -> tuple[Tensor, Tensor]:
        norm = safe_hypot(p_B[..., 0], p_B[..., 1])
        return norm - self.radius, p_B / norm.clamp_min(1e-12)[..., None]

    def sdf_and_grad_planes(self, px: Tensor, py: Tensor) -> tuple[Tensor, Tensor, Tensor]:
        native = shape_planes(self, px, py)
        if native is not None:
            return native
        norm = safe_hypot(px, py)
        inv = norm.clamp_min(1e-12).reciprocal()
        return norm - self.radius, px * inv, py * inv

    def outline(self, n_arc: int = 720) -> np.ndarray:
        ang = np.linspace(0.0, 2 * math.pi, n_arc, endpoint=False)
        return self.radius * np.stack([np.cos(ang), np.sin(ang)], axis=1)

    @property
    def area(self) -> float:
        return math.pi * self.radius**2

    def describe(self) -> str:
        return f"circle r={self.radius:g}"


class _PolygonalShape(Shape2D):
    """Shapes whose boundary is a polygon: exact SDF through :func:`polygon_sdf`."""

    @cached_property
    def _vertices(self) -> np.ndarray:
        return self.outline()

    def sdf(self, p_B: Tensor) -> Tensor:
        return polygon_sdf(p_B, self._vertices)


@dataclass(frozen=True)
class LShape(_PolygonalShape):
    """L-shape in a ``size = (w, h)`` bounding box centred on its frame: the bottom strip
    (height ``thickness``) plus the left strip (width ``thickness``).

    Its SDF is exact and cheaper than a polygon's per-edge work: outside, the L is the union
    of its two strips (φ = min of theirs, exact outside a union); inside, it is the bounding
    box minus the open notch (φ = max(φ_box, −φ_notch), exact inside a difference).
    """

    size: tuple[float, float] = field(metadata=POSITIVE)
    thickness: float = field(metadata=POSITIVE)
    type: Literal["lshape"] = "lshape"
    type_tag: ClassVar[str] = "lshape"

    def check(self) -> tuple[str, str] | None:
        if self.thickness >= min(self.size):
            return "thickness", f"must be smaller than both sides {list(self.size)}"
        return None

    def sdf(self, p_B: Tensor) -> Tensor:
        return lshape_sdf(p_B[..., 0], p_B[..., 1], self.size[0] / 2, self.size[1] / 2,
                          self.thickness)

    def sdf_and_grad(self, p_B: Tensor) -> tuple[Tensor, Tensor]:
        phi, gx, gy = self.sdf_and_grad_planes(p_B[..., 0], p_B[..., 1])
        return phi, torch.stack((gx, gy), dim=-1)

    def sdf_and_grad_planes(self, px: Tensor, py: Tensor) -> tuple[Tensor, Tensor, Tensor]:
        """Closed form from the boxes of :func:`lshape_sdf`, all four in one pass: outside,
        the nearer strip; inside, the bounding box or the notch (its negated SDF),
        whichever is larger."""
        native = shape_planes(self, px, py)
        if native is not None:
            return native
        params, sign = lshape_boxes(self.size, self.thickness, px.dtype)
        ones = [1] * px.dim()
        phi, gx, gy = _box_sdf_and_grad(px, py, *params.view(4, 4, *ones))  # (4 boxes, ...)
        values = torch.stack((phi, gx, gy)) * sign.view(1, 4, *ones)  # the notch negated
        bottom, left, box, notch = values[0]
        pick = torch.where(torch.minimum(bottom, left) < 0, (box <= notch) + 2, bottom >= left)
        chosen = values.gather(1, pick[None, None].expand(3, 1, *pick.shape))[:, 0]
        return chosen[0], chosen[1], chosen[2]

    def outline(self, n_arc: int = 720) -> np.ndarray:
        w, h, t = self.size[0] / 2, self.size[1] / 2, self.thickness
        return np.array(
            [[-w, -h], [w, -h], [w, -h + t], [-w + t, -h + t], [-w + t, h], [-w, h]],
            dtype=np.float64,
        )

    def describe(self) -> str:
        return f"lshape {self.size[0]:g}x{self.size[1]:g} t={self.thickness:g}"


@dataclass(frozen=True)
class Polygon(_PolygonalShape):
    """Simple polygon, convex or not, either winding; vertices in its own frame."""

    vertices: tuple[tuple[float, float], ...]
    type: Literal["polygon"] = "polygon"
    type_tag: ClassVar[str] = "polygon"

    def check(self) -> tuple[str, str] | None:
        from robotplan.polygons import is_simple

        ok, why = is_simple(np.asarray(self.vertices, dtype=np.float64))
        return None if ok else ("vertices", why)

    def outline(self, n_arc: int = 720) -> np.ndarray:
        return as_ccw(np.asarray(self.vertices, dtype=np.float64))

    def describe(self) -> str:
        return f"polygon of {len(self.vertices)} vertices"
