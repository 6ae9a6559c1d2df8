"""Reading and validating scene files (YAML or JSON, safe loader only).

``load_scene(path)`` returns a :class:`~robotplan.scene.schema.Scene` or raises
:class:`SceneError`, whose text is one line naming the file and the field.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from robotplan.geometry.polygons import intersection_area
from robotplan.scene.reader import SchemaError, read
from robotplan.scene.schema import RegionGoal, Scene, TouchGoal

__all__ = ["SceneError", "load_scene", "parse_scene"]

SUPPORTED_VERSION = 1
_OVERLAP_AREA = 1e-9  # m²: footprints sharing less than this merely touch
_TOL = 1e-9


class SceneError(Exception):
    """A scene file is unusable. ``str(err)`` is ``"<file>: <field>: <message>"``."""

    def __init__(self, file: str | Path, field: str, message: str) -> None:
        self.file, self.field, self.message = str(file), field, message
        super().__init__(f"{file}: {field}: {message}" if field else f"{file}: {message}")


class _StrictSafeLoader(yaml.SafeLoader):
    """The safe loader, refusing duplicate keys instead of keeping the last silently."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        seen: set[Any] = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if key in seen:
                mark = key_node.start_mark
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r} (line {mark.line + 1})", mark)
            seen.add(key)
        return super().construct_mapping(node, deep=deep)


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict:
    out: dict[str, Any] = {}
    for k, v in pairs:
        if k in out:
            raise ValueError(f"duplicate key {k!r}")
        out[k] = v
    return out


def _parse_text(text: str, path: Path) -> Any:
    if path.suffix.lower() == ".json":
        try:
            return json.loads(text, object_pairs_hook=_no_duplicates)
        except (json.JSONDecodeError, ValueError) as err:
            raise SceneError(path, "", f"invalid JSON: {err}") from None
    try:
        return yaml.load(text, Loader=_StrictSafeLoader)
    except yaml.constructor.ConstructorError as err:
        mark = err.problem_mark
        where = f"line {mark.line + 1}" if mark else "YAML"
        problem = err.problem or str(err)
        if "could not determine a constructor" in problem:
            problem = (f"YAML tag {problem.split('tag')[-1].strip()} is not allowed: "
                       "scene files hold plain data only")
        raise SceneError(path, where, problem) from None
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark else "YAML"
        problem = getattr(err, "problem", None) or str(err)
        raise SceneError(path, where, f"invalid YAML: {problem}") from None


def load_scene(path: str | Path) -> Scene:
    """Read, check and return the scene in ``path`` (YAML or JSON)."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise SceneError(path, "", "no such file") from None
    except IsADirectoryError:
        raise SceneError(path, "", "is a directory, not a scene file") from None
    except OSError as err:
        raise SceneError(path, "", f"cannot read: {err.strerror}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise SceneError(path, "", "not a UTF-8 text file") from None
    return parse_scene(_parse_text(text, path), path)


def parse_scene(data: Any, path: str | Path = "<scene>") -> Scene:
    """Check already-parsed scene data (a dict) and build the :class:`Scene`."""
    if data is None:
        raise SceneError(path, "", "empty scene file")
    if not isinstance(data, dict):
        raise SceneError(path, "", f"must be a mapping of fields, got {type(data).__name__}")
    if "version" not in data:
        raise SceneError(path, "version", f"missing required field (use version: "
                         f"{SUPPORTED_VERSION})")
    if data["version"] != SUPPORTED_VERSION or isinstance(data["version"], bool):
        raise SceneError(path, "version", f"unsupported version {data['version']!r}; this "
                         f"robotplan reads version {SUPPORTED_VERSION}")
    try:
        scene = read(Scene, data)
        _check_scene(scene)
    except SchemaError as err:
        raise SceneError(path, err.field, err.message) from None
    object.__setattr__(scene, "path", Path(path))
    return scene


def _check_scene(scene: Scene) -> None:
    """Cross-field checks the types cannot express. Raises SchemaError."""
    if not scene.objects:
        raise SchemaError("objects", "at least one movable object is required")
    if not scene.pushers and not scene.robots:
        raise SchemaError("pushers", "every scene needs at least one pusher or robot")
    where: dict[str, str] = {}
    groups = (("objects", scene.objects), ("obstacles", scene.obstacles),
              ("pushers", scene.pushers), ("robots", scene.robots))
    for group, items in groups:
        for i, item in enumerate(items):
            path = f"{group}[{i}]"
            if item.name in where:
                raise SchemaError(f"{path}.name",
                                  f"duplicate name {item.name!r} (also {where[item.name]})")
            where[item.name] = path
    object_names = [o.name for o in scene.objects]
    for i, p in enumerate(scene.pushers):
        for j, target in enumerate(p.touches or []):
            if target not in object_names:
                raise SchemaError(f"pushers[{i}].touches[{j}]",
                                  f"{target!r} is not an object (objects: {object_names})")
    _check_goal(scene, object_names)
    _check_robots(scene)
    _check_placement(scene, where)


def _check_goal(scene: Scene, object_names: list[str]) -> None:
    goal = scene.goal
    if goal.object not in object_names:
        raise SchemaError("goal.object",
                          f"{goal.object!r} is not an object (objects: {object_names})")
    if isinstance(goal, TouchGoal):
        if goal.robot is not None and goal.robot not in [r.name for r in scene.robots]:
            raise SchemaError("goal.robot", f"{goal.robot!r} is not a robot of this scene "
                              f"(robots: {[r.name for r in scene.robots]})")
        if goal.pusher is not None and goal.pusher not in [p.name for p in scene.pushers]:
            raise SchemaError("goal.pusher", f"{goal.pusher!r} is not a pusher of this scene "
                              f"(pushers: {[p.name for p in scene.pushers]})")


def _check_robots(scene: Scene) -> None:
    from robotplan.scene.robots import available_models, load_robot_model

    for i, r in enumerate(scene.robots):
        if r.model not in available_models():
            raise SchemaError(f"robots[{i}].model", f"unknown robot model {r.model!r}; "
                              f"available: {available_models()}")
        model = load_robot_model(r.model)
        if r.q0 is not None:
            if len(r.q0) != model.dof:
                raise SchemaError(f"robots[{i}].q0", f"must have {model.dof} joint angles for "
                                  f"{r.model}, got {len(r.q0)}")
            if not model.within_limits(r.q0):
                raise SchemaError(f"robots[{i}].q0", f"outside the joint limits of {r.model}")


def _check_placement(scene: Scene, where: dict[str, str]) -> None:
    x0, x1, y0, y1 = scene.workspace.bounds
    bounds = f"x in [{x0:g}, {x1:g}], y in [{y0:g}, {y1:g}]"

    def inside(outline: np.ndarray) -> bool:
        return bool(outline[:, 0].min() >= x0 - _TOL and outline[:, 0].max() <= x1 + _TOL
                    and outline[:, 1].min() >= y0 - _TOL and outline[:, 1].max() <= y1 + _TOL)

    table_bodies = [b for b in scene.bodies.values() if b.role != "robot"]
    outlines = {b.name: b.outline_world() for b in table_bodies}
    for b in table_bodies:
        if not inside(outlines[b.name]):
            field = "position" if b.role == "pusher" else "pose"
            raise SchemaError(f"{where[b.name]}.{field}",
                              f"{b.name!r} lies (partly) outside the workspace ({bounds})")
    if isinstance(scene.goal, RegionGoal) and not inside(scene.goal_region.outline_world()):
        raise SchemaError("goal.region.pose", f"the goal region lies (partly) outside the "
                          f"workspace ({bounds})")
    bodies = list(scene.bodies.values())
    for i, a in enumerate(bodies):
        for b in bodies[i + 1:]:
            if a.top <= b.bottom or b.top <= a.bottom:
                continue  # one passes above the other
            oa = outlines.get(a.name, a.outline_world())
            ob = outlines.get(b.name, b.outline_world())
            area = intersection_area(oa, ob)
            if area > _OVERLAP_AREA:
                raise SchemaError(f"{where[b.name]}.{'position' if b.role == 'pusher' else 'pose'}",
                                  f"{b.name!r} overlaps {a.name!r} at the start "
                                  f"({area * 1e4:.2f} cm²)")
