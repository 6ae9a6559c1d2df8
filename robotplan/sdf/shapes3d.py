"""Exact signed-distance functions of 3D shapes (torch, batched, differentiable).

``shape.sdf(p_B)`` takes points ``(..., 3)`` in the shape frame and returns φ ``(...)``
(negative inside). Primitives are closed-form; :class:`Mesh` wraps a watertight trimesh
mesh: the value is exact (closest point on the triangles, sign from containment) and the
gradient is the exact ``(p − c)/|p − c|`` direction, so it is differentiable in the points.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import torch
from torch import Tensor

from robotplan.sdf.closed_form import safe_norm
from robotplan.sdf.shapes2d import Shape2D

if TYPE_CHECKING:  # trimesh is imported where a mesh is used: it costs ~1 s at start-up
    import trimesh

__all__ = ["Box3D", "Capsule", "Cylinder", "Extrusion", "Mesh", "Shape3D", "Sphere"]


class Shape3D:
    """Base class of 3D shapes."""

    def sdf(self, p_B: Tensor) -> Tensor:
        """φ at points ``(..., 3)`` of the shape frame → ``(...)``."""
        raise NotImplementedError


def _round_corner(d: Tensor) -> Tensor:
    """Exact SDF from per-axis signed gaps ``d (..., k)`` of an intersection of slabs."""
    return safe_norm(d.clamp_min(0.0)) + d.amax(dim=-1).clamp_max(0.0)


@dataclass(frozen=True)
class Sphere(Shape3D):
    """Ball of ``radius`` centred on its frame."""

    radius: float

    def sdf(self, p_B: Tensor) -> Tensor:
        return safe_norm(p_B) - self.radius


@dataclass(frozen=True)
class Box3D(Shape3D):
    """Cuboid with full side lengths ``size = (x, y, z)``, centred on its frame."""

    size: tuple[float, float, float]

    def sdf(self, p_B: Tensor) -> Tensor:
        half = torch.tensor(self.size, dtype=p_B.dtype, device=p_B.device) / 2
        return _round_corner(p_B.abs() - half)


@dataclass(frozen=True)
class Cylinder(Shape3D):
    """Solid cylinder around the frame's z axis, ``length`` in total, centred."""

    radius: float
    length: float

    def sdf(self, p_B: Tensor) -> Tensor:
        radial = safe_norm(p_B[..., :2]) - self.radius
        axial = p_B[..., 2].abs() - self.length / 2
        return _round_corner(torch.stack((radial, axial), dim=-1))


@dataclass(frozen=True)
class Capsule(Shape3D):
    """Points within ``radius`` of the z-axis segment of ``length`` centred on the frame."""

    radius: float
    length: float

    def sdf(self, p_B: Tensor) -> Tensor:
        h = self.length / 2
        z = p_B[..., 2:3]
        offset = torch.cat((p_B[..., :2], z - z.clamp(-h, h)), dim=-1)
        return safe_norm(offset) - self.radius


@dataclass(frozen=True)
class Extrusion(Shape3D):
    """A 2D footprint extruded from ``z = 0`` to ``z = height`` (a table-top object)."""

    footprint: Shape2D
    height: float

    def sdf(self, p_B: Tensor) -> Tensor:
        planar = self.footprint.sdf(p_B[..., :2])
        axial = (p_B[..., 2] - self.height / 2).abs() - self.height / 2
        return _round_corner(torch.stack((planar, axial), dim=-1))


class Mesh(Shape3D):
    """Watertight triangle mesh (trimesh) in its own frame."""

    def __init__(self, mesh: trimesh.Trimesh) -> None:
        if not mesh.is_watertight:
            raise ValueError("mesh SDF needs a watertight mesh (inside/outside is undefined)")
        self.mesh = mesh

    @classmethod
    def load(cls, path: str) -> Mesh:
        import trimesh

        return cls(trimesh.load_mesh(path, force="mesh"))

    def sdf(self, p_B: Tensor) -> Tensor:
        flat = p_B.reshape(-1, 3)
        pts = flat.detach().cpu().double().numpy()
        import trimesh

        closest, _, _ = trimesh.proximity.closest_point(self.mesh, pts)
        inside = self.mesh.contains(pts)
        c = torch.from_numpy(np.asarray(closest)).to(flat)
        sign = torch.from_numpy(np.where(inside, -1.0, 1.0)).to(flat)
        return (sign * safe_norm(flat - c)).reshape(p_B.shape[:-1])
