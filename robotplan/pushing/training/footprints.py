"""Footprints of pushed objects: the families never seen in training (paper Tab. 6, Figs. 2
and 7) and the compact storage of any footprint in push data shards.

A footprint is stored as a type code, its bounding size ``(w, h)``, a thickness (L-shapes;
a box stores its full height, the L-shape that is the box, so both render by one closed
form) and up to ``MAX_VERTICES`` polygon vertices (NaN-padded), so a shard holds boxes, L-shapes,
polygons and discs alike.
"""

from __future__ import annotations

import math

import numpy as np

from robotplan.sdf import Box, Circle, LShape, Polygon, Shape2D

__all__ = ["BOX", "CIRCLE", "LSHAPE", "MAX_VERTICES", "OOD_FAMILIES", "POLYGON",
           "decode_footprint", "draw_ood_shape", "encode_footprint"]

BOX, LSHAPE, POLYGON, CIRCLE = 0, 1, 2, 3
MAX_VERTICES = 12

OOD_FAMILIES = ("triangle", "pentagon", "hexagon", "circle", "T", "cross", "U", "trapezoid")
"""Footprints never seen in training; T, cross and U are concave. Scene ``i`` of a set of
them draws family ``i mod 8``."""


def draw_ood_shape(rng: np.random.Generator, family: str) -> Shape2D:
    """A random footprint of ``family`` with bounding sides of 0.10–0.26 m (the push
    data's range), centred near its frame's origin."""
    u = rng.uniform
    if family == "circle":
        return Circle(round(float(u(0.05, 0.10)), 4))
    if family in ("pentagon", "hexagon"):
        n, r = (5 if family == "pentagon" else 6), u(0.07, 0.12)
        a = np.arange(n) * 2 * math.pi / n + math.pi / 2
        pts = r * np.stack((np.cos(a), np.sin(a)), 1)
    elif family == "triangle":
        b, h = u(0.14, 0.24), u(0.12, 0.22)
        pts = np.array([[-b / 2, -h / 3], [b / 2, -h / 3], [0.0, 2 * h / 3]])
    elif family == "trapezoid":
        b, h = u(0.16, 0.26), u(0.10, 0.18)
        top = b * u(0.4, 0.8)
        pts = np.array([[-b / 2, -h / 2], [b / 2, -h / 2], [top / 2, h / 2], [-top / 2, h / 2]])
    elif family == "T":
        w, h, t = u(0.16, 0.26), u(0.14, 0.24), u(0.05, 0.08)
        pts = np.array([[-t / 2, -h / 2], [t / 2, -h / 2], [t / 2, h / 2 - t], [w / 2, h / 2 - t],
                        [w / 2, h / 2], [-w / 2, h / 2], [-w / 2, h / 2 - t],
                        [-t / 2, h / 2 - t]])
    elif family == "cross":
        a, t = u(0.16, 0.26) / 2, u(0.05, 0.08) / 2
        pts = np.array([[t, -a], [t, -t], [a, -t], [a, t], [t, t], [t, a], [-t, a], [-t, t],
                        [-a, t], [-a, -t], [-t, -t], [-t, -a]])
    elif family == "U":
        w, h, t = u(0.16, 0.26), u(0.12, 0.20), u(0.04, 0.07)
        pts = np.array([[-w / 2, -h / 2], [w / 2, -h / 2], [w / 2, h / 2], [w / 2 - t, h / 2],
                        [w / 2 - t, -h / 2 + t], [-w / 2 + t, -h / 2 + t], [-w / 2 + t, h / 2],
                        [-w / 2, h / 2]])
    else:
        raise ValueError(f"unknown footprint family {family!r}")
    return Polygon(tuple((round(float(x), 4), round(float(y), 4)) for x, y in pts))


def encode_footprint(shape: Shape2D) -> tuple[int, tuple[float, float], float, np.ndarray]:
    """``(type code, bounding size (w, h), thickness, vertices (MAX_VERTICES, 2))``."""
    vertices = np.full((MAX_VERTICES, 2), np.nan)
    if isinstance(shape, Box):
        return BOX, (float(shape.size[0]), float(shape.size[1])), float(shape.size[1]), vertices
    if isinstance(shape, LShape):
        return (LSHAPE, (float(shape.size[0]), float(shape.size[1])), float(shape.thickness),
                vertices)
    if isinstance(shape, Circle):
        d = 2 * float(shape.radius)
        return CIRCLE, (d, d), 0.0, vertices
    if isinstance(shape, Polygon):
        pts = np.asarray(shape.vertices, dtype=float)
        if len(pts) > MAX_VERTICES:
            raise ValueError(f"a polygon of {len(pts)} vertices; at most {MAX_VERTICES} stored")
        vertices[:len(pts)] = pts
        # the bounding size about the frame's origin (what reaches of query points read)
        half = np.abs(pts).max(0)
        return POLYGON, (2 * float(half[0]), 2 * float(half[1])), 0.0, vertices
    raise ValueError(f"no storage for a {type(shape).__name__} footprint")


def decode_footprint(code: int, size: np.ndarray, thickness: float,
                     vertices: np.ndarray | None = None) -> Shape2D:
    """The footprint :func:`encode_footprint` stored."""
    w, h = float(size[0]), float(size[1])
    if code == BOX:
        return Box((w, h))
    if code == LSHAPE:
        return LShape((w, h), float(thickness))
    if code == CIRCLE:
        return Circle(w / 2)
    if code == POLYGON and vertices is not None:
        pts = vertices[~np.isnan(vertices[:, 0])]
        return Polygon(tuple((float(x), float(y)) for x, y in pts))
    raise ValueError(f"footprint type {code}: unknown, or a polygon without vertices")
