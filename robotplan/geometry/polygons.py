"""Exact planar polygon geometry in numpy (float64): areas, validity, intersections.

Used for the coverage metric (share of an object's footprint inside a goal region) and for
scene validation (self-intersection, overlap at the start). Polygons are ``(V, 2)`` arrays
of vertices in order, either winding, without the closing vertex repeated.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "area_centroid",
    "as_ccw",
    "clip_convex",
    "convex_parts",
    "intersection_area",
    "is_convex",
    "is_simple",
    "signed_area",
    "triangulate",
]

_EPS = 1e-12


def signed_area(poly: np.ndarray) -> float:
    """Shoelace area: positive for counter-clockwise, negative for clockwise vertices."""
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def area_centroid(loops: list[np.ndarray]) -> np.ndarray:
    """Area centroid ``(2,)`` of a polygon given as its loops ``[(V, 2)]``: the outer one
    counter-clockwise, holes clockwise (their signed areas and moments subtract)."""
    moment, area = 0.0, 0.0
    for p in loops:
        q = np.roll(p, -1, axis=0)
        cross = p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]
        moment = moment + ((p + q) * cross[:, None]).sum(0)
        area = area + signed_area(p)
    return moment / (6.0 * area)


def as_ccw(poly: np.ndarray) -> np.ndarray:
    """The same polygon with counter-clockwise winding."""
    poly = np.asarray(poly, dtype=np.float64)
    return poly if signed_area(poly) >= 0 else poly[::-1].copy()


def _cross(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))


def _on_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> bool:
    return bool(
        min(a[0], b[0]) - _EPS <= p[0] <= max(a[0], b[0]) + _EPS
        and min(a[1], b[1]) - _EPS <= p[1] <= max(a[1], b[1]) + _EPS
    )


def segments_intersect(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray) -> bool:
    """Whether closed segments ab and cd share a point (touching and collinear overlap count)."""
    d1, d2 = _cross(c, d, a), _cross(c, d, b)
    d3, d4 = _cross(a, b, c), _cross(a, b, d)
    if ((d1 > _EPS and d2 < -_EPS) or (d1 < -_EPS and d2 > _EPS)) and (
        (d3 > _EPS and d4 < -_EPS) or (d3 < -_EPS and d4 > _EPS)
    ):
        return True
    return (
        (abs(d1) <= _EPS and _on_segment(a, c, d))
        or (abs(d2) <= _EPS and _on_segment(b, c, d))
        or (abs(d3) <= _EPS and _on_segment(c, a, b))
        or (abs(d4) <= _EPS and _on_segment(d, a, b))
    )


def is_simple(poly: np.ndarray) -> tuple[bool, str]:
    """Whether a polygon is simple (no edge crosses or touches a non-adjacent edge).

    Returns ``(ok, reason)``; ``reason`` says what is wrong when ``ok`` is False.
    """
    poly = np.asarray(poly, dtype=np.float64)
    n = len(poly)
    if n < 3:
        return False, f"needs at least 3 vertices, got {n}"
    for i in range(n):
        if np.linalg.norm(poly[i] - poly[(i + 1) % n]) <= _EPS:
            return False, f"vertices {i} and {(i + 1) % n} coincide"
    for i in range(n):
        a, b = poly[i], poly[(i + 1) % n]
        for j in range(i + 1, n):
            if j == i or (j + 1) % n == i or j == (i + 1) % n:
                continue  # adjacent edges share a vertex by construction
            if segments_intersect(a, b, poly[j], poly[(j + 1) % n]):
                return False, f"edges {i} and {j} intersect (self-intersecting polygon)"
    # adjacent edges folding back onto each other (a spike) also make it non-simple
    for i in range(n):
        p, q, r = poly[i - 1], poly[i], poly[(i + 1) % n]
        if abs(_cross(p, q, r)) <= _EPS and np.dot(q - p, r - q) < 0:
            return False, f"edges meeting at vertex {i} fold back onto each other"
    if abs(signed_area(poly)) <= _EPS:
        return False, "has zero area"
    return True, ""


def triangulate(poly: np.ndarray) -> list[np.ndarray]:
    """Ear-clipping triangulation of a simple polygon into CCW triangles ``(3, 2)``."""
    pts = as_ccw(poly)
    idx = list(range(len(pts)))
    tris: list[np.ndarray] = []
    guard = 0
    while len(idx) > 3 and guard < 10 * len(pts) ** 2:
        guard += 1
        m = len(idx)
        for k in range(m):
            i0, i1, i2 = idx[k - 1], idx[k], idx[(k + 1) % m]
            a, b, c = pts[i0], pts[i1], pts[i2]
            if _cross(a, b, c) <= _EPS:
                continue  # reflex or degenerate corner: not an ear
            if any(
                _point_in_triangle(pts[j], a, b, c) for j in idx if j not in (i0, i1, i2)
            ):
                continue
            tris.append(np.stack([a, b, c]))
            idx.pop(k)
            break
        else:  # only collinear corners remain; drop one (it carries no area)
            idx.pop(0)
    if len(idx) == 3:
        tri = pts[idx]
        if abs(signed_area(tri)) > _EPS:
            tris.append(tri)
    return tris


def _point_in_triangle(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> bool:
    return _cross(a, b, p) >= -_EPS and _cross(b, c, p) >= -_EPS and _cross(c, a, p) >= -_EPS


def clip_convex(subject: np.ndarray, clip: np.ndarray) -> np.ndarray:
    """Sutherland–Hodgman: the part of ``subject`` inside the convex CCW polygon ``clip``.

    ``subject`` may be concave; the result may then contain zero-width bridges, which
    carry no area, so its shoelace area is exact.
    """
    out = np.asarray(subject, dtype=np.float64)
    n = len(clip)
    for i in range(n):
        if len(out) == 0:
            break
        a, b = clip[i], clip[(i + 1) % n]
        edge = b - a
        side = edge[0] * (out[:, 1] - a[1]) - edge[1] * (out[:, 0] - a[0])  # >= 0: inside
        new: list[np.ndarray] = []
        m = len(out)
        for j in range(m):
            p, q = out[j], out[(j + 1) % m]
            sp, sq = side[j], side[(j + 1) % m]
            if sp >= 0:
                new.append(p)
            if (sp >= 0) != (sq >= 0):
                new.append(p + (q - p) * (sp / (sp - sq)))
        out = np.array(new).reshape(-1, 2)
    return out


def is_convex(poly: np.ndarray) -> bool:
    """Whether a simple polygon is convex (collinear vertices allowed)."""
    p = as_ccw(poly)
    e = np.roll(p, -1, axis=0) - p
    turn = e[:, 0] * np.roll(e[:, 1], -1) - e[:, 1] * np.roll(e[:, 0], -1)
    return bool((turn >= -_EPS).all())


def intersection_area(poly_a: np.ndarray, poly_b: np.ndarray) -> float:
    """Exact area of the intersection of two simple polygons (either may be concave).

    A convex one clips the other directly; two concave ones go through an ear-clipping
    triangulation of the second.
    """
    a, b = as_ccw(poly_a), as_ccw(poly_b)
    if (a.min(0) > b.max(0)).any() or (b.min(0) > a.max(0)).any():
        return 0.0  # bounding boxes apart
    if is_convex(b):
        clips, subject = [b], a
    elif is_convex(a):
        clips, subject = [a], b
    else:
        clips, subject = triangulate(b), a
    total = 0.0
    for clip in clips:
        piece = clip_convex(subject, clip)
        if len(piece) >= 3:
            total += abs(signed_area(piece))
    return total


def convex_parts(poly: np.ndarray) -> list[np.ndarray]:
    """Convex pieces ``[(V_i, 2)]`` (CCW) whose union is the simple polygon ``poly``: the
    polygon itself when convex, else its ear-clipping triangles merged greedily across
    shared edges while the union stays convex (Hertel–Mehlhorn style)."""
    poly = as_ccw(poly)
    if is_convex(poly):
        return [poly]
    parts = [t.copy() for t in triangulate(poly)]
    merged = True
    while merged:
        merged = False
        for i in range(len(parts)):
            for j in range(i + 1, len(parts)):
                union = _merge_on_shared_edge(parts[i], parts[j])
                if union is not None and is_convex(union):
                    parts[i] = union
                    parts.pop(j)
                    merged = True
                    break
            if merged:
                break
    return parts


def _merge_on_shared_edge(a: np.ndarray, b: np.ndarray) -> np.ndarray | None:
    """The polygon a ∪ b when they share an edge (a's u→v is b's v→u), else None."""
    n, m = len(a), len(b)
    for i in range(n):
        u, v = a[i], a[(i + 1) % n]
        for j in range(m):
            if np.allclose(b[j], v) and np.allclose(b[(j + 1) % m], u):
                # walk a from v round to u, then b from u (after j+1) round to v
                ring = [a[(i + 1 + k) % n] for k in range(n)]
                ring += [b[(j + 2 + k) % m] for k in range(m - 2)]
                return np.array(ring)
    return None
