"""A mesh's footprint as an SDF: exact with holes, against shapely's distances."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from shapely.geometry import Point
from shapely.geometry import Polygon as ShapelyPolygon

from robotplan.sdf.mesh_footprint import MeshFootprint

OUTER = ((-0.1, -0.05), (0.1, -0.05), (0.1, 0.05), (0.0, 0.02), (-0.1, 0.05))
HOLES = (((-0.06, -0.03), (-0.04, -0.01), (-0.02, -0.03)),  # clockwise
         ((0.03, -0.02), (0.03, 0.0), (0.06, 0.0), (0.06, -0.02)))


def test_the_sdf_is_the_signed_distance_of_the_solid_with_holes(rng):
    shape = MeshFootprint(vertices=OUTER, holes=HOLES)
    solid = ShapelyPolygon(OUTER, HOLES)
    points = rng.uniform(-0.14, 0.14, size=(2000, 2))
    phi = shape.sdf(torch.as_tensor(points, dtype=torch.float64)).numpy()
    boundary = solid.boundary
    expected = np.array([boundary.distance(Point(p)) * (-1 if solid.contains(Point(p)) else 1)
                         for p in points])
    assert np.abs(phi - expected).max() < 1e-9
    inside_holes = [ShapelyPolygon(OUTER).contains(Point(p)) and not solid.contains(Point(p))
                    for p in points]
    assert sum(inside_holes) > 10 and (phi[np.array(inside_holes)] > 0).all()


def test_area_takes_the_holes_out_and_the_outline_is_the_outer_loop():
    shape = MeshFootprint(vertices=OUTER, holes=HOLES)
    assert shape.area == pytest.approx(ShapelyPolygon(OUTER, HOLES).area)
    assert len(shape.outline()) == len(OUTER) and shape.type == "polygon"
    assert "2 holes" in shape.describe()


def test_the_closed_form_gradient_is_autograds(rng):
    shape = MeshFootprint(vertices=OUTER, holes=HOLES)
    points = torch.from_numpy(rng.uniform(-0.14, 0.14, size=(2000, 2)))
    phi, g = shape.sdf_and_grad(points)
    p = points.clone().requires_grad_(True)
    (ref,) = torch.autograd.grad(shape.sdf(p).sum(), p)
    assert (phi - shape.sdf(points)).abs().max() < 1e-14
    assert (g - ref).abs().max() < 1e-9
