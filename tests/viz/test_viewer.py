"""The playback page's bodies."""

from __future__ import annotations

import numpy as np
import pytest

from tests.conftest import TASKS


def test_a_mesh_object_is_shown_as_its_mesh():
    """Its surface in the playback is the mesh, standing on the table in the footprint's
    frame: the same outline from above, the mesh's height."""
    from robotplan import load_scene
    from robotplan.viz.viewer import _body_mesh

    scene = load_scene(TASKS / "mesh_push.yaml")
    surface = _body_mesh(scene, "bracket")
    points = np.array([surface.vertex(i) for i in range(surface.num_vertices())])
    outline = scene.bodies["bracket"].shape.outline()
    assert np.abs(points[:, :2].min(0) - outline.min(0)).max() < 1e-6
    assert np.abs(points[:, :2].max(0) - outline.max(0)).max() < 1e-6
    assert points[:, 2].min() == pytest.approx(0.0) and points[:, 2].max() == pytest.approx(0.04)
