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
from functools import cached_property
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
    "polygon_sdf",
    "safe_hypot",
    "safe_norm",
]

POSITIVE = {"positive": True}


_EPS = 1e-30  # under the square root: the value moves by at most sqrt(_EPS) = 1e-15 m


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


def polygon_sdf(p: Tensor, vertices: Tensor) -> Tensor:
    """Exact SDF of a simple polygon (convex or not, either winding).

    Args:
        p: ``(..., 2)`` query points.
        vertices: ``(V, 2)`` polygon vertices in order.
    Returns:
        ``(...)`` signed distance: magnitude = distance to the nearest edge, sign from the
        crossing number (negative inside).
    """
    a = vertices.to(p)
    b = torch.roll(a, shifts=-1, dims=0)
    e = b - a  # (V, 2)
    w = p[..., None, :] - a  # (..., V, 2)
    t = ((w * e).sum(-1) / (e * e).sum(-1)).clamp(0.0, 1.0)
    dist = safe_norm(w - e * t[..., None]).amin(dim=-1)
    # Crossing number: an edge a→b crosses the horizontal ray to +x from p.
    py = p[..., None, 1]
    straddles = (a[:, 1] <= py) != (b[:, 1] <= py)
    x_cross = a[:, 0] + (py - a[:, 1]) * e[:, 0] / torch.where(e[:, 1] == 0, 1.0, e[:, 1])
    crossings = (straddles & (p[..., None, 0] < x_cross)).sum(-1)
    inside = (crossings % 2) == 1
    return torch.where(inside, -dist, dist)


@dataclass(frozen=True)
class Box(Shape2D):
    """Rectangle with full side lengths ``size = (w, h)``, centred on its frame."""

    size: tuple[float, float] = field(metadata=POSITIVE)
    type: Literal["box"] = "box"
    type_tag: ClassVar[str] = "box"

    def sdf(self, p_B: Tensor) -> Tensor:
        qx = p_B[..., 0].abs() - self.size[0] / 2
        qy = p_B[..., 1].abs() - self.size[1] / 2
        outside = safe_hypot(qx.clamp_min(0.0), qy.clamp_min(0.0))
        return outside + torch.maximum(qx, qy).clamp_max(0.0)

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
    def _vertices_t(self) -> Tensor:
        return torch.from_numpy(self.outline())

    def sdf(self, p_B: Tensor) -> Tensor:
        return polygon_sdf(p_B, self._vertices_t)


@dataclass(frozen=True)
class LShape(_PolygonalShape):
    """L-shape in a ``size = (w, h)`` bounding box centred on its frame: the bottom strip
    (height ``thickness``) plus the left strip (width ``thickness``)."""

    size: tuple[float, float] = field(metadata=POSITIVE)
    thickness: float = field(metadata=POSITIVE)
    type: Literal["lshape"] = "lshape"
    type_tag: ClassVar[str] = "lshape"

    def check(self) -> tuple[str, str] | None:
        if self.thickness >= min(self.size):
            return "thickness", f"must be smaller than both sides {list(self.size)}"
        return None

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
