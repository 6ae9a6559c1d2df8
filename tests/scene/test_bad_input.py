"""Inputs at the edges of the scene format (exponent numbers, huge grids, regions smaller
than their object, big files, wrong types anywhere): each is read correctly or refused in one
line naming the file and the field, within seconds."""

from __future__ import annotations

import json
import math
import time

import pytest
import yaml

from robotplan import SceneError, load_scene
from robotplan.scene import parse_scene
from robotplan.scene.limits import MAX_BODIES, MAX_GRID_CELLS, MAX_POLYGON_VERTICES
from tests.conftest import TASKS
from tests.scene.test_loader import ARMS, BASE, mutate


def refused(path) -> SceneError:
    with pytest.raises(SceneError) as err:
        load_scene(path)
    assert err.value.file == str(path)
    assert "\n" not in str(err.value) and len(str(err.value)) < 400, str(err.value)
    return err.value


# --- numbers with an exponent --------------------------------------------------------------

@pytest.mark.parametrize("name", ["scene.json", "scene.JSON", "scene.yaml", "scene", "scene.txt"])
def test_json_exponent_numbers_are_numbers_whatever_the_file_name(tmp_path, name):
    data = mutate(BASE, "objects.0.pose", [3e-06, 0.02, 0.4])
    text = json.dumps(data, indent="\t" if name.endswith(("json", "JSON")) else 2)
    assert "3e-06" in text
    f = tmp_path / name
    f.write_text(text)
    assert load_scene(f).objects[0].pose == (3e-06, 0.02, 0.4)


def test_yaml_reads_exponent_floats_and_keeps_ints_and_strings(tmp_path):
    f = tmp_path / "exp.yaml"
    f.write_text((TASKS / "box_push.yaml").read_text()
                 .replace("pose: [0.0, 0.02, 0.4]", "pose: [3e-06, 2E-2, 4e-1]")
                 .replace("radius: 0.03", "radius: 3.0e-2")
                 .replace("size: [0.4, 0.4]", "size: [4e-1, 1E0]")
                 .replace("name: box_push", "name: 1e5x"))
    scene = load_scene(f)
    assert scene.objects[0].pose == (3e-06, 0.02, 0.4)
    assert scene.pushers[0].radius == 0.03
    assert scene.goal.region.shape.size == (0.4, 1.0)
    assert scene.name == "1e5x" and scene.version == 1
    from robotplan.scene.files import _parse_yaml

    assert _parse_yaml("[1e-3, 3e-06, 1E5, -2.5e+2, 7, 0x10, e5, 1e, .5e1]") == [
        0.001, 3e-06, 100000.0, -250.0, 7, 16, "e5", "1e", 5.0]


def test_json_duplicate_keys_and_bad_json_are_refused(tmp_path):
    f = tmp_path / "dup.json"
    f.write_text('{"version": 1, "version": 1}')
    assert "duplicate key 'version'" in refused(f).message
    g = tmp_path / "deep.json"
    g.write_text("[" * 100_000 + "]" * 100_000)
    assert "JSON" in refused(g).message
    h = tmp_path / "long.json"
    h.write_text('{"version": ' + "1" * 5000 + "}")
    assert "JSON" in refused(h).message


# --- the workspace grid --------------------------------------------------------------------

def test_a_huge_workspace_is_refused_with_its_cell_count(tmp_path):
    f = tmp_path / "km.yaml"
    f.write_text(yaml.safe_dump(mutate(BASE, "workspace.size", [1e6, 1e6])))  # 1,000 km
    err = refused(f)
    assert err.field == "workspace.size"
    assert "1e+16 cells" in err.message and f"{MAX_GRID_CELLS:,}" in err.message
    g = tmp_path / "fine.yaml"
    g.write_text(yaml.safe_dump(mutate(BASE, "workspace.resolution", 1e-5)))
    err = refused(g)
    assert err.field == "workspace.resolution" and "cells" in err.message
    coarse = mutate(mutate(BASE, "workspace.size", [2000.0, 2000.0]), "workspace.resolution", 1)
    assert parse_scene(coarse).workspace.shape == (2000, 2000)  # as many cells is fine


def test_numbers_far_beyond_any_table_are_refused(tmp_path):
    for value, words in ((1e300, "magnitude"), (10**400, "magnitude"), (-1e7, "magnitude")):
        with pytest.raises(SceneError, match=words) as err:
            parse_scene(mutate(BASE, "objects.0.pose", [value, 0.0, 0.0]))
        assert err.value.field == "objects[0].pose[0]"


# --- a goal region smaller than the object -------------------------------------------------

def test_a_region_smaller_than_the_object_is_refused_naming_both_areas():
    with pytest.raises(SceneError) as err:
        parse_scene(mutate(BASE, "goal.region.shape.size", [0.1, 0.1]))
    assert err.value.field == "goal.region"
    assert "100 cm²" in err.value.message and "240 cm²" in err.value.message  # box 20 x 12 cm
    with pytest.raises(SceneError) as err:
        parse_scene(mutate(BASE, "goal.region.shape", {"type": "circle", "radius": 0.08}))
    assert err.value.field == "goal.region"


def test_a_region_exactly_the_object_is_accepted():
    same = mutate(BASE, "goal.region", {"shape": BASE["objects"][0]["shape"],
                                        "pose": [0.36, 0.05, 0.4]})
    assert parse_scene(same).goal.region.shape == parse_scene(BASE).objects[0].shape


# --- big files -----------------------------------------------------------------------------

def star(n: int, r0: float = 0.2, r1: float = 0.05) -> list[list[float]]:
    """A star polygon of ``n`` vertices (spikes of radius r0, valleys r1)."""
    return [[round((r0 if i % 2 == 0 else r1) * math.cos(2 * math.pi * i / n), 9),
             round((r0 if i % 2 == 0 else r1) * math.sin(2 * math.pi * i / n), 9)]
            for i in range(n)]


def polygon_obstacle(name: str, pose: list[float], vertices: list[list[float]]) -> dict:
    return {"name": name, "pose": pose, "shape": {"type": "polygon", "vertices": vertices}}


def test_big_scene_files_are_refused_quickly(tmp_path):
    wide = mutate(BASE, "workspace.size", [4.0, 4.0])
    huge_polygon = mutate(wide, "obstacles", [polygon_obstacle("p", [1, 1, 0], star(150_000))])
    many_vertices = mutate(wide, "obstacles", [polygon_obstacle("p", [1, 1, 0], star(20_000))])
    many_polygons = mutate(wide, "obstacles", [
        polygon_obstacle(f"p{k}", [-1.5 + 0.41 * k, 1.5, 0], star(MAX_POLYGON_VERTICES))
        for k in range(9)])
    many_bodies = mutate(wide, "obstacles", [
        {"name": f"o{i}", "pose": [-1.9 + 0.002 * (i % 1000), -1.9 + 0.01 * (i // 1000), 0],
         "shape": {"type": "box", "size": [0.001, 0.001]}} for i in range(5000)])
    cases = [(huge_polygon, "", "MB"), (many_vertices, "obstacles[0].shape.vertices", "20000"),
             (many_polygons, "obstacles[8].shape.vertices", "at most 1024"),
             (many_bodies, "obstacles", f"at most {MAX_BODIES}")]
    for i, (data, field, words) in enumerate(cases):
        f = tmp_path / f"big{i}.json"  # JSON is YAML; json writes megabytes fast
        f.write_text(json.dumps(data))
        t0 = time.perf_counter()
        err = refused(f)
        assert time.perf_counter() - t0 < 5
        assert err.field == field and words in err.message, str(err)
    assert (tmp_path / "big0.json").stat().st_size > 4_000_000


def test_a_scene_at_the_limits_checks_in_seconds(tmp_path):
    """Eight 128-vertex stars whose spikes interleave (their bounding boxes overlap, they do
    not) and 91 pushers packed so that neighbours touch: every pair needs a real test."""
    data = mutate(BASE, "workspace.size", [4.0, 4.0])
    data["obstacles"] = [polygon_obstacle(f"s{k}", [-1.5 + 0.399 * k, 1.5, (k % 2) * math.pi / 64],
                                          star(MAX_POLYGON_VERTICES)) for k in range(8)]
    r = 0.03
    data["pushers"] = [{"name": f"p{i}", "radius": r,
                        "position": [-1.8 + (i % 10) * 2 * r + (i // 10 % 2) * r,
                                     -1.8 + (i // 10) * r * math.sqrt(3)]} for i in range(91)]
    data["objects"][0]["pose"] = [1.0, -1.0, 0.0]
    data["goal"]["region"]["pose"] = [1.5, -1.5, 0.0]
    f = tmp_path / "limits.yaml"
    f.write_text(yaml.safe_dump(data))
    t0 = time.perf_counter()
    scene = load_scene(f)
    assert time.perf_counter() - t0 < 5
    assert len(scene.bodies) == MAX_BODIES
    data["pushers"][1]["position"][0] -= 1e-3  # 1 mm into its neighbour
    with pytest.raises(SceneError, match="overlaps 'p0'") as err:
        parse_scene(data)
    assert err.value.field == "pushers[1].position"


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


@pytest.mark.parametrize(("text", "words"), [
    ("version: 1\n? [1, 2]\n: 3\n", "plain value"),
    ("version: 1\nname: 2001-13-01\n", "invalid YAML value"),
    ("version: 1\nname: !!int x\n", "invalid YAML value"),
    ("version: 1\nname: !!timestamp 99\n", "invalid YAML value"),
    ("version: " + "1" * 5000 + "\n", "invalid YAML value"),
    ("version: 1\nname: " + "[" * 5000 + "]" * 5000 + "\n", "invalid YAML"),
    ("version: 1\nobjects: &a [*a]\n", "objects[0]"),
])
def test_malformed_yaml_values_are_one_line(tmp_path, text, words):
    f = tmp_path / "bad.yaml"
    f.write_text(text)
    assert words in str(refused(f))


def test_yaml_merge_keys_are_plain_data(tmp_path):
    f = tmp_path / "merge.yaml"
    f.write_text((TASKS / "box_push.yaml").read_text().replace(
        "    radius: 0.03\n", "    <<: {radius: 0.03}\n"))
    assert load_scene(f).pushers[0].radius == 0.03


def test_a_robot_tip_overlapping_names_the_field_that_places_it():
    big_tip = mutate(ARMS, "robots.0.tip_radius", 0.5)
    with pytest.raises(SceneError, match="'left' overlaps") as err:
        parse_scene(big_tip)
    assert err.value.field == "robots[0].base"
    with pytest.raises(SceneError, match="'left' overlaps") as err:
        parse_scene(mutate(big_tip, "robots.0.q0", [0.0, 0.7, 0.0, -1.4, 0.0, 1.0, 0.0]))
    assert err.value.field == "robots[0].q0"
