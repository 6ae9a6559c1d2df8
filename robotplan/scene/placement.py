"""Start placement of a scene's bodies: inside the workspace, and no two overlapping.

Bodies whose footprints share less than ``OVERLAP_AREA`` merely touch. The pairwise test
is quadratic in the number of bodies, so each pair is settled cheaply where it can be:
bounding boxes apart; discs by their exact areas (a disc and a disc, a disc and a polygon,
vectorised over the edges); two polygons whose boundaries stay apart overlap only when one
holds the other. Only polygons that touch or cross go through the exact (slower) clipping
of :func:`robotplan.geometry.polygons.intersection_area`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from robotplan.geometry.polygons import intersection_area, signed_area
from robotplan.scene.reader import SchemaError
from robotplan.sdf import Circle

if TYPE_CHECKING:
    from robotplan.scene.bodies import Body
    from robotplan.scene.schema import Scene

__all__ = ["OVERLAP_AREA", "check_placement", "overlap_area"]

OVERLAP_AREA = 1e-9  # m²: footprints sharing less than this merely touch
_TOL = 1e-9  # m


def check_placement(scene: Scene, where: dict[str, str]) -> None:
    """Every table body and the goal region inside the workspace; no two bodies that meet
    in height overlapping at the start. Raises SchemaError naming the later body's pose."""
    x0, x1, y0, y1 = scene.workspace.bounds
    bounds = f"x in [{x0:g}, {x1:g}], y in [{y0:g}, {y1:g}]"

    def inside(outline: np.ndarray) -> bool:
        return bool(outline[:, 0].min() >= x0 - _TOL and outline[:, 0].max() <= x1 + _TOL
                    and outline[:, 1].min() >= y0 - _TOL and outline[:, 1].max() <= y1 + _TOL)

    q0_given = {r.name for r in scene.robots if r.q0 is not None}

    def pose_field(b: Body) -> str:
        """The field that places ``b``: a robot's tip follows its q0 or else its base."""
        if b.role == "robot":
            return f"{where[b.name]}.{'q0' if b.name in q0_given else 'base'}"
        return f"{where[b.name]}.{'position' if b.role == 'pusher' else 'pose'}"

    bodies = list(scene.bodies.values())
    outlines = {b.name: b.outline_world() for b in bodies}
    for b in bodies:
        if b.role != "robot" and not inside(outlines[b.name]):
            raise SchemaError(pose_field(b),
                              f"{b.name!r} lies (partly) outside the workspace ({bounds})")
    if scene.goal_region is not None and not inside(scene.goal_region.outline_world()):
        where = "goal.pose" if scene.goal.type == "pose" else "goal.region.pose"
        raise SchemaError(where, f"the goal region lies (partly) outside the "
                          f"workspace ({bounds})")
    boxes = {name: (o.min(axis=0), o.max(axis=0)) for name, o in outlines.items()}
    for i, a in enumerate(bodies):
        for b in bodies[i + 1:]:
            if a.top <= b.bottom or b.top <= a.bottom:
                continue  # one passes above the other
            (lo_a, hi_a), (lo_b, hi_b) = boxes[a.name], boxes[b.name]
            if (lo_a > hi_b + _TOL).any() or (lo_b > hi_a + _TOL).any():
                continue  # bounding boxes apart
            area = overlap_area(a, b, outlines[a.name], outlines[b.name])
            if area > OVERLAP_AREA:
                raise SchemaError(pose_field(b), f"{b.name!r} overlaps {a.name!r} at the "
                                  f"start ({area * 1e4:.2f} cm²)")


def overlap_area(a: Body, b: Body, outline_a: np.ndarray, outline_b: np.ndarray) -> float:
    """Area (m²) shared by the footprints of ``a`` and ``b`` given their world outlines."""
    disc_a, disc_b = isinstance(a.shape, Circle), isinstance(b.shape, Circle)
    if disc_a and disc_b:
        return _disc_disc_area(np.asarray(a.pose[:2]), a.shape.radius,
                               np.asarray(b.pose[:2]), b.shape.radius)
    if disc_a or disc_b:
        disc, polygon = (a, outline_b) if disc_a else (b, outline_a)
        return _disc_polygon_area(np.asarray(disc.pose[:2]), disc.shape.radius, polygon)
    return _polygon_polygon_area(outline_a, outline_b)


def _disc_disc_area(c1: np.ndarray, r1: float, c2: np.ndarray, r2: float) -> float:
    """Exact area of the lens shared by two discs."""
    d = float(np.hypot(*(c2 - c1)))
    if d >= r1 + r2:
        return 0.0
    if d <= abs(r1 - r2):
        return math.pi * min(r1, r2) ** 2
    a1 = math.acos(max(-1.0, min(1.0, (d * d + r1 * r1 - r2 * r2) / (2 * d * r1))))
    a2 = math.acos(max(-1.0, min(1.0, (d * d + r2 * r2 - r1 * r1) / (2 * d * r2))))
    kite = 0.5 * math.sqrt(max(0.0, (-d + r1 + r2) * (d + r1 - r2) * (d - r1 + r2)
                                * (d + r1 + r2)))
    return r1 * r1 * a1 + r2 * r2 * a2 - kite


def _disc_polygon_area(centre: np.ndarray, r: float, polygon: np.ndarray) -> float:
    """Exact area shared by a disc and a simple polygon: the sum over the polygon's edges of
    the signed area of the disc within the triangle (centre, edge), all edges at once."""
    p = polygon - centre
    a, b = p, np.roll(p, -1, axis=0)
    e = b - a
    # |a + t e| = r at the roots t of (e·e) t² + 2 (a·e) t + (a·a − r²) = 0
    ee = np.maximum((e * e).sum(1), 1e-300)
    ae = (a * e).sum(1)
    disc = ae * ae - ee * ((a * a).sum(1) - r * r)
    root = np.sqrt(np.maximum(disc, 0.0))
    t1 = np.where(disc > 0, (-ae - root) / ee, 0.0).clip(0.0, 1.0)
    t2 = np.where(disc > 0, (-ae + root) / ee, 0.0).clip(0.0, 1.0)
    ts = np.stack([np.zeros_like(t1), t1, t2, np.ones_like(t1)], axis=1)  # (V, 4)
    pts = a[:, None, :] + ts[..., None] * e[:, None, :]  # (V, 4, 2): up to 3 pieces an edge
    s, f = pts[:, :-1], pts[:, 1:]
    cross = s[..., 0] * f[..., 1] - s[..., 1] * f[..., 0]
    dot = (s * f).sum(-1)
    mid = 0.5 * (s + f)
    in_disc = (mid * mid).sum(-1) <= r * r
    # a piece inside the disc adds its triangle with the centre, one outside the disc sector
    area = np.where(in_disc, 0.5 * cross, 0.5 * r * r * np.arctan2(cross, dot))
    return float(abs(area.sum()))


def _polygon_polygon_area(pa: np.ndarray, pb: np.ndarray) -> float:
    """Exact area shared by two simple polygons; the clipping only where they meet."""
    if _boundary_distance(pa, pb) > _TOL:
        if _contains(pb, pa[0]):
            return abs(signed_area(pa))  # b holds all of a
        if _contains(pa, pb[0]):
            return abs(signed_area(pb))
        return 0.0
    return intersection_area(pa, pb)


def _boundary_distance(pa: np.ndarray, pb: np.ndarray) -> float:
    """Distance between the boundaries of two polygons (0 where edges cross)."""
    a0, a1 = pa, np.roll(pa, -1, axis=0)
    b0, b1 = pb, np.roll(pb, -1, axis=0)

    def side(o: np.ndarray, d: np.ndarray, p: np.ndarray) -> np.ndarray:  # (n, 1) x (1, m)
        return ((d[..., 0] - o[..., 0]) * (p[..., 1] - o[..., 1])
                - (d[..., 1] - o[..., 1]) * (p[..., 0] - o[..., 0]))

    A0, A1, B0, B1 = a0[:, None], a1[:, None], b0[None], b1[None]
    crosses = ((side(B0, B1, A0) * side(B0, B1, A1) < 0)
               & (side(A0, A1, B0) * side(A0, A1, B1) < 0))
    if crosses.any():
        return 0.0
    return math.sqrt(min(_point_segment_d2(pa, b0, b1).min(),
                         _point_segment_d2(pb, a0, a1).min()))


def _point_segment_d2(p: np.ndarray, s0: np.ndarray, s1: np.ndarray) -> np.ndarray:
    """Squared distances ``(P, S)`` from points ``p (P, 2)`` to segments ``s0 → s1 (S, 2)``."""
    e = s1 - s0
    w = p[:, None, :] - s0[None]
    t = ((w * e).sum(-1) / np.maximum((e * e).sum(-1), 1e-300)).clip(0.0, 1.0)
    d = w - t[..., None] * e
    return (d * d).sum(-1)


def _contains(polygon: np.ndarray, point: np.ndarray) -> bool:
    """Whether ``point`` lies inside ``polygon`` (crossing number; not on its boundary)."""
    a, b = polygon, np.roll(polygon, -1, axis=0)
    x, y = point
    straddles = (a[:, 1] > y) != (b[:, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return bool((straddles & (x < x_cross)).sum() % 2)
