"""Reading and validating scene files (YAML or JSON, safe loader only).

``load_scene(path)`` returns a :class:`~robotplan.scene.schema.Scene` or raises
:class:`SceneError`, whose text is one line naming the file and the field.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from robotplan.scene.files import read_data
from robotplan.scene.limits import check_counts, check_grid
from robotplan.scene.meshes import resolve_mesh_footprints, resolve_mesh_solids
from robotplan.scene.mug_hook_checks import check_hang_scene
from robotplan.scene.placement import check_placement
from robotplan.scene.reader import SchemaError, read, show
from robotplan.scene.robots import available_models, load_robot_model
from robotplan.scene.schema import SOLID_SHAPES, HangGoal, RegionGoal, Scene, TouchGoal

__all__ = ["SceneError", "load_scene", "parse_scene"]

SUPPORTED_VERSION = 1


class SceneError(Exception):
    """A scene file is unusable. ``str(err)`` is ``"<file>: <field>: <message>"``."""

    def __init__(self, file: str | Path, field: str, message: str) -> None:
        self.file, self.field, self.message = str(file), field, message
        super().__init__(f"{file}: {field}: {message}" if field else f"{file}: {message}")


def load_scene(path: str | Path) -> Scene:
    """Read, check and return the scene in ``path`` (YAML or JSON)."""
    path = Path(path)
    try:
        data = read_data(path)
    except SchemaError as err:
        raise SceneError(path, err.field, err.message) from None
    return parse_scene(data, path)


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
        raise SceneError(path, "version", f"unsupported version {show(data['version'])}; this "
                         f"robotplan reads version {SUPPORTED_VERSION}")
    try:
        check_counts(data)
        scene = read(Scene, data)
        scene = (resolve_mesh_solids(scene, Path(path)) if isinstance(scene.goal, HangGoal)
                 else resolve_mesh_footprints(scene, Path(path)))
        _check_scene(scene)
    except SchemaError as err:
        raise SceneError(path, err.field, err.message) from None
    object.__setattr__(scene, "path", Path(path))
    return scene


def _check_scene(scene: Scene) -> None:
    """Cross-field checks the types cannot express. Raises SchemaError."""
    check_grid(scene.workspace)
    if isinstance(scene.goal, HangGoal):
        check_hang_scene(scene)
        return
    for group in ("objects", "obstacles"):
        for i, body in enumerate(getattr(scene, group)):
            if isinstance(body.shape, SOLID_SHAPES):
                raise SchemaError(f"{group}[{i}].shape", f"a {body.shape.type} belongs to a "
                                  "hang scene (goal type hang); pushing scenes take footprints")
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
                                  f"duplicate name {show(item.name)} (also {where[item.name]})")
            where[item.name] = path
    object_names = [o.name for o in scene.objects]
    for i, p in enumerate(scene.pushers):
        for j, target in enumerate(p.touches or []):
            if target not in object_names:
                raise SchemaError(f"pushers[{i}].touches[{j}]",
                                  f"{show(target)} is not an object (objects: "
                                  f"{show(object_names)})")
    _check_goal(scene, object_names)
    _check_robots(scene)
    check_placement(scene, where)


def _check_goal(scene: Scene, object_names: list[str]) -> None:
    goal = scene.goal
    if goal.object not in object_names:
        raise SchemaError("goal.object", f"{show(goal.object)} is not an object (objects: "
                          f"{show(object_names)})")
    if isinstance(goal, TouchGoal):
        if goal.robot is not None and goal.robot not in [r.name for r in scene.robots]:
            raise SchemaError("goal.robot", f"{show(goal.robot)} is not a robot of this "
                              f"scene (robots: {show([r.name for r in scene.robots])})")
        if goal.pusher is not None and goal.pusher not in [p.name for p in scene.pushers]:
            raise SchemaError("goal.pusher", f"{show(goal.pusher)} is not a pusher of this "
                              f"scene (pushers: {show([p.name for p in scene.pushers])})")
    elif isinstance(goal, RegionGoal):
        _check_region_area(scene, goal)


def _check_region_area(scene: Scene, goal: RegionGoal) -> None:
    """The object must fit in the region: full coverage of a smaller region is impossible."""
    (obj,) = [o for o in scene.objects if o.name == goal.object]
    region_area, object_area = goal.region.shape.area, obj.shape.area
    if region_area < object_area * (1 - 1e-9):  # equal areas fit when the shapes match
        raise SchemaError("goal.region", f"the region's area ({region_area * 1e4:.4g} cm²) is "
                          f"smaller than the footprint of {show(goal.object)} ("
                          f"{object_area * 1e4:.4g} cm²): the object can never lie entirely "
                          "inside it")


def _check_robots(scene: Scene) -> None:
    for i, r in enumerate(scene.robots):
        if r.model not in available_models():
            raise SchemaError(f"robots[{i}].model", f"unknown robot model {show(r.model)}; "
                              f"available: {available_models()}")
        model = load_robot_model(r.model)
        if r.q0 is not None:
            if len(r.q0) != model.dof:
                raise SchemaError(f"robots[{i}].q0", f"must have {model.dof} joint angles for "
                                  f"{r.model}, got {len(r.q0)}")
            if not model.within_limits(r.q0):
                raise SchemaError(f"robots[{i}].q0", f"outside the joint limits of {r.model}")
