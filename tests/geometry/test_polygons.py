import numpy as np
import pytest
import shapely

from robotplan.geometry.polygons import intersection_area, is_simple, signed_area, triangulate


def random_star_polygon(rng, n=9, center=(0.0, 0.0)):
    """A simple (star-shaped) polygon, usually concave."""
    ang = np.sort(rng.uniform(0, 2 * np.pi, n))
    rad = rng.uniform(0.05, 0.2, n)
    return np.stack([center[0] + rad * np.cos(ang), center[1] + rad * np.sin(ang)], 1)


def test_triangulation_preserves_area(rng):
    for _ in range(30):
        poly = random_star_polygon(rng)
        tris = triangulate(poly)
        assert len(tris) == len(poly) - 2
        assert sum(signed_area(t) for t in tris) == pytest.approx(abs(signed_area(poly)), abs=1e-14)


def test_intersection_area_matches_shapely(rng):
    for _ in range(50):
        a = random_star_polygon(rng)
        b = random_star_polygon(rng, center=tuple(rng.uniform(-0.15, 0.15, 2)))
        if rng.random() < 0.5:
            b = b[::-1]
        ref = shapely.Polygon(a).intersection(shapely.Polygon(b)).area
        assert intersection_area(a, b) == pytest.approx(ref, abs=1e-12)


@pytest.mark.parametrize(("poly", "reason"), [
    ([[0, 0], [1, 1], [1, 0], [0, 1]], "intersect"),          # bow tie
    ([[0, 0], [1, 0]], "at least 3"),
    ([[0, 0], [1, 0], [1, 0], [0, 1]], "coincide"),
    ([[0, 0], [1, 0], [2, 0]], "fold back"),
    ([[0, 0], [2, 0], [2, 2], [1, 0], [0, 2]], "intersect"),  # a vertex touching an edge
])
def test_non_simple_polygons_are_refused(poly, reason):
    ok, why = is_simple(np.array(poly, dtype=float))
    assert not ok and reason in why


def test_concave_polygon_is_simple():
    ok, why = is_simple(np.array([[0, 0], [2, 0], [2, 2], [1, 1], [0, 2]], dtype=float))
    assert ok, why


def test_convex_parts_cover_the_polygon_with_few_convex_pieces(rng):
    from robotplan.geometry.polygons import convex_parts, is_convex

    for _ in range(30):
        poly = random_star_polygon(rng)
        parts = convex_parts(poly)
        assert all(is_convex(p) and signed_area(p) > 0 for p in parts)
        assert sum(signed_area(p) for p in parts) == pytest.approx(abs(signed_area(poly)),
                                                                 abs=1e-14)
        union = shapely.unary_union([shapely.Polygon(p) for p in parts])
        assert union.symmetric_difference(shapely.Polygon(poly)).area < 1e-10
        assert len(parts) <= len(poly) - 2
    cross = np.array([[1, -3], [1, -1], [3, -1], [3, 1], [1, 1], [1, 3], [-1, 3], [-1, 1],
                      [-3, 1], [-3, -1], [-1, -1], [-1, -3]], dtype=float)
    assert len(convex_parts(cross)) <= 5  # 10 triangles merge into a few convex pieces
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    assert len(convex_parts(square)) == 1
