"""The paper's success metric: the share of an object's footprint inside the goal region."""

from __future__ import annotations

from collections.abc import Sequence

from robotplan.geometry.polygons import intersection_area, signed_area
from robotplan.scene.bodies import Body

__all__ = ["coverage"]


def coverage(body: Body, X_WB: Sequence[float], region: Body) -> float:
    """area(body at ``X_WB`` ∩ region) / area(body), in [0, 1].

    Exact for polygonal footprints (box, lshape, polygon); discs are 720-gons (relative
    area error 1.3e-5). ``X_WB = (x, y, yaw)``.
    """
    outline = body.outline_world(tuple(X_WB))
    inside = intersection_area(outline, region.outline_world())
    return min(1.0, inside / abs(signed_area(outline)))
