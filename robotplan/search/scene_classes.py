"""The classes of a scene (arms, chains, obstacles, pose goals), each of which may have its
own learned dynamics by default (``skeletons/dynamics.yaml``), program settings
(``skeletons/settings.yaml``) and closed-loop settings (``skeletons/loop.yaml``)."""

from __future__ import annotations

from functools import cache
from pathlib import Path

import yaml

from robotplan.base.resources import DYNAMICS_FOLDERS, skeletons_dir
from robotplan.scene import Scene

__all__ = ["DYNAMICS_CLASSES", "chain_target", "default_dynamics", "load_default_dynamics",
           "scene_classes"]


def chain_target(scene: Scene) -> tuple[str, str] | None:
    """``(obj, target)`` when the only free pusher may not touch the goal's object but may
    touch the one other object: it pushes ``obj``, which pushes ``target`` (paper Fig. 9)."""
    if scene.robots or len(scene.pushers) != 1 or len(scene.objects) != 2:
        return None
    goal_obj = getattr(scene.goal, "object", None)
    allowed = scene.pushers[0].touches
    others = [o.name for o in scene.objects if o.name != goal_obj]
    if allowed is None or goal_obj in allowed or others[0] not in allowed:
        return None
    return others[0], goal_obj


DYNAMICS_CLASSES = ("arms", "chains", "obstacles", "pose")
"""The classes a scene may belong to (:func:`scene_classes`), each of which may have its own
default learned dynamics (``skeletons/dynamics.yaml``), program settings
(``skeletons/settings.yaml``: ``arms``, ``pose``) and closed-loop settings
(``skeletons/loop.yaml``: ``arms``, ``chains``, ``pose``)."""


def scene_classes(scene: Scene) -> tuple[str, ...]:
    """The classes of ``DYNAMICS_CLASSES`` a scene belongs to, in that order (chains: the
    pusher may touch only the object that pushes the goal's object)."""
    return tuple(name for name, member in (
        ("arms", bool(scene.robots)), ("chains", chain_target(scene) is not None),
        ("obstacles", bool(scene.obstacles)), ("pose", scene.goal.type == "pose")) if member)


@cache
def load_default_dynamics(path: Path | None = None) -> dict[str, str]:
    """``skeletons/dynamics.yaml``: scene class (or ``default``) → dynamics kind."""
    path = path or skeletons_dir() / "dynamics.yaml"
    data = yaml.safe_load(path.read_text()) or {}
    if not isinstance(data, dict) or "default" not in data:
        raise ValueError(f"{path}: must map scene classes and 'default' to dynamics kinds")
    for name, kind in data.items():
        if name != "default" and name not in DYNAMICS_CLASSES:
            raise ValueError(f"{path}: {name}: not a scene class; one of {DYNAMICS_CLASSES}")
        if kind not in DYNAMICS_FOLDERS:
            raise ValueError(f"{path}: {name}: {kind!r} is not a dynamics kind; one of "
                             f"{tuple(DYNAMICS_FOLDERS)}")
    return data


def default_dynamics(scene: Scene) -> str:
    """The dynamics kind (``flow``, ``rigid``, ``direct``) ``scene`` plans with when none is
    named: that of its first class listed in ``skeletons/dynamics.yaml``, else ``default``."""
    table = load_default_dynamics()
    return next((table[c] for c in scene_classes(scene) if c in table), table["default"])
