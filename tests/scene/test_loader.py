"""Scene files: every good example loads; every bad case is refused naming file and field."""

from __future__ import annotations

import copy
import json

import pytest
import torch
import yaml

from robotplan import SceneError, load_scene
from robotplan.hanging.scene.parts import hang_parts
from robotplan.scene import RegionGoal, TouchGoal, parse_scene
from robotplan.scene.schema import HangGoal
from tests.conftest import TASKS

GOOD = sorted(TASKS.rglob("*.yaml"))  # tasks and variants, a hang among them
BASE = yaml.safe_load((TASKS / "box_push.yaml").read_text())
ARMS = yaml.safe_load((TASKS / "two_arm_touch.yaml").read_text())


def mutate(base: dict, path: str, value=None, delete: bool = False) -> dict:
    """Copy ``base`` and set (or delete) the entry at a dotted path like ``objects.0.pose``."""
    data = copy.deepcopy(base)
    *parents, last = path.split(".")
    node = data
    for key in parents:
        node = node[int(key)] if isinstance(node, list) else node[key]
    key = int(last) if isinstance(node, list) else last
    if delete:
        del node[key]
    else:
        node[key] = value
    return data


L_POLY = [[0, 0], [1, 1], [1, 0], [0, 1]]
# (id, scene data, field the message must name)
BAD_CASES = [
    ("unknown-top-field", mutate(BASE, "colour", "red"), "colour"),
    ("pose-goal-coverage", mutate(BASE, "goal", {"type": "pose", "object": "box",
                                                 "pose": [0.3, 0.0, 1.0], "coverage": 1.5}),
     "goal.coverage"),
    ("pose-goal-outside", mutate(BASE, "goal", {"type": "pose", "object": "box",
                                                "pose": [0.69, 0.0, 0.0]}), "goal.pose"),
    ("pose-goal-short", mutate(BASE, "goal", {"type": "pose", "object": "box",
                                              "pose": [0.3, 0.0]}), "goal.pose"),
    ("unknown-nested-field", mutate(BASE, "objects.0.colour", "red"), "objects[0].colour"),
    ("missing-pose", mutate(BASE, "objects.0.pose", delete=True), "objects[0].pose"),
    ("missing-goal", mutate(BASE, "goal", delete=True), "goal"),
    ("missing-version", mutate(BASE, "version", delete=True), "version"),
    ("version-2", mutate(BASE, "version", 2), "version"),
    ("pose-not-list", mutate(BASE, "objects.0.pose", "left"), "objects[0].pose"),
    ("pose-entry-string", mutate(BASE, "objects.0.pose", [0, "a", 0]), "objects[0].pose[1]"),
    ("pose-too-short", mutate(BASE, "objects.0.pose", [0, 0]), "objects[0].pose"),
    ("nan", mutate(BASE, "objects.0.pose", [float("nan"), 0, 0]), "objects[0].pose[0]"),
    ("inf", mutate(BASE, "pushers.0.position", [float("inf"), 0]), "pushers[0].position[0]"),
    ("negative-size", mutate(BASE, "objects.0.shape.size", [-0.2, 0.1]),
     "objects[0].shape.size[0]"),
    ("zero-radius", mutate(BASE, "pushers.0.radius", 0.0), "pushers[0].radius"),
    ("bool-radius", mutate(BASE, "pushers.0.radius", True), "pushers[0].radius"),
    ("negative-height", mutate(BASE, "objects.0.height", -0.06), "objects[0].height"),
    ("unknown-shape", mutate(BASE, "objects.0.shape", {"type": "star", "size": [1, 1]}),
     "objects[0].shape.type"),
    ("lshape-too-thick", mutate(BASE, "objects.0.shape",
                                {"type": "lshape", "size": [0.2, 0.1], "thickness": 0.1}),
     "objects[0].shape.thickness"),
    ("self-intersecting", mutate(BASE, "objects.0.shape",
                                 {"type": "polygon", "vertices": [[x * 0.1, y * 0.1]
                                                                  for x, y in L_POLY]}),
     "objects[0].shape.vertices"),
    ("duplicate-name", mutate(BASE, "pushers.0.name", "box"), "pushers[0].name"),
    ("goal-object-missing", mutate(BASE, "goal.object", "nope"), "goal.object"),
    ("goal-type", mutate(BASE, "goal.type", "stack"), "goal.type"),
    ("touch-goal-no-robot", mutate(ARMS, "goal.robot", "middle"), "goal.robot"),
    ("touch-goal-both", mutate(ARMS, "goal.pusher", "pusher"), "goal.robot"),
    ("touches-unknown", mutate(BASE, "pushers.0.touches", ["ghost"]), "pushers[0].touches[0]"),
    ("outside-workspace", mutate(BASE, "objects.0.pose", [0.66, 0.0, 0.0]), "objects[0].pose"),
    ("pusher-outside", mutate(BASE, "pushers.0.position", [-0.69, 0.0]), "pushers[0].position"),
    ("region-outside", mutate(BASE, "goal.region.pose", [0.6, 0.0, 0.0]), "goal.region.pose"),
    ("pusher-overlaps", mutate(BASE, "pushers.0.position", [-0.1, 0.02]),
     "pushers[0].position"),
    ("obstacle-overlaps", mutate(BASE, "obstacles", [{"name": "wall", "pose": [0.05, 0, 0],
                                                      "shape": {"type": "box",
                                                                "size": [0.05, 0.3]}}]),
     "obstacles[0].pose"),
    ("no-objects", mutate(BASE, "objects", []), "objects"),
    ("no-actor", mutate(BASE, "pushers", []), "pushers"),
    ("objects-not-list", mutate(BASE, "objects", {"name": "box"}), "objects"),
    ("bad-resolution", mutate(BASE, "workspace.resolution", -0.01), "workspace.resolution"),
    ("robot-model", mutate(ARMS, "robots.0.model", "ur5"), "robots[0].model"),
    ("robot-q0-length", mutate(ARMS, "robots.0.q0", [0.0, 0.1]), "robots[0].q0"),
    ("robot-q0-limits", mutate(ARMS, "robots.0.q0", [0, 3.0, 0, 0, 0, 0, 0]), "robots[0].q0"),
    ("top-level-list", [1, 2], ""),
]


@pytest.mark.parametrize("path", GOOD, ids=lambda p: p.stem)
def test_good_scenes_load(path):
    scene = load_scene(path)
    assert scene.name == path.stem
    if isinstance(scene.goal, HangGoal):  # 3D solids, not footprints
        mug, hook, _, _ = hang_parts(scene)
        pts = torch.zeros(3, 3, dtype=torch.float64)
        assert mug.sdf(pts).shape == (3,) and hook.sdf(pts).shape == (3,)
        return
    assert set(scene.bodies) >= {o.name for o in scene.objects}
    for body in scene.bodies.values():
        pts = torch.zeros(3, 2, dtype=torch.float64)
        assert body.sdf(pts).shape == (3,)


def test_body_sdf_is_at_the_scene_pose(box_scene):
    box = box_scene.bodies["box"]
    centre = torch.tensor([box.pose[:2]], dtype=torch.float64)
    assert box.sdf(centre).item() == pytest.approx(-0.06)  # half the short side
    pusher = box_scene.bodies["pusher"]
    assert pusher.sdf(torch.tensor([[-0.28, 0.10]])).item() == pytest.approx(-0.03)


@pytest.mark.parametrize(("case", "data", "field"), BAD_CASES, ids=[c[0] for c in BAD_CASES])
def test_bad_scene_is_refused_naming_the_field(tmp_path, case, data, field):
    f = tmp_path / f"{case}.yaml"
    f.write_text(yaml.safe_dump(data) if not isinstance(data, str) else data)
    with pytest.raises(SceneError) as err:
        load_scene(f)
    assert err.value.file == str(f)
    assert err.value.field == field, str(err.value)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize(("text", "field", "words"), [
    ("", "", "empty"),
    ("# only a comment\n", "", "empty"),
    ("version: 1\nobjects: [\n", "line", "invalid YAML"),
    ("version: 1\nversion: 1\n", "line 2", "duplicate key"),
    ("just a string", "", "mapping"),
])
def test_bad_yaml_text(tmp_path, text, field, words):
    f = tmp_path / "bad.yaml"
    f.write_text(text)
    with pytest.raises(SceneError) as err:
        load_scene(f)
    assert err.value.field.startswith(field) and words in str(err.value)


def test_python_tags_are_refused_and_never_executed(tmp_path):
    marker = tmp_path / "executed"
    f = tmp_path / "evil.yaml"
    f.write_text(f"!!python/object/apply:os.system ['touch {marker}']\n")
    with pytest.raises(SceneError, match="not allowed"):
        load_scene(f)
    assert not marker.exists()
    g = tmp_path / "evil2.yaml"
    g.write_text("version: 1\nname: !!python/name:os.getcwd ''\n")
    with pytest.raises(SceneError, match="not allowed"):
        load_scene(g)


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(SceneError, match="no such file"):
        load_scene(tmp_path / "nope.yaml")
    with pytest.raises(SceneError, match="directory"):
        load_scene(tmp_path)


def test_json_scene_loads_and_matches_yaml(tmp_path):
    f = tmp_path / "box.json"
    f.write_text(json.dumps(BASE, indent="\t"))
    a, b = load_scene(f), load_scene(TASKS / "box_push.yaml")
    assert a.objects == b.objects and a.goal == b.goal
    bad = tmp_path / "nan.json"
    bad.write_text(json.dumps(mutate(BASE, "objects.0.pose", [float("nan"), 0, 0])))
    with pytest.raises(SceneError) as err:
        load_scene(bad)
    assert err.value.field == "objects[0].pose[0]"


def test_defaults_and_goal_types():
    scene = load_scene(TASKS / "box_push.yaml")
    assert scene.objects[0].height == 0.06 and scene.obstacles == []
    assert isinstance(scene.goal, RegionGoal)
    touch = load_scene(TASKS / "two_arm_touch.yaml")
    assert isinstance(touch.goal, TouchGoal) and touch.goal.actor == "right"
    assert touch.bodies["right"].role == "robot"


def test_robot_tip_is_placed_by_forward_kinematics(tmp_path):
    data = mutate(ARMS, "robots.0.q0", [0.0, 0.9, 0.0, -1.3, 0.0, 0.9, 0.0])
    f = tmp_path / "q0.yaml"
    f.write_text(yaml.safe_dump(data))
    moved = load_scene(f).bodies["left"]
    home = load_scene(TASKS / "two_arm_touch.yaml").bodies["left"]
    assert moved.pose[0] != pytest.approx(home.pose[0], abs=1e-3)


def test_message_format(tmp_path):
    f = tmp_path / "s.yaml"
    f.write_text(yaml.safe_dump(mutate(BASE, "objects.0.shape.size", [-0.2, 0.1])))
    with pytest.raises(SceneError) as err:
        load_scene(f)
    assert str(err.value) == f"{f}: objects[0].shape.size[0]: must be positive, got -0.2"




def test_a_pose_goal_is_the_objects_own_footprint_at_the_pose():
    doc = mutate(BASE, "goal", {"type": "pose", "object": "box", "pose": [0.3, 0.05, 1.2]})
    scene = parse_scene(doc, "pose.yaml")
    assert scene.goal.type == "pose" and scene.goal.coverage == 0.95
    region = scene.goal_region
    assert region.shape == scene.objects[0].shape and region.pose == (0.3, 0.05, 1.2)
    assert "box to the pose (0.3, 0.05, 1.2)" in scene.summary()


# PyYAML reads YAML 1.1, where the key ``on`` is a boolean: quote it for the mutations
HANG = yaml.safe_load((TASKS / "mug_hang.yaml").read_text().replace("on: hook", '"on": hook'))


@pytest.mark.parametrize("name,data,field", [
    ("hang-on-missing", mutate(HANG, "goal.on", "shelf"), "goal.on"),
    ("hang-object", mutate(HANG, "goal.object", "cup"), "goal.object"),
    ("hang-with-pusher", mutate(HANG, "pushers", [{"name": "p", "radius": 0.03,
                                                   "position": [0.5, 0.5]}]), "pushers"),
    ("hang-handle-off-cup", mutate(HANG, "objects.0.shape.handle_span", 0.09),
     "objects[0].shape.handle_span"),
    ("hang-hook-parts", mutate(HANG, "obstacles.0.shape.angles", [0.1]),
     "obstacles[0].shape.angles"),
    ("hang-mug-at-post", mutate(HANG, "objects.0.pose", [0.03, 0.0, 0.0]), "objects[0].pose"),
    ("mug-in-push-scene", mutate(BASE, "objects.0.shape", {"type": "mug", "radius": 0.04,
                                                            "height": 0.1, "handle_height": 0.6,
                                                            "handle_reach": 0.03,
                                                            "handle_span": 0.03}),
     "objects[0].shape"),
])
def test_bad_hang_scene_is_refused_naming_the_field(tmp_path, name, data, field):
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(SceneError) as err:
        load_scene(path)
    assert err.value.field == field, str(err.value)


def test_yaml_reads_on_as_a_string():
    """YAML 1.1 reads ``on`` as a boolean; a hang goal's ``on: hook`` must stay a name."""
    scene = load_scene(TASKS / "mug_hang.yaml")
    assert scene.goal.on == "hook"
