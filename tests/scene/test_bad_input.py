"""Inputs at the edges of the scene format (exponent numbers, huge grids, regions smaller
than their object, big files, wrong types anywhere): each is read correctly or refused in one
line naming the file and the field, within seconds."""

from __future__ import annotations

import pytest

from robotplan import SceneError, load_scene
from robotplan.scene import parse_scene
from tests.scene.test_loader import BASE, mutate


def refused(path) -> SceneError:
    with pytest.raises(SceneError) as err:
        load_scene(path)
    assert err.value.file == str(path)
    assert "\n" not in str(err.value) and len(str(err.value)) < 400, str(err.value)
    return err.value


def test_numbers_far_beyond_any_table_are_refused(tmp_path):
    for value, words in ((1e300, "magnitude"), (10**400, "magnitude"), (-1e7, "magnitude")):
        with pytest.raises(SceneError, match=words) as err:
            parse_scene(mutate(BASE, "objects.0.pose", [value, 0.0, 0.0]))
        assert err.value.field == "objects[0].pose[0]"


# --- wrong types anywhere ------------------------------------------------------------------

@pytest.mark.parametrize(("path", "value", "field"), [
    ("objects.0.shape.type", {}, "objects[0].shape.type"),
    ("objects.0.shape.type", [], "objects[0].shape.type"),
    ("goal.type", {"a": 1}, "goal.type"),
    ("goal.region.shape.type", [1], "goal.region.shape.type"),
    ("goal.region.shape", "box", "goal.region.shape"),
    ("workspace", [], "workspace"),
    ("workspace.size", {}, "workspace.size"),
    ("version", {}, "version"),
    ("version", [1], "version"),
    ("name", {}, "name"),
    ("objects.0", None, "objects[0]"),
    ("objects.0.name", ["box"], "objects[0].name"),
    ("pushers.0.touches", "box", "pushers[0].touches"),
    ("pushers.0.touches", [{}], "pushers[0].touches[0]"),
    ("goal.object", {}, "goal.object"),
])
def test_a_wrong_typed_field_is_one_line(path, value, field):
    with pytest.raises(SceneError) as err:
        parse_scene(mutate(BASE, path, value))
    assert err.value.field == field, str(err.value)
