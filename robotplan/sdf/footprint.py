"""What a footprint rests on: its centroid, its axis-aligned boxes and the points of its rim
that carry it on the table (shared by the simulator's bodies and the planner's limit
surface)."""

from __future__ import annotations

import numpy as np

from robotplan.geometry.polygons import convex_parts, signed_area
from robotplan.sdf.shapes2d import Box, Circle, LShape, Shape2D

__all__ = ["footprint_boxes", "footprint_centroid", "support_corners"]


def footprint_centroid(shape: Shape2D) -> np.ndarray:
    """Area centroid ``(2,)`` of a footprint in its own frame (centre of mass, uniform)."""
    p = shape.outline()
    q = np.roll(p, -1, axis=0)
    cross = p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]
    return ((p + q) * cross[:, None]).sum(0) / (6.0 * signed_area(p))


def footprint_boxes(shape: Shape2D) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    """The footprint as axis-aligned boxes ``(centre, half_extents)`` in its frame."""
    if isinstance(shape, Box):
        return [((0.0, 0.0), (shape.size[0] / 2, shape.size[1] / 2))]
    if isinstance(shape, LShape):
        w, h, t = shape.size[0] / 2, shape.size[1] / 2, shape.thickness
        return [((0.0, -h + t / 2), (w, t / 2)),
                ((-w + t / 2, t / 2), (t / 2, h - t / 2))]
    raise NotImplementedError(f"no pybullet body for {shape.type} footprints yet")


def support_corners(shape: Shape2D) -> np.ndarray:
    """Points ``(K, 2)`` of the simulated footprint's rim in the shape frame where
    pybullet's contacts with the table carry the object (they set its limit surface):
    the corners of its boxes or convex parts, 16 points round a disc."""
    if isinstance(shape, Circle):
        a = np.linspace(0, 2 * np.pi, 16, endpoint=False)
        return shape.radius * np.stack((np.cos(a), np.sin(a)), 1)
    if isinstance(shape, Box | LShape):
        signs = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]], dtype=float)
        return np.vstack([np.asarray(c) + signs * np.asarray(h) for c, h in footprint_boxes(shape)])
    return np.vstack(convex_parts(shape.outline()))
