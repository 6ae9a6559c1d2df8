"""Footprint storage: every kind survives a shard, the unseen families are what they say."""

import numpy as np
import pytest
import torch

from robotplan.pushing.training.footprints import (
    MAX_VERTICES,
    OOD_FAMILIES,
    decode_footprint,
    draw_ood_shape,
    encode_footprint,
)
from robotplan.sdf import Box, Circle, LShape, Polygon


@pytest.fixture
def rng():
    return np.random.default_rng(0)


def test_every_footprint_round_trips_through_its_stored_form(rng):
    shapes = [Box((0.2, 0.1)), LShape((0.2, 0.25), 0.06),
              *(draw_ood_shape(rng, f) for f in OOD_FAMILIES)]
    points = torch.rand(200, 2, dtype=torch.float64) * 0.4 - 0.2
    for shape in shapes:
        code, size, thickness, vertices = encode_footprint(shape)
        assert vertices.shape == (MAX_VERTICES, 2)
        stored = np.asarray(size, dtype=np.float32), np.float32(thickness)
        again = decode_footprint(code, stored[0], float(stored[1]),
                                 vertices.astype(np.float32))
        assert type(again) is type(shape)
        # float32 storage: the SDFs agree to its rounding
        assert torch.max(torch.abs(again.sdf(points) - shape.sdf(points))) < 1e-6, shape
        # the stored bounding size covers the footprint (query points reach from it)
        half = np.asarray(size) / 2
        outline = np.asarray(shape.outline())
        assert np.all(np.abs(outline) <= half + 1e-9), shape


def test_the_unseen_families_are_concave_where_they_should_be(rng):
    for family in OOD_FAMILIES:
        shape = draw_ood_shape(rng, family)
        if family == "circle":
            assert isinstance(shape, Circle)
            continue
        assert isinstance(shape, Polygon)
        pts = np.asarray(shape.vertices)
        e = np.roll(pts, -1, 0) - pts
        f = np.roll(e, -1, 0)
        turns = np.sign(e[:, 0] * f[:, 1] - e[:, 1] * f[:, 0])  # the turn at each vertex
        assert (len(set(turns)) > 1) == (family in ("T", "cross", "U")), family
    with pytest.raises(ValueError, match="unknown footprint family"):
        draw_ood_shape(rng, "star")
