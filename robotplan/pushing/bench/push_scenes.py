"""The random push scenes of ``robotplan bench push``, drawn as in the paper (app. I): the
object roughly in the middle of the table (position noise 3 cm, any yaw), the pusher on a
circle around it, the goal region at one of 8 positions around the object (every 45°,
0.35 m away) with Gaussian noise (2 cm) on its centre, a square large enough for the object
in any orientation (at least 0.4 m). Boxes and L-shapes come from the ranges of the push
data; ``ood`` footprints were never seen in training, nor the ``mesh`` files of
``tasks/meshes/bench/`` (their footprints, from the meshes); ``pose`` asks for a target
pose."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np

from robotplan.base.resources import tasks_dir
from robotplan.pushing.training.footprints import OOD_FAMILIES, draw_ood_shape
from robotplan.pushing.training.push_data import PushDataSpec, draw_shape

__all__ = ["MESH_FAMILIES", "OOD_FAMILIES", "POSE_FAMILIES", "copy_meshes",
           "draw_ood_shape", "draw_scene", "family_of", "scene_name"]

MESH_FAMILIES = {"hex_nut": ("hex_nut.stl", 0.001), "arch": ("arch.ply", 1.0),
                 "mug": ("mug.obj", 1.0)}
"""``--shapes mesh``: scene ``i`` pushes mesh ``i mod 3`` of ``tasks/meshes/bench/`` (file,
scale), copied beside the scene files under ``meshes/``."""

GOAL_DISTANCE = 0.35  # m from the object to the goal centre
GOAL_NOISE = 0.02  # m, standard deviation per axis
CENTER_NOISE = 0.03  # m


def copy_meshes(scenes_dir: Path) -> None:
    """Put the bench meshes under ``scenes_dir/meshes/``, where mesh scenes name them."""
    (scenes_dir / "meshes").mkdir(parents=True, exist_ok=True)
    for file, _ in MESH_FAMILIES.values():
        shutil.copyfile(tasks_dir() / "meshes" / "bench" / file, scenes_dir / "meshes" / file)


def _mesh_shape(family: str, scenes_dir: Path):
    """``(footprint, shape document)`` of a bench mesh in ``scenes_dir/meshes/``."""
    from robotplan.scene.meshes import MeshShape, mesh_footprint

    file, scale = MESH_FAMILIES[family]
    shape = MeshShape(f"meshes/{file}", scale)
    doc = {"type": "mesh", "file": shape.file, "scale": scale}
    return mesh_footprint(shape, scenes_dir / "scene.yaml")[0], doc


def _shape_doc(shape) -> dict:
    if shape.type == "circle":
        return {"type": "circle", "radius": float(shape.radius)}
    if shape.type == "polygon":
        return {"type": "polygon", "vertices": [list(v) for v in shape.vertices]}
    if shape.type == "box":
        return {"type": "box", "size": [round(float(v), 4) for v in shape.size]}
    return {"type": "lshape", "size": [round(float(v), 4) for v in shape.size],
            "thickness": round(float(shape.thickness), 4)}


POSE_FAMILIES = ("box", "T")
"""``--shapes pose``: scene ``i`` moves a box (even i) or a T-shape (odd i) to a target
pose ``POSE_DISTANCE`` away, turned by 30–90° either way (Push-T's task)."""
POSE_DISTANCE = (0.15, 0.3)  # m
POSE_TURN_DEG = (30.0, 90.0)


def scene_name(index: int, kind: str) -> str:
    """The name of benchmark scene ``index`` of shape type ``kind`` (any seed)."""
    return f"bench_{kind}_{index:03d}"


def draw_scene(index: int, seed: int, kind: str, scenes_dir: Path | None = None) -> dict:
    """The scene document (the YAML schema) of benchmark scene ``index`` for ``seed``; a mesh
    scene's file lies in ``scenes_dir`` (:func:`copy_meshes`)."""
    rng = np.random.default_rng([seed, index, {"box": 0, "lshape": 1, "ood": 2, "mesh": 4}
                                 .get(kind, 3)])
    family = family_of(index, kind)
    shape_doc = None
    if kind == "mesh":
        assert scenes_dir is not None, "a mesh scene needs the folder of its mesh files"
        shape, shape_doc = _mesh_shape(family, scenes_dir)
    elif kind == "ood" or family == "T":
        shape = draw_ood_shape(rng, family)
    else:
        shape = draw_shape(rng, PushDataSpec(), family)
    r_obj = shape.bound_radius
    center = rng.normal(0.0, CENTER_NOISE, 2)
    yaw = rng.uniform(-math.pi, math.pi)
    radius = rng.uniform(0.02, 0.05)
    ang = rng.uniform(0, 2 * math.pi)
    dist = r_obj + radius + rng.uniform(0.05, 0.15)
    pusher = center + dist * np.array([math.cos(ang), math.sin(ang)])
    g_ang = math.radians(45 * int(rng.integers(8)))
    goal = (center + GOAL_DISTANCE * np.array([math.cos(g_ang), math.sin(g_ang)])
            + rng.normal(0.0, GOAL_NOISE, 2))
    side = max(0.4, 2 * r_obj + 0.04)
    r = lambda v: round(float(v), 4)  # noqa: E731
    goal_doc = {"type": "region", "object": "object",
                "region": {"shape": {"type": "box", "size": [r(side), r(side)]},
                           "pose": [r(goal[0]), r(goal[1]), 0.0]}}
    if kind == "pose":
        away = center + rng.uniform(*POSE_DISTANCE) * np.array([math.cos(g_ang),
                                                                  math.sin(g_ang)])
        turn = math.radians(rng.uniform(*POSE_TURN_DEG)) * rng.choice([-1.0, 1.0])
        target_yaw = (yaw + turn + math.pi) % (2 * math.pi) - math.pi
        goal_doc = {"type": "pose", "object": "object",
                    "pose": [r(away[0]), r(away[1]), r(target_yaw)]}
    return {
        "version": 1, "name": scene_name(index, kind),
        "workspace": {"center": [0.0, 0.0], "size": [1.4, 1.4], "resolution": 0.01},
        "objects": [{"name": "object", "shape": shape_doc or _shape_doc(shape),
                     "pose": [r(center[0]), r(center[1]), r(yaw)]}],
        "pushers": [{"name": "pusher", "radius": r(radius),
                     "position": [r(pusher[0]), r(pusher[1])]}],
        "goal": goal_doc,
    }


def family_of(index: int, kind: str) -> str:
    if kind == "ood":
        return OOD_FAMILIES[index % len(OOD_FAMILIES)]
    if kind == "pose":
        return POSE_FAMILIES[index % len(POSE_FAMILIES)]
    if kind == "mesh":
        return list(MESH_FAMILIES)[index % len(MESH_FAMILIES)]
    return kind
