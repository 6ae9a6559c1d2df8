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

from robotplan.base import native
from robotplan.geometry.polygons import as_ccw, signed_area
from robotplan.sdf.closed_form import (
    box_sdf,
    box_sdf_and_grad,
    lshape_boxes,
    lshape_sdf,
    polygon_sdf,
    polygon_sdf_and_grad,
    safe_hypot,
    safe_norm,
)

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

    @property
    def kernel_shape(self) -> native.KernelShape | None:
        """This shape as the C kernels know it (circles, boxes, L-shapes), else None."""
        return _kernel_shape(self)

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


@dataclass(frozen=True)
class Box(Shape2D):
    """Rectangle with full side lengths ``size = (w, h)``, centred on its frame."""

    size: tuple[float, float] = field(metadata=POSITIVE)
    type: Literal["box"] = "box"
    type_tag: ClassVar[str] = "box"

    def sdf(self, p_B: Tensor) -> Tensor:
        return box_sdf(p_B[..., 0], p_B[..., 1], 0.0, 0.0, self.size[0] / 2, self.size[1] / 2)

    def sdf_and_grad(self, p_B: Tensor) -> tuple[Tensor, Tensor]:
        phi, gx, gy = self.sdf_and_grad_planes(p_B[..., 0], p_B[..., 1])
        return phi, torch.stack((gx, gy), dim=-1)

    def sdf_and_grad_planes(self, px: Tensor, py: Tensor) -> tuple[Tensor, Tensor, Tensor]:
        return (native.shape_planes(self.kernel_shape, px, py)
                or box_sdf_and_grad(px, py, 0.0, 0.0, self.size[0] / 2, self.size[1] / 2))

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
        planes = native.shape_planes(self.kernel_shape, px, py)
        if planes is not None:
            return planes
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
    """Shapes whose boundary is a polygon: exact SDF through :func:`polygon_sdf`, its
    gradient in closed form (:func:`polygon_sdf_and_grad`)."""

    @cached_property
    def _vertices(self) -> np.ndarray:
        return self.outline()

    def sdf(self, p_B: Tensor) -> Tensor:
        return polygon_sdf(p_B, self._vertices)

    def sdf_and_grad(self, p_B: Tensor) -> tuple[Tensor, Tensor]:
        phi, gx, gy = self.sdf_and_grad_planes(p_B[..., 0], p_B[..., 1])
        return phi, torch.stack((gx, gy), dim=-1)

    def sdf_and_grad_planes(self, px: Tensor, py: Tensor) -> tuple[Tensor, Tensor, Tensor]:
        return polygon_sdf_and_grad(px, py, self._vertices)


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
        planes = native.shape_planes(self.kernel_shape, px, py)
        if planes is not None:
            return planes
        params, sign = lshape_boxes(self.size, self.thickness, px.dtype)
        ones = [1] * px.dim()
        phi, gx, gy = box_sdf_and_grad(px, py, *params.view(4, 4, *ones))  # (4 boxes, ...)
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
        from robotplan.geometry.polygons import is_simple

        ok, why = is_simple(np.asarray(self.vertices, dtype=np.float64))
        return None if ok else ("vertices", why)

    def outline(self, n_arc: int = 720) -> np.ndarray:
        return as_ccw(np.asarray(self.vertices, dtype=np.float64))

    def describe(self) -> str:
        return f"polygon of {len(self.vertices)} vertices"


@lru_cache(maxsize=256)
def _kernel_shape(shape: Shape2D) -> native.KernelShape | None:
    """The kernels' code and float32 parameters of a shape (once per shape: shapes are
    frozen dataclasses)."""
    if isinstance(shape, Circle):
        kind, params = native.CIRCLE, [shape.radius]
    elif isinstance(shape, Box):
        kind, params = native.BOX, [shape.size[0] / 2, shape.size[1] / 2]
    elif isinstance(shape, LShape):
        boxes, _ = lshape_boxes(shape.size, shape.thickness, torch.float64)
        kind, params = native.LSHAPE, boxes.T.flatten().tolist()  # per box: centre, half sides
    else:
        return None
    return kind, torch.tensor(params, dtype=torch.float32)
