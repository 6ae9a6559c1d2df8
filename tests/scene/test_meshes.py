"""Mesh shapes in scene files: read beside the scene, turned into footprints the 2D
planner uses as it is, and every unusable mesh refused in one line with exit status 2."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
import trimesh
import yaml

from robotplan import SceneError, load_scene
from robotplan.sdf import Polygon
from robotplan.sdf.mesh_footprint import MeshFootprint
from tests.cli.test_app import call, run
from tests.conftest import TASKS


def scene_doc(shape: dict, region: dict | None = None) -> dict:
    return {"version": 1, "name": "mesh_push",
            "objects": [{"name": "bracket", "shape": shape, "pose": [0.0, 0.0, 0.3]}],
            "pushers": [{"name": "pusher", "radius": 0.03, "position": [-0.25, -0.2]}],
            "goal": {"type": "region", "object": "bracket",
                     "region": region or {"shape": {"type": "box", "size": [0.4, 0.4]},
                                          "pose": [0.3, 0.2, 0.0]}}}


@pytest.fixture
def folder(tmp_path):
    (tmp_path / "meshes").mkdir()
    shutil.copyfile(TASKS / "meshes" / "l_bracket.stl", tmp_path / "meshes" / "l.stl")
    return tmp_path


def write_scene(folder, doc: dict, name: str = "scene.yaml"):
    path = folder / name
    path.write_text(yaml.safe_dump(doc))
    return path


def test_a_mesh_object_is_its_footprint_centred_on_its_centroid(folder):
    scene = load_scene(write_scene(folder, scene_doc(
        {"type": "mesh", "file": "meshes/l.stl", "scale": 0.001})))
    body = scene.objects[0]
    assert isinstance(body.shape, MeshFootprint) and isinstance(body.shape, Polygon)
    assert body.height == pytest.approx(0.04)
    outline = body.shape.outline()
    assert np.ptp(outline, axis=0) == pytest.approx([0.2, 0.15], abs=1e-6)
    assert body.shape.area == pytest.approx(0.2 * 0.06 + 0.06 * 0.09, rel=1e-5)
    # B is the centroid: the outline's first moment about it vanishes
    from robotplan.sdf.footprint import footprint_centroid

    assert np.abs(footprint_centroid(body.shape)).max() < 1e-6
    assert body.shape.mesh_file == str((folder / "meshes" / "l.stl").resolve())
    assert scene.bodies["bracket"].top == pytest.approx(0.04)


def test_a_mesh_may_be_a_goal_region_too(folder):
    region = {"shape": {"type": "mesh", "file": "meshes/l.stl", "scale": 0.0015},
              "pose": [0.3, 0.2, 0.3]}
    scene = load_scene(write_scene(folder, scene_doc(
        {"type": "mesh", "file": "meshes/l.stl", "scale": 0.001}, region)))
    assert scene.goal_region.area == pytest.approx(2.25 * scene.objects[0].shape.area,
                                                   rel=1e-4)


BAD = [
    ({"file": "../outside.stl"}, "objects[0].shape.file", "outside the scene's folder"),
    ({"file": "https://example.org/l.stl"}, "objects[0].shape.file", "not a URL"),
    ({"file": "meshes/none.stl"}, "objects[0].shape.file", "no such file"),
    ({"file": "meshes/open.stl"}, "objects[0].shape.file", "not watertight"),
    ({"file": "meshes/empty.obj"}, "objects[0].shape.file", "no triangles"),
    ({"file": "meshes/flat.stl"}, "objects[0].shape.file", "flat"),
    ({"file": "meshes/l.stl", "scale": 1.0}, "objects[0].shape.file", "larger than"),
    ({"file": "meshes/l.stl", "scale": -1.0}, "objects[0].shape.scale", "positive"),
    ({"file": "meshes/dense.stl"}, "objects[0].shape.file", "too many"),
    ({"file": "meshes/round.stl", "tolerance": 0.0000001}, "objects[0].shape.tolerance",
     "raise it"),
    ({"file": "meshes/l.stl", "tolerance": 0.05}, "objects[0].shape.tolerance", "at most"),
]


def make_bad_meshes(folder) -> None:
    box = trimesh.creation.box([0.1, 0.1, 0.05])
    trimesh.Trimesh(box.vertices, box.faces[:-2]).export(str(folder / "meshes" / "open.stl"))
    (folder / "meshes" / "empty.obj").write_text("v 0 0 0\n")
    trimesh.creation.cylinder(0.08, 0.03, sections=512).export(str(folder / "meshes" /
                                                                    "round.stl"))
    trimesh.creation.box([0.1, 0.1, 0.0005]).export(str(folder / "meshes" / "flat.stl"))
    trimesh.creation.icosphere(7, 0.05).export(str(folder / "meshes" / "dense.stl"))
    (folder.parent / "outside.stl").write_bytes((folder / "meshes" / "l.stl").read_bytes())


def test_unusable_meshes_are_refused_naming_the_file_and_field(folder):
    make_bad_meshes(folder)
    for shape, field, words in BAD:
        path = write_scene(folder, scene_doc({"type": "mesh", **shape}))
        with pytest.raises(SceneError) as err:
            load_scene(path)
        assert err.value.file == str(path) and err.value.field == field, str(err.value)
        assert "\n" not in str(err.value) and (words is None or words in str(err.value))


def test_check_refuses_a_bad_mesh_with_one_line_and_exit_2(folder, capsys):
    make_bad_meshes(folder)
    paths = [write_scene(folder, scene_doc({"type": "mesh", **shape}), f"bad{i}.yaml")
             for i, (shape, _, _) in enumerate(BAD)]
    first = run("check", str(paths[0]))
    results = [first] + [call(capsys, "check", str(p)) for p in paths[1:]]
    for res, path, (_, field, _) in zip(results, paths, BAD, strict=True):
        assert res.returncode == 2, res
        lines = res.stderr.strip().splitlines()
        assert len(lines) == 1 and str(path) in lines[0] and field in lines[0], res.stderr
        assert "Traceback" not in res.stderr


def test_a_hang_scene_takes_a_mesh_mug_and_hook(tmp_path):
    """Their solids resolved (the handle's opening, the arm found); a mug mesh without a
    handle is refused naming the field."""
    from robotplan.scene.meshes import MeshSolid

    (tmp_path / "meshes").mkdir()
    for name in ("mug_square_handle.stl", "hook_square_rod.stl"):
        shutil.copyfile(TASKS / "meshes" / "hang" / name, tmp_path / "meshes" / name)
    doc = {"version": 1, "name": "mesh_hang",
           "objects": [{"name": "mug", "pose": [0.3, -0.2, 0.0],
                        "shape": {"type": "mesh", "file": "meshes/mug_square_handle.stl"}}],
           "obstacles": [{"name": "hook", "pose": [0.0, 0.0, 0.0],
                          "shape": {"type": "mesh", "file": "meshes/hook_square_rod.stl"}}],
           "goal": {"type": "hang", "object": "mug", "on": "hook"}}
    scene = load_scene(write_scene(tmp_path, doc))
    mug, hook = scene.objects[0].shape, scene.obstacles[0].shape
    assert isinstance(mug, MeshSolid) and mug.role == "mug" and hook.role == "hook"
    assert len(hook.solid().arm_points()) == 3 and mug.solid().opening()[2] > 0.008
    profile = np.array([[0, 0], [0.04, 0], [0.04, 0.1], [0.034, 0.1], [0.034, 0.006],
                        [0, 0.006]])
    trimesh.creation.revolve(profile, sections=32).export(str(tmp_path / "meshes" / "cup.obj"))
    doc["objects"][0]["shape"]["file"] = "meshes/cup.obj"
    with pytest.raises(SceneError) as err:
        load_scene(write_scene(tmp_path, doc, "cup.yaml"))
    assert err.value.field == "objects[0].shape.file" and "no opening" in str(err.value)
    doc["objects"][0]["pose"] = [0.02, 0.0, 0.0]
    doc["objects"][0]["shape"]["file"] = "meshes/mug_square_handle.stl"
    with pytest.raises(SceneError, match="post"):
        load_scene(write_scene(tmp_path, doc, "close.yaml"))
