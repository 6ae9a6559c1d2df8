"""The footprint of a user's mesh: a polygon with holes, and where its mesh lies.

A mesh object's shape frame B sits at its footprint's area centroid on the table, its axes
those of the mesh file. The footprint is the mesh's projection on the table
(:func:`robotplan.geometry.meshes.footprint_loops`); every 2D part of the planner sees a
:class:`Polygon` (the outer loop), the SDF keeps the holes, and the simulator reads the
mesh itself through ``mesh_file``, ``scale`` and ``mesh_offset``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import torch
from torch import Tensor

from robotplan.geometry.polygons import signed_area
from robotplan.sdf.closed_form import polygon_sdf, polygon_sdf_and_grad
from robotplan.sdf.shapes2d import Polygon

__all__ = ["MeshFootprint"]


@dataclass(frozen=True)
class MeshFootprint(Polygon):
    """A mesh's footprint: ``vertices`` its outer loop and ``holes`` its inner loops, in
    frame B. ``mesh_file`` (absolute path), ``scale`` (file units → m) and ``mesh_offset``
    (the point of the scaled mesh that is B's origin: the footprint's centroid in x, y and
    the mesh's lowest z) place the mesh in B. ``prism``: the mesh is its footprint extruded (a
    plate cut from sheet), so the footprint's prism is the mesh exactly.

    φ = max(φ_outer, −φ_hole₁, …): exact, as every hole lies inside the outer loop and
    the holes are disjoint (inside the solid the nearest boundary is the outer loop or a
    hole's, outside it only the loop the point is outside of is nearer).
    """

    holes: tuple[tuple[tuple[float, float], ...], ...] = ()
    mesh_file: str = ""
    scale: float = 1.0
    mesh_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    prism: bool = False

    def sdf(self, p_B: Tensor) -> Tensor:
        phi = polygon_sdf(p_B, self._vertices)
        for hole in self._hole_arrays:
            phi = torch.maximum(phi, -polygon_sdf(p_B, hole))
        return phi

    def sdf_and_grad_planes(self, px: Tensor, py: Tensor) -> tuple[Tensor, Tensor, Tensor]:
        phi, gx, gy = polygon_sdf_and_grad(px, py, self._vertices)
        for hole in self._hole_arrays:
            h, hx, hy = polygon_sdf_and_grad(px, py, hole)
            deeper = -h > phi
            phi = torch.where(deeper, -h, phi)
            gx, gy = torch.where(deeper, -hx, gx), torch.where(deeper, -hy, gy)
        return phi, gx, gy

    @cached_property
    def _hole_arrays(self) -> list[np.ndarray]:
        return [np.asarray(h, dtype=np.float64) for h in self.holes]

    @property
    def area(self) -> float:
        return signed_area(self.outline()) - sum(abs(signed_area(h)) for h in self._hole_arrays)

    def describe(self) -> str:
        holes = f", {len(self.holes)} hole{'s' * (len(self.holes) != 1)}" if self.holes else ""
        return f"mesh {self.mesh_file.rsplit('/', 1)[-1]} (footprint of " \
               f"{len(self.vertices)} vertices{holes})"
