"""The scene file format (docs/design.md#scene-files) as typed dataclasses: these classes *are*
the schema.

Units are metres and radians in the table frame W (z up, table top at z = 0). A planar pose
``X_WB = (x, y, yaw)`` places a shape frame B on the table.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Literal

from robotplan.scene.meshes import MeshShape
from robotplan.sdf import Box, Circle, LShape, Polygon, Workspace
from robotplan.sdf.mug_hook import Hook, Mug

if TYPE_CHECKING:
    from robotplan.scene.bodies import Body

__all__ = [
    "DEFAULT_HEIGHT",
    "SOLID_SHAPES",
    "BodySpec",
    "HangGoal",
    "HookShape",
    "MeshShape",
    "MugShape",
    "PoseGoal",
    "PusherSpec",
    "Region",
    "RegionGoal",
    "RobotSpec",
    "Scene",
    "ShapeSpec",
    "TouchGoal",
]

POSITIVE = {"positive": True}
DEFAULT_HEIGHT = 0.06


@dataclass(frozen=True)
class MugShape:
    """A procedural mug (:class:`robotplan.sdf.mug_hook.Mug`): its frame at the centre
    of the bottom, the handle towards +x. ``handle_height`` is a fraction of ``height``."""

    radius: float = field(metadata=POSITIVE)
    height: float = field(metadata=POSITIVE)
    handle_height: float = field(metadata=POSITIVE)
    handle_reach: float = field(metadata=POSITIVE)
    handle_span: float = field(metadata=POSITIVE)
    wall: float = field(default=0.006, metadata=POSITIVE)
    handle_radius: float = field(default=0.005, metadata=POSITIVE)
    type: Literal["mug"] = "mug"

    def check(self) -> tuple[str, str] | None:
        if self.wall >= self.radius:
            return "wall", "must be thinner than the radius"
        zc = self.handle_height * self.height
        if zc - self.handle_span - self.handle_radius < self.wall - 1e-12 or \
                zc + self.handle_span + self.handle_radius > self.height + 1e-12:
            return "handle_span", "the handle must stay on the cup's wall, between the bottom " \
                "and the rim"
        return None

    def solid(self) -> Mug:
        return Mug(self.radius, self.height, self.handle_height, self.handle_reach,
                   self.handle_span, self.wall, self.handle_radius)


@dataclass(frozen=True)
class HookShape:
    """A hook (:class:`robotplan.sdf.mug_hook.Hook`): a post on the table and an arm of one
    to three straight parts (lengths, and angles in rad above the horizontal) towards +x."""

    post_height: float = field(metadata=POSITIVE)
    lengths: tuple[float, ...]
    angles: tuple[float, ...]
    post_radius: float = field(default=0.012, metadata=POSITIVE)
    rod_radius: float = field(default=0.005, metadata=POSITIVE)
    type: Literal["hook"] = "hook"

    def check(self) -> tuple[str, str] | None:
        if not 1 <= len(self.lengths) <= 3:
            return "lengths", "an arm has one to three parts"
        if len(self.angles) != len(self.lengths):
            return "angles", "one angle per part, as many as lengths"
        if min(self.lengths) <= 0:
            return "lengths", "must be positive"
        return None

    def solid(self) -> Hook:
        return Hook(self.post_height, tuple(self.lengths), tuple(self.angles),
                    self.post_radius, self.rod_radius)


ShapeSpec = Box | Circle | LShape | Polygon | MeshShape | MugShape | HookShape
SOLID_SHAPES = (MugShape, HookShape)  # 3D: only in hang scenes


@dataclass(frozen=True)
class BodySpec:
    """A movable object or a fixed obstacle: a footprint extruded to ``height``."""

    name: str
    shape: ShapeSpec
    pose: tuple[float, float, float]
    height: float = field(default=DEFAULT_HEIGHT, metadata=POSITIVE)


@dataclass(frozen=True)
class PusherSpec:
    """A free spherical pusher, centre at ``z = radius``. ``touches``: objects it may push
    (``None`` means all)."""

    name: str
    radius: float = field(metadata=POSITIVE)
    position: tuple[float, float]
    touches: list[str] | None = None


@dataclass(frozen=True)
class RobotSpec:
    """An arm from ``robots/<model>/`` with a spherical tip at its flange.

    ``base = (x, y, z, yaw)`` of the robot base in W; ``q0`` the start joint angles
    (default: the model's home pose).
    """

    name: str
    model: str
    base: tuple[float, float, float, float]
    tip_radius: float = field(metadata=POSITIVE)
    q0: tuple[float, ...] | None = None


@dataclass(frozen=True)
class Region:
    """A goal region: a footprint at a fixed pose."""

    shape: ShapeSpec
    pose: tuple[float, float, float]


@dataclass(frozen=True)
class RegionGoal:
    """``object`` must end entirely inside ``region`` (H_g, eq. 8)."""

    object: str
    region: Region
    type: Literal["region"] = "region"


@dataclass(frozen=True)
class PoseGoal:
    """``object`` must end at ``pose`` (x, y, yaw): success is coverage of its own footprint
    at that pose of at least ``coverage`` (Push-T's measure, 0.95). Planned as a region goal
    whose region is that footprint (H_g, eq. 8)."""

    object: str
    pose: tuple[float, float, float]
    coverage: float = 0.95
    type: Literal["pose"] = "pose"

    def check(self) -> tuple[str, str] | None:
        if not 0.0 < self.coverage <= 1.0:
            return "coverage", "must be in (0, 1]"
        return None


@dataclass(frozen=True)
class TouchGoal:
    """The tip of ``robot`` (or the pusher ``pusher``) must end in contact with ``object``."""

    object: str
    robot: str | None = None
    pusher: str | None = None
    type: Literal["touch"] = "touch"

    @property
    def actor(self) -> str:
        return self.robot if self.robot is not None else str(self.pusher)

    def check(self) -> tuple[str, str] | None:
        if (self.robot is None) == (self.pusher is None):
            return "robot", "a touch goal names exactly one of 'robot' or 'pusher'"
        return None


@dataclass(frozen=True)
class HangGoal:
    """The mug ``object`` must hang on the hook ``on`` (an obstacle): found by H_hang and
    H_coll (paper §7.1), checked by dropping it in the simulator."""

    object: str
    on: str
    type: Literal["hang"] = "hang"


@dataclass(frozen=True)
class Scene:
    """A whole scene file. ``version`` must be 1."""

    version: int
    objects: list[BodySpec]
    goal: RegionGoal | PoseGoal | TouchGoal | HangGoal
    name: str = "scene"
    workspace: Workspace = field(default_factory=Workspace)
    obstacles: list[BodySpec] = field(default_factory=list)
    pushers: list[PusherSpec] = field(default_factory=list)
    robots: list[RobotSpec] = field(default_factory=list)
    path: Path | None = field(default=None, compare=False, init=False)

    @cached_property
    def bodies(self) -> dict[str, Body]:
        """Every object, obstacle, pusher and robot tip by name, at its start pose."""
        from robotplan.scene.bodies import scene_bodies

        return scene_bodies(self)

    @property
    def goal_region(self) -> Body | None:
        """The goal region as a body (for H_g and coverage), or None for a touch goal."""
        from robotplan.scene.bodies import region_body

        if isinstance(self.goal, PoseGoal):
            return region_body(self.goal, self.objects)
        return region_body(self.goal) if isinstance(self.goal, RegionGoal) else None

    def summary(self) -> str:
        def count(n: int, word: str) -> str:
            return f"{n} {word}" + ("" if n == 1 else "s")

        g = self.goal
        if isinstance(g, HangGoal):
            return f"{self.name}: hang {g.object} on {g.on}"
        goal = (f"{g.object} into a region" if isinstance(g, RegionGoal)
                else f"{g.object} to the pose ({', '.join(f'{v:g}' for v in g.pose)})"
                if isinstance(g, PoseGoal) else f"{g.actor} touches {g.object}")
        return (f"{self.name}: {count(len(self.objects), 'object')}, "
                f"{count(len(self.obstacles), 'obstacle')}, {count(len(self.pushers), 'pusher')}, "
                f"{count(len(self.robots), 'robot')}; goal: {goal}")

    def with_state(self, poses: dict[str, tuple[float, float, float]] | None = None,
                   joints: dict[str, tuple[float, ...]] | None = None) -> Scene:
        """This scene with objects and obstacles at observed ``poses`` (name → x, y, yaw),
        free pushers at observed positions (name → x, y) and arms at observed ``joints``
        (name → angles): what a planner re-planning from a perceived state gets."""
        poses, joints = dict(poses or {}), dict(joints or {})
        known = ({b.name for b in (*self.objects, *self.obstacles, *self.pushers)}
                 | {r.name for r in self.robots})
        unknown = (set(poses) | set(joints)) - known
        if unknown:
            raise KeyError(f"no body named {sorted(unknown)} in scene {self.name!r}")

        def posed(specs: list[BodySpec]) -> list[BodySpec]:
            return [replace(b, pose=tuple(map(float, poses[b.name]))) if b.name in poses
                    else b for b in specs]

        moved = replace(self, objects=posed(self.objects), obstacles=posed(self.obstacles),
                        pushers=[replace(p, position=tuple(map(float, poses[p.name][:2])))
                                 if p.name in poses else p for p in self.pushers],
                        robots=[replace(r, q0=tuple(map(float, joints[r.name])))
                                if r.name in joints else r for r in self.robots])
        object.__setattr__(moved, "path", self.path)
        return moved
