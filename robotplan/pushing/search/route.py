"""Routes of an object around obstacles as straight face pushes (paper C.3, Fig. 10).

With obstacles between an object and its goal, the skeleton search needs more than which
face to push: the order of the pushes and how far each goes. A route fixes both. It is a
path of the object's centre made of straight segments along the axes of the object's start
frame (for a box: along its face normals), each one push from the face behind it, that
keeps the whole footprint ``clearance`` away from every obstacle. :func:`face_routes`
enumerates the rectilinear routes of up to three segments (an L around a corner, or a
detour to either side of each obstacle), shortest first, each ending where the object first
lies inside the goal region; :func:`routed_candidates` turns
them into skeletons whose push phases carry the route's waypoints (``Phase.via``) as the
initial guess, with phases long enough for the longest push.

Straight pushes suit open-loop execution: a sphere pushing a face through the centroid
moves a box straight in pybullet, while a push 2 mm off the centre turns it by 0.13 rad in
0.3 m and 0.5 rad in 0.6 m (tests/pushing/search/test_route.py), an error no later push of the
open-loop plan sees. Routed programs therefore use the ``routes`` settings
(``skeletons/settings.yaml``), and a route only takes
directions in which the pusher can meet a face on the centroid's line
(:func:`centred_pushes`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import torch

from robotplan.functionals.clearance import densify, obstacle_clearance
from robotplan.functionals.sticking import centroid
from robotplan.pushing.program.skeleton import Phase, Skeleton, SkeletonSpace
from robotplan.scene import Body, Scene
from robotplan.scene.task import PushTask
from robotplan.sdf import Shape2D

__all__ = ["Route", "centred_pushes", "face_routes", "routed_candidates"]

ROUTE_CLEARANCE = 0.04  # m between the routed footprint and every obstacle
ROUTE_LIMIT = 3  # routes tried: the shortest, fewest segments first
# m: a route ends where the footprint (at its start yaw) lies this far inside the goal
# region: beyond the region's inset that the program plans into (goal.inset, 2 cm)
GOAL_INSIDE = 0.03
MAX_STEPS_PER_PHASE = 30  # longer segments are split into several pushes


@dataclass(frozen=True)
class Route:
    """Waypoints ``(K + 1, 2)`` of the object's centre (table frame) and, per segment, the
    direction index ``(K,)`` into the object frame's axes +x, +y, −x, −y."""

    waypoints: np.ndarray
    directions: tuple[int, ...]

    @property
    def length(self) -> float:
        return float(np.linalg.norm(np.diff(self.waypoints, axis=0), axis=1).sum())

    @property
    def segments(self) -> np.ndarray:
        """Segment lengths ``(K,)`` in m."""
        return np.linalg.norm(np.diff(self.waypoints, axis=0), axis=1)


def _frame(yaw: float) -> np.ndarray:
    """Columns: the object's start axes in the table frame ``(2, 2)``."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s], [s, c]])


def _legs(moves: list[tuple[int, float]]) -> list[tuple[int, float]]:
    """Drop zero moves and merge consecutive moves along the same axis."""
    out: list[tuple[int, float]] = []
    for axis, d in moves:
        if abs(d) < 1e-3:
            continue
        if out and out[-1][0] == axis:
            out[-1] = (axis, out[-1][1] + d)
        else:
            out.append((axis, d))
    return [(a, d) for a, d in out if abs(d) >= 1e-3]  # merged moves may cancel


def _clear(scene: Scene, obj: str, points: np.ndarray, yaw: float, clearance: float,
           step: float = 0.005) -> bool:
    """Whether the object at yaw ``yaw`` moving along the polyline ``points (W, 2)`` keeps
    ``clearance`` from every obstacle and stays on the workspace."""
    ws = scene.workspace
    lo = np.asarray(ws.center) - np.asarray(ws.size) / 2
    hi = np.asarray(ws.center) + np.asarray(ws.size) / 2
    c, s = math.cos(yaw), math.sin(yaw)
    local = scene.bodies[obj].shape.outline(n_arc=64) @ np.array([[c, s], [-s, c]])
    poses = densify(np.column_stack((points, np.full(len(points), yaw))), step)
    every = poses[:, None, :2] + local[None]  # (C, V, 2)
    if (every < lo).any() or (every > hi).any():
        return False
    return obstacle_clearance(scene, obj, poses, step=math.inf) >= clearance  # dense already


def centred_pushes(shape: Shape2D, radius: float, tilt_deg: float = 5.0) -> set[int]:
    """The axis directions (0: +x, 1: +y, 2: −x, 3: −y of the shape frame) in which a
    sphere of ``radius`` coming along the line through the centroid touches a face, not a
    corner: its contact normal within ``tilt_deg`` of the line. An L-shape pushed towards
    −y from above meets the corner of its upright bar, not a face."""
    c = centroid(shape.outline())
    far = shape.bound_radius + float(np.linalg.norm(c)) + radius
    s = torch.linspace(far, 0.0, int(far / 0.0005) + 1, dtype=torch.float64)
    out = set()
    for k in range(4):
        d = np.eye(2)[k % 2] * (1 - 2 * (k // 2))
        centres = torch.as_tensor(c)[None] - s[:, None] * torch.as_tensor(d)[None]
        phi, grad = shape.sdf_and_grad(centres)
        touching = torch.nonzero(phi <= radius)
        if not len(touching):
            continue
        g = grad[int(touching[0])]
        if float(-(g @ torch.as_tensor(d)) / g.norm()) >= math.cos(math.radians(tilt_deg)):
            out.add(k)
    return out


def _inside(region: Body, outline: np.ndarray, xy: np.ndarray, margin: float) -> bool:
    """Whether the footprint ``outline (V, 2)`` (object frame axes in the table frame) at
    ``xy`` lies ``margin`` inside ``region``."""
    points = torch.as_tensor(outline + xy, dtype=torch.float64)
    return float(region.sdf(points).max()) <= -margin


def _trim_to_region(legs: list[tuple[int, float]], start: np.ndarray, R: np.ndarray,
                    outline: np.ndarray, region: Body | None) -> list[tuple[int, float]]:
    """Drop the route's last legs while the object already lies GOAL_INSIDE within the
    goal region where they begin: the region's centre is only where a route aims, and a
    push of a few centimetres more is a phase (reach + push) the program must also solve."""
    while region is not None and len(legs) > 1:
        before = start + np.sum([np.eye(2)[a] * x for a, x in legs[:-1]], axis=0) @ R.T
        if not _inside(region, outline, before, GOAL_INSIDE):
            break
        legs = legs[:-1]
    return legs


def face_routes(scene: Scene, obj: str, goal_xy: np.ndarray,
                clearance: float = ROUTE_CLEARANCE,
                pushable: set[int] | None = None, region: Body | None = None
                ) -> list[Route]:
    """Rectilinear routes of ``obj``'s centre from its start to ``goal_xy`` along its start
    axes, of at most three segments, keeping its footprint (at its start yaw) ``clearance``
    from every obstacle: the two L-shaped routes (either axis first) and, for each axis,
    detours that pass each obstacle on either side; only directions in ``pushable`` (all by
    default). With the goal ``region``, a route ends at the first waypoint where the
    footprint lies inside it (:func:`_trim_to_region`). The ROUTE_LIMIT shortest, fewest
    segments first among equal lengths."""
    body = scene.bodies[obj]
    start = np.array(body.pose[:2], dtype=float)
    yaw = float(body.pose[2])
    R = _frame(yaw)
    d = R.T @ (np.asarray(goal_xy, dtype=float) - start)  # travel in the object's axes
    local = body.shape.outline(n_arc=64)
    plans: list[list[tuple[int, float]]] = [[(0, d[0]), (1, d[1])], [(1, d[1]), (0, d[0])]]
    for spec in scene.obstacles:
        rim = (scene.bodies[spec.name].outline_world() - start) @ R  # in the object's axes
        for axis in (0, 1):
            other = 1 - axis
            for side in (rim[:, axis].max() - local[:, axis].min() + clearance,
                         rim[:, axis].min() - local[:, axis].max() - clearance):
                plans.append([(axis, side), (other, d[other]), (axis, d[axis] - side)])
    routes: dict[tuple, Route] = {}
    outline = local @ R.T  # the footprint at its start yaw, about its centre
    for plan in plans:
        legs = _trim_to_region(_legs(plan), start, R, outline, region)
        if not legs:
            continue
        dirs = tuple(a + (2 if x < 0 else 0) for a, x in legs)
        if pushable is not None and not set(dirs) <= pushable:
            continue
        rel = np.cumsum([np.eye(2)[a] * x for a, x in legs], axis=0)
        waypoints = np.vstack((start, start + rel @ R.T))
        if not _clear(scene, obj, waypoints, yaw, 0.9 * clearance):  # detours at exactly it
            continue
        key = tuple(np.round(waypoints, 4).ravel())
        routes.setdefault(key, Route(waypoints, dirs))
    ordered = sorted(routes.values(), key=lambda r: (round(r.length, 3), len(r.directions)))
    return ordered[:ROUTE_LIMIT]


def _split(route: Route, longest: float) -> Route:
    """Split segments longer than ``longest`` (m) into equal pushes."""
    points, dirs = [route.waypoints[0]], []
    for a, b, k in zip(route.waypoints[:-1], route.waypoints[1:], route.directions,
                       strict=True):
        n = max(1, math.ceil(float(np.linalg.norm(b - a)) / longest - 1e-9))
        points += [a + (b - a) * i / n for i in range(1, n + 1)]
        dirs += [k] * n
    return Route(np.array(points), tuple(dirs))


def routed_candidates(task: PushTask, space: SkeletonSpace, speed: float,
                      max_pushes: int = 4) -> tuple[SkeletonSpace, list[Skeleton]]:
    """Skeletons in which the task's pusher pushes its object along :func:`face_routes` to
    the goal region's centre, each ending where the object lies inside it (reach + push per segment,
    the push from the face behind the segment, ``via`` the segment's end), and the space
    they need: init points in the object's frame, enough steps per phase for the longest
    push at ``speed`` m per step (two steps for contact), at most MAX_STEPS_PER_PHASE."""
    scene, obj, actor, region = task.scene, task.obj, task.actors[0], task.region
    pushable = centred_pushes(scene.bodies[obj].shape, scene.bodies[actor].shape.radius)
    routes = face_routes(scene, obj, np.array(region.pose[:2], dtype=float),
                         pushable=pushable, region=region)
    longest = (MAX_STEPS_PER_PHASE - 2) * speed
    routes = [r for r in (_split(r, longest) for r in routes) if len(r.directions) <= max_pushes]
    if not routes:
        return space, []
    steps = max(space.steps_per_phase,
                max(math.ceil(float(r.segments.max()) / speed) + 2 for r in routes))
    routed = replace(space, steps_per_phase=steps, init_frame="object",
                     init_directions_deg=(0.0, 90.0, 180.0, 270.0))
    skeletons = []
    for r in routes:
        phases: list[Phase] = []
        for k, direction in enumerate(r.directions):
            init = (direction + 2) % 4  # the pusher starts behind the face it pushes
            phases.append(Phase("reach", actor, obj, init))
            phases.append(Phase("push", actor, obj, init,
                                via=(float(r.waypoints[k + 1][0]), float(r.waypoints[k + 1][1]))))
        skeletons.append(Skeleton(tuple(phases)))
    return routed, skeletons
