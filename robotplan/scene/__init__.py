"""Scene files: the schema (dataclasses), loading and validation, and the posed bodies."""

from robotplan.scene.bodies import Body
from robotplan.scene.loader import SceneError, load_scene, parse_scene
from robotplan.scene.schema import (
    BodySpec,
    PoseGoal,
    PusherSpec,
    Region,
    RegionGoal,
    RobotSpec,
    Scene,
    TouchGoal,
)

__all__ = [
    "Body",
    "BodySpec",
    "PoseGoal",
    "PusherSpec",
    "Region",
    "RegionGoal",
    "RobotSpec",
    "Scene",
    "SceneError",
    "TouchGoal",
    "load_scene",
    "parse_scene",
]
