"""What a footprint rests on: its centroid, its axis-aligned boxes and the points of its rim
that carry it on the table (shared by the simulator's bodies and the planner's limit
surface)."""

from __future__ import annotations

import numpy as np

from robotplan.geometry.polygons import area_centroid, as_ccw, convex_parts
from robotplan.sdf.shapes2d import Box, Circle, LShape, Shape2D

__all__ = ["footprint_boxes", "footprint_centroid", "footprint_parts", "support_corners"]


def footprint_centroid(shape: Shape2D) -> np.ndarray:
    """Area centroid ``(2,)`` of a footprint in its own frame (centre of mass, uniform)."""
    return area_centroid([shape.outline()])


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
    return np.vstack(footprint_parts(shape))


def footprint_parts(shape: Shape2D) -> list[np.ndarray]:
    """The footprint as convex polygons ``[(V, 2)]`` in its frame that cover it exactly:
    a footprint with holes is first cut through each hole into simple pieces."""
    holes = getattr(shape, "holes", ())
    if not holes:
        return convex_parts(shape.outline())
    from shapely.geometry import LineString
    from shapely.geometry import Polygon as Solid
    from shapely.ops import split

    todo, simple = [Solid(shape.outline(), holes)], []
    while todo:
        piece = todo.pop()
        if not piece.interiors:
            simple.append(as_ccw(np.asarray(piece.exterior.coords)[:-1]))
            continue
        x = Solid(piece.interiors[0]).centroid.x  # a vertical cut through the hole
        y0, y1 = piece.bounds[1] - 1.0, piece.bounds[3] + 1.0
        todo += list(split(piece, LineString([(x, y0), (x, y1)])).geoms)
    return [part for piece in simple for part in convex_parts(piece)]
