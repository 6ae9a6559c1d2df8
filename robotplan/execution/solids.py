"""What a simulator builds for a footprint extruded to its height: the same solids in every
world, each simulator realising them with its own shapes.

A body's frame is the footprint's centroid (its centre of mass, uniform density) at half
the height; :func:`footprint_solids` gives the pieces in that frame: boxes for boxes and
L-shapes (as the push data), a cylinder for a disc, the mesh's convex pieces for a mesh,
convex prisms (one per :func:`~robotplan.sdf.footprint.footprint_parts` piece) for other
polygons and for a mesh that is its footprint's prism.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from robotplan.sdf import Box, Circle, LShape, Shape2D
from robotplan.sdf.footprint import footprint_boxes, footprint_centroid, footprint_parts
from robotplan.sdf.mesh_footprint import MeshFootprint

__all__ = ["Solid", "footprint_solids", "planar_body_pose", "read_pieces",
           "shape_frame_pose"]


@dataclass(frozen=True)
class Solid:
    """One piece of a body in its frame. ``kind``: ``box`` (``centre (3,)``, ``half (3,)``),
    ``cylinder`` (``radius``, ``length`` along z), ``prisms`` (``parts``: convex polygons
    ``[(V, 2)]`` extruded over ``length``) or ``pieces`` (the convex pieces in ``file``, in the
    mesh's units times ``scale``, moved by ``centre``)."""

    kind: str
    centre: tuple[float, float, float] = (0.0, 0.0, 0.0)
    half: tuple[float, float, float] = (0.0, 0.0, 0.0)
    radius: float = 0.0
    length: float = 0.0
    parts: tuple = ()
    file: Path | None = None
    scale: float = 1.0


def footprint_solids(shape: Shape2D, height: float) -> list[Solid]:
    """The pieces of ``shape`` extruded to ``height`` (see the module docstring)."""
    com = footprint_centroid(shape)
    if isinstance(shape, Box | LShape):
        return [Solid("box", (cx - com[0], cy - com[1], 0.0), (hx, hy, height / 2))
                for (cx, cy), (hx, hy) in footprint_boxes(shape)]
    if isinstance(shape, Circle):
        return [Solid("cylinder", radius=shape.radius, length=height)]
    if isinstance(shape, MeshFootprint) and not shape.prism:
        # the mesh itself: B's point of the scaled mesh is mesh_offset
        from robotplan.execution.convex_pieces import convex_pieces_file

        at = -np.asarray(shape.mesh_offset) - np.array([com[0], com[1], height / 2])
        return [Solid("pieces", tuple(at.tolist()), file=convex_pieces_file(
            shape.mesh_file, shape.scale), scale=shape.scale)]
    parts = tuple(part - com for part in footprint_parts(shape))
    return [Solid("prisms", parts=parts, length=height)]


def read_pieces(path: Path) -> list[np.ndarray]:
    """The vertices ``[(V, 3)]`` of each ``o`` group of a convex-pieces OBJ file."""
    pieces: list[list[list[float]]] = []
    for line in Path(path).read_text().splitlines():
        if line.startswith("o ") or (line.startswith("v ") and not pieces):
            pieces.append([])
        if line.startswith("v "):
            pieces[-1].append([float(v) for v in line.split()[1:4]])
    return [np.array(p) for p in pieces if p]


def planar_body_pose(pose, shape: Shape2D) -> tuple[np.ndarray, float]:
    """Where a body of footprint ``shape`` at planar ``pose (x, y, yaw)`` has its frame: the
    centroid's world position ``(2,)`` and the yaw."""
    com = footprint_centroid(shape)
    x, y, yaw = pose
    cs, sn = np.cos(yaw), np.sin(yaw)
    return np.array([x + cs * com[0] - sn * com[1], y + sn * com[0] + cs * com[1]]), yaw


def shape_frame_pose(position: np.ndarray, R: np.ndarray, com: np.ndarray
                     ) -> tuple[np.ndarray, float]:
    """The planar pose ``(x, y, yaw)`` of the shape frame of a body whose frame (the
    footprint's centroid ``com (2,)`` in the shape frame) is at ``position (3,)`` turned by
    ``R (3, 3)``, and its tilt: the larger of its roll and pitch (rad)."""
    yaw = float(np.arctan2(R[1, 0], R[0, 0]))
    pitch = float(np.arcsin(np.clip(-R[2, 0], -1.0, 1.0)))
    roll = float(np.arctan2(R[2, 1], R[2, 2]))
    cs, sn = np.cos(yaw), np.sin(yaw)
    x = position[0] - (cs * com[0] - sn * com[1])
    y = position[1] - (sn * com[0] + cs * com[1])
    return np.array([x, y, yaw]), max(abs(roll), abs(pitch))
