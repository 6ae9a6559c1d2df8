"""The random push scenes of ``robotplan bench push``, drawn as in the paper (app. I): the
object roughly in the middle of the table (position noise 3 cm, any yaw), the pusher on a
circle around it, the goal region at one of 8 positions around the object (every 45°,
0.35 m away) with Gaussian noise (2 cm) on its centre, a square large enough for the object
in any orientation (at least 0.4 m). Boxes and L-shapes come from the ranges of the push
data; ``ood`` footprints were never seen in training; ``pose`` asks for a target pose."""

from __future__ import annotations

import math

import numpy as np

from robotplan.training.push_data import PushDataSpec, draw_shape

__all__ = ["OOD_FAMILIES", "POSE_FAMILIES", "draw_ood_shape", "draw_scene", "family_of"]

GOAL_DISTANCE = 0.35  # m from the object to the goal centre
GOAL_NOISE = 0.02  # m, standard deviation per axis
CENTER_NOISE = 0.03  # m


OOD_FAMILIES = ("triangle", "pentagon", "hexagon", "circle", "T", "cross", "U", "trapezoid")
"""Footprints never seen in training (``--shapes ood``, paper Figs. 2 and 7); T, cross and
U are concave. Scene ``i`` draws family ``i mod 8``, so 16 scenes hold each twice."""


def draw_ood_shape(rng: np.random.Generator, family: str):
    """A random footprint of ``family`` with bounding sides of 0.10–0.26 m (the push
    data's range), centred near its frame's origin."""
    from robotplan.sdf import Circle, Polygon

    u = rng.uniform
    if family == "circle":
        return Circle(round(float(u(0.05, 0.10)), 4))
    if family in ("pentagon", "hexagon"):
        n, r = (5 if family == "pentagon" else 6), u(0.07, 0.12)
        a = np.arange(n) * 2 * math.pi / n + math.pi / 2
        pts = r * np.stack((np.cos(a), np.sin(a)), 1)
    elif family == "triangle":
        b, h = u(0.14, 0.24), u(0.12, 0.22)
        pts = np.array([[-b / 2, -h / 3], [b / 2, -h / 3], [0.0, 2 * h / 3]])
    elif family == "trapezoid":
        b, h = u(0.16, 0.26), u(0.10, 0.18)
        top = b * u(0.4, 0.8)
        pts = np.array([[-b / 2, -h / 2], [b / 2, -h / 2], [top / 2, h / 2], [-top / 2, h / 2]])
    elif family == "T":
        w, h, t = u(0.16, 0.26), u(0.14, 0.24), u(0.05, 0.08)
        pts = np.array([[-t / 2, -h / 2], [t / 2, -h / 2], [t / 2, h / 2 - t], [w / 2, h / 2 - t],
                        [w / 2, h / 2], [-w / 2, h / 2], [-w / 2, h / 2 - t],
                        [-t / 2, h / 2 - t]])
    elif family == "cross":
        a, t = u(0.16, 0.26) / 2, u(0.05, 0.08) / 2
        pts = np.array([[t, -a], [t, -t], [a, -t], [a, t], [t, t], [t, a], [-t, a], [-t, t],
                        [-a, t], [-a, -t], [-t, -t], [-t, -a]])
    elif family == "U":
        w, h, t = u(0.16, 0.26), u(0.12, 0.20), u(0.04, 0.07)
        pts = np.array([[-w / 2, -h / 2], [w / 2, -h / 2], [w / 2, h / 2], [w / 2 - t, h / 2],
                        [w / 2 - t, -h / 2 + t], [-w / 2 + t, -h / 2 + t], [-w / 2 + t, h / 2],
                        [-w / 2, h / 2]])
    else:
        raise ValueError(f"unknown footprint family {family!r}")
    return Polygon(tuple((round(float(x), 4), round(float(y), 4)) for x, y in pts))


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


def draw_scene(index: int, seed: int, kind: str) -> dict:
    """The scene document (the YAML schema) of benchmark scene ``index`` for ``seed``."""
    rng = np.random.default_rng([seed, index, {"box": 0, "lshape": 1, "ood": 2}.get(kind, 3)])
    family = family_of(index, kind)
    if kind == "ood" or family == "T":
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
        "version": 1, "name": f"bench_{kind}_{index:03d}",
        "workspace": {"center": [0.0, 0.0], "size": [1.4, 1.4], "resolution": 0.01},
        "objects": [{"name": "object", "shape": _shape_doc(shape),
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
    return kind
