"""The task a scene asks for, classified once (docs/design.md#tasks).

Loading a scene yields a :class:`PushTask` or a :class:`HangTask`: what the planner must do,
named. Every layer below the facade reads the kind of a scene from its task (``task.arms``,
``task.goal``, ``task.chained``, ``task.classes``) and its bodies from ``task.scene``; only
this module and the scene file's own checks look at the raw fields to tell kinds apart.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import ClassVar, Literal

from robotplan.scene.bodies import Body
from robotplan.scene.loader import load_scene
from robotplan.scene.schema import HangGoal, PusherSpec, Scene, TouchGoal

__all__ = ["PUSH_CLASSES", "HangTask", "PushTask", "Task", "TaskPlan", "UnsupportedScene",
           "family_of", "load_task", "make_task"]

PUSH_CLASSES = ("arms", "chains", "obstacles", "pose")
"""The classes a push task may belong to (:attr:`PushTask.classes`), each of which may have
its own default learned dynamics (``skeletons/dynamics.yaml``), program settings
(``skeletons/settings.yaml``) and closed-loop settings (``skeletons/loop.yaml``)."""


class UnsupportedScene(ValueError):
    """The scene is valid but needs a planner feature that is not built yet."""


@dataclass(frozen=True)
class PushTask:
    """Push ``obj`` with the ``actors`` until the goal holds.

    ``arms``: the actors are robot arms (their tips push), else one free pusher.
    ``goal``: ``region`` (the goal's object inside a region, H_g eq. 8), ``pose`` (at a pose,
    planned as the region of its own footprint there) or ``touch`` (``touch_actor``'s tip
    ends on the object). ``chained``: the goal's object, pushed by ``obj``, which the pusher
    may touch (paper Fig. 9); None when the actors touch the goal's object themselves.
    """

    scene: Scene
    obj: str
    actors: tuple[str, ...]
    arms: bool
    goal: Literal["region", "pose", "touch"]
    chained: str | None = None
    touch_actor: str | None = None
    family: ClassVar[str] = "push"

    @property
    def goal_object(self) -> str:
        """The object the goal names (``chained`` in a chain, else ``obj``)."""
        return self.chained or self.obj

    @property
    def obstacles(self) -> bool:
        return bool(self.scene.obstacles)

    @property
    def pusher(self) -> PusherSpec | None:
        """The free pusher (None for arms)."""
        return None if self.arms else self.scene.pushers[0]

    @property
    def region(self) -> Body | None:
        """The goal region as a body (a pose goal's footprint at its pose; None for touch)."""
        return self.scene.goal_region

    @property
    def classes(self) -> tuple[str, ...]:
        """The classes of :data:`PUSH_CLASSES` the task belongs to, in that order."""
        return tuple(name for name, member in (
            ("arms", self.arms), ("chains", self.chained is not None),
            ("obstacles", self.obstacles), ("pose", self.goal == "pose")) if member)

    @property
    def single(self) -> bool:
        """One free pusher and one object (no arms, no chain)."""
        return not self.arms and self.chained is None

    def at(self, scene: Scene) -> PushTask:
        """The same task in ``scene``: this scene with its bodies at other poses
        (:meth:`Scene.with_state`)."""
        return replace(self, scene=scene)

    def describe(self) -> str:
        actor = "arms " + ", ".join(self.actors) if self.arms else f"pusher {self.actors[0]}"
        via = f" (it pushes {self.chained})" if self.chained else ""
        return f"push {self.obj}{via} with {actor}; goal: {self.goal}"


@dataclass(frozen=True)
class HangTask:
    """Hang the mug ``mug`` on the hook ``hook`` (H_hang and H_coll, paper §7.1)."""

    scene: Scene
    mug: str
    hook: str
    family: ClassVar[str] = "hang"

    def at(self, scene: Scene) -> HangTask:
        return replace(self, scene=scene)

    def describe(self) -> str:
        return f"hang {self.mug} on {self.hook}"


Task = PushTask | HangTask


@dataclass
class TaskPlan:
    """What a family's planner returns: its task first (``scene`` is the task's)."""

    task: Task

    @property
    def scene(self) -> Scene:
        return self.task.scene


def _chain(scene: Scene) -> tuple[str, str] | None:
    """``(obj, target)`` when the only free pusher may not touch the goal's object but may
    touch the one other object: it pushes ``obj``, which pushes ``target``."""
    if scene.robots or len(scene.pushers) != 1 or len(scene.objects) != 2:
        return None
    goal_obj = scene.goal.object
    allowed = scene.pushers[0].touches
    others = [o.name for o in scene.objects if o.name != goal_obj]
    if allowed is None or goal_obj in allowed or others[0] not in allowed:
        return None
    return others[0], goal_obj


def family_of(scene: Scene) -> str:
    """The task family a scene asks for (``push`` or ``hang``), without the checks of
    :func:`make_task`: what commands that draw or check any valid scene go by."""
    return "hang" if isinstance(scene.goal, HangGoal) else "push"


def make_task(scene: Scene) -> Task:
    """The task of a valid scene; :class:`UnsupportedScene` (naming the field) for a scene
    the planner does not handle yet."""
    goal = scene.goal
    if family_of(scene) == "hang":
        return HangTask(scene, goal.object, goal.on)
    touch = goal.actor if isinstance(goal, TouchGoal) else None
    chain = _chain(scene)
    if chain is not None and touch is None:
        return PushTask(scene, chain[0], (scene.pushers[0].name,), False, goal.type,
                        chained=chain[1])
    if len(scene.objects) != 1:
        raise UnsupportedScene("objects: more than one movable object is planned only when "
                               "the pusher touches one of two and it pushes the goal's object "
                               "(pushers[0].touches)")
    if scene.robots and scene.pushers:
        raise UnsupportedScene("pushers: free pushers beside robot arms are not planned yet")
    if not scene.robots and len(scene.pushers) != 1:
        raise UnsupportedScene("pushers: only one free pusher is planned yet")
    if touch is not None and not scene.robots:
        raise UnsupportedScene("goal: touch goals are planned for robot arms only")
    actors = tuple(r.name for r in scene.robots) or (scene.pushers[0].name,)
    return PushTask(scene, scene.objects[0].name, actors, bool(scene.robots), goal.type,
                    touch_actor=touch)


def load_task(path: str | Path) -> Task:
    """Read a scene file (:func:`~robotplan.scene.loader.load_scene`) and classify it."""
    return make_task(load_scene(path))
