"""Lint of robots/hang/shapes.yaml: it reads, and the shapes drawn from it are sound mugs and
hooks whose arm lies inside the query grid X_h."""

import numpy as np
import pytest
import torch
import yaml

from robotplan.base.resources import robots_dir
from robotplan.hanging.scene.ranges import HangRanges, load_hang_ranges
from robotplan.scene.reader import SchemaError, read


def test_ranges_read_and_the_grid_is_the_papers():
    ranges = load_hang_ranges()
    assert ranges.grid.cells == 40 and abs(ranges.grid.size / ranges.grid.cells - 0.01) < 1e-12


def test_drawn_mugs_keep_the_handle_on_the_cup(rng):
    ranges = load_hang_ranges()
    for _ in range(200):
        mug = ranges.mug.sample(rng)
        z = mug.handle_points()[:, 2]
        assert mug.handle_span > 0
        assert z.min() - mug.handle_radius >= mug.wall - 1e-12
        assert z.max() + mug.handle_radius <= mug.height + 1e-12
        lo, hi = ranges.mug.radius
        assert lo <= mug.radius <= hi


def test_drawn_hooks_lie_in_the_grid(rng):
    ranges = load_hang_ranges()
    parts = set()
    for k in range(200):
        hook = ranges.hook.sample(rng)
        parts.add(len(hook.lengths))
        centre = ranges.grid.centre(hook)
        arm = hook.arm_points()
        assert np.all(np.abs(arm - centre) < ranges.grid.size / 2)
        if k >= 10:
            continue
        pts = torch.from_numpy(ranges.grid.points(hook).reshape(-1, 3))
        assert (hook.sdf(pts) < 0).any(), "the grid sees the hook"
    assert parts == {2, 3}


def test_a_bad_range_names_its_field():
    data = yaml.safe_load((robots_dir() / "hang" / "shapes.yaml").read_text())
    data["mug"]["height"] = [0.12, 0.07]
    with pytest.raises(SchemaError, match=r"mug\.height"):
        read(HangRanges, data)
