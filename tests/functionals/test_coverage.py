"""Coverage (the paper's metric) against shapely's exact intersection areas."""

import numpy as np
import pytest
import shapely

from robotplan.functionals.coverage import coverage
from robotplan.scene.bodies import Body
from robotplan.sdf import Box, Circle, LShape, Polygon

REGION = Body("goal", "region", Box((0.4, 0.4)), (0.36, 0.05, 0.0), 0.0, 0.0)
SHAPES = [Box((0.2, 0.12)), LShape((0.24, 0.18), 0.07),
          Polygon(((0, 0), (0.2, 0), (0.2, 0.05), (0.05, 0.05), (0.05, 0.2), (0, 0.2))),
          Polygon(((0.0, 0.0), (0.15, 0.02), (0.05, 0.12)))]


def shapely_coverage(body: Body, pose, region: Body) -> float:
    a = shapely.Polygon(body.outline_world(pose))
    return a.intersection(shapely.Polygon(region.outline_world())).area / a.area


@pytest.mark.parametrize("shape", SHAPES, ids=lambda s: s.type)
def test_coverage_matches_exact_area(shape, rng):
    body = Body("obj", "object", shape, (0, 0, 0), 0.0, 0.06)
    for _ in range(40):
        pose = (rng.uniform(0.0, 0.7), rng.uniform(-0.3, 0.4), rng.uniform(-np.pi, np.pi))
        assert abs(coverage(body, pose, REGION) - shapely_coverage(body, pose, REGION)) < 1e-9


def test_coverage_extremes_and_rotated_concave_region():
    box = Body("obj", "object", Box((0.1, 0.1)), (0, 0, 0), 0.0, 0.06)
    assert coverage(box, (0.36, 0.05, 0.3), REGION) == pytest.approx(1.0)
    assert coverage(box, (-0.5, 0.0, 0.0), REGION) == 0.0
    assert coverage(box, (0.16, 0.05, 0.0), REGION) == pytest.approx(0.5)  # half across edge
    ell_region = Body("goal", "region", LShape((0.4, 0.4), 0.1), (0.0, 0.0, 0.7), 0.0, 0.0)
    pose = (-0.05, -0.1, 0.2)
    assert coverage(box, pose, ell_region) == pytest.approx(
        shapely_coverage(box, pose, ell_region), abs=1e-9)


def test_circle_coverage_within_1e3():
    disc = Body("obj", "object", Circle(0.05), (0, 0, 0), 0.0, 0.06)
    # a disc centred on the region's edge is half inside
    assert coverage(disc, (0.16, 0.05, 0.0), REGION) == pytest.approx(0.5, abs=1e-3)
