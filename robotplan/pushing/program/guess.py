"""The initial guess of a push program (paper app. I.2): the pusher circles the object to
the phase's fixed init point, steps into contact and pushes towards the goal."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import torch

from robotplan.functionals.base import sdf_pose_gradients

if TYPE_CHECKING:
    from robotplan.pushing.program.push_program import PushProgram

__all__ = ["contact_offset", "contact_point_guess", "guess_goal", "init_point", "initial_guess",
           "object_route"]


def init_point(prog: PushProgram, index: int, center: np.ndarray) -> np.ndarray:
    """The phase's fixed init point ``index`` around an object centred at ``center``."""
    start = np.array(prog.obj.pose[:2], dtype=float)
    goal = guess_goal(prog, start)
    ang = prog.space.init_angle(index, start, None if np.allclose(goal, start) else goal,
                                prog.obj.pose[2])
    dist = (prog.obj.shape.bound_radius + prog.pusher.shape.radius
            + prog.space.init_clearance)
    return center + dist * np.array([math.cos(ang), math.sin(ang)])


def contact_offset(prog: PushProgram, X_obj: np.ndarray, direction: np.ndarray,
                   depth: float = 0.001, samples: int = 64) -> np.ndarray:
    """Where along ``direction`` from the object's origin the pusher touches it from
    outside (its centre at φ_obj = radius − depth): the outermost crossing on the ray.

    From an origin inside the object, bisection on the ray. The origin need not be inside
    (an L-shape's frame is its bounding box's centre, usually in the notch): then the ray
    is sampled and the last sample within reach brackets the bisection, and a ray that
    never comes within reach (into the notch's opening) gets its closest approach moved
    along −∇φ onto the touching level.
    """
    u = direction / max(float(np.linalg.norm(direction)), 1e-9)
    target = prog.pusher.shape.radius - depth
    reach = prog.obj.shape.bound_radius + prog.pusher.shape.radius
    X = torch.as_tensor(X_obj, dtype=torch.float64)[None]

    def phi(d: np.ndarray) -> np.ndarray:
        points = torch.as_tensor(X_obj[:2] + d[:, None] * u, dtype=torch.float64)[None]
        return prog.obj.sdf(points, X)[0].numpy()

    lo, hi = 0.0, reach
    if phi(np.zeros(1))[0] >= target:  # the origin is outside: find the outermost bracket
        d = np.linspace(0.0, reach, samples)
        values = phi(d)
        inside = np.nonzero(values < target)[0]
        if len(inside) == 0:
            best = X_obj[:2] + d[int(np.argmin(values))] * u
            phi_b, _, grad = sdf_pose_gradients(
                prog.obj, torch.as_tensor(best, dtype=torch.float64)[None, None], X)
            step = (float(phi_b[0, 0]) - target) * grad[0, 0].numpy()
            return best - step - X_obj[:2]
        lo, hi = d[inside[-1]], d[min(inside[-1] + 1, samples - 1)]
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        if phi(np.array([mid]))[0] < target:
            lo = mid
        else:
            hi = mid
    return hi * u


def contact_point_guess(prog: PushProgram, q_obj: np.ndarray, q_pusher: np.ndarray
                        ) -> np.ndarray:
    """H_PoC's contact point for pusher centres ``q_pusher (n, 2)`` beside objects at
    ``q_obj (n, 3)``: the point of the pusher's surface that faces the object (its centre
    moved by the radius against ∇φ_obj). It lies on both surfaces when they touch, and
    never at the pusher's centre, where φ_pusher's gradient vanishes (a solver started
    there could not move it: violation = radius)."""
    X = torch.as_tensor(q_obj, dtype=torch.float64)
    points = torch.as_tensor(q_pusher, dtype=torch.float64)[:, None, :]
    _, _, grad = sdf_pose_gradients(prog.obj, points, X)
    n = grad[:, 0].numpy()
    n = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-9)
    return q_pusher - prog.pusher.shape.radius * n


TOUCH_DISTANCE = 0.6  # m from the touching arm's base where the guess brings the object


def guess_goal(prog: PushProgram, start: np.ndarray) -> np.ndarray:
    """Where the guess pushes the object: the goal region's centre, or for a touch goal by
    an arm, towards that arm until it is ``TOUCH_DISTANCE`` from its base."""
    if prog.region is not None:
        return np.array(prog.region.pose[:2], dtype=float)
    robot = next((r for r in prog.scene.robots if r.name == prog.task.touch_actor), None)
    if robot is None or not prog.skeleton.pushes:
        return start
    away = start - np.array(robot.base[:2])
    dist = float(np.linalg.norm(away))
    return start - away / max(dist, 1e-9) * max(0.0, dist - TOUCH_DISTANCE)


def object_route(prog: PushProgram, start: np.ndarray, goal: np.ndarray,
                 clearance: float = 0.03) -> np.ndarray:
    """Waypoints ``(W, 2)`` of the object's centre from ``start`` to ``goal``: straight, or
    around every obstacle whose disc (bound radius + the object's + ``clearance``) the
    straight line crosses, by the side nearer to the line."""
    points = [start]
    u = goal - start
    length = float(np.linalg.norm(u))
    if length < 1e-9:
        return np.array([start, goal])
    u = u / length
    normal = np.array([-u[1], u[0]])
    detours = []
    for spec in prog.scene.obstacles:
        wall = prog.scene.bodies[spec.name]
        c = np.array(wall.pose[:2], dtype=float)
        reach = wall.shape.bound_radius + prog.obj.shape.bound_radius + clearance
        along, side = float((c - start) @ u), float((c - start) @ normal)
        if 0.0 < along < length and abs(side) < reach:
            sign = -1.0 if side >= 0 else 1.0
            detours.append((along, c + sign * reach * normal))
    points += [via for _, via in sorted(detours, key=lambda d: d[0])]
    return np.array([*points, goal])


def face_push_lengths(directions: np.ndarray, travel: np.ndarray) -> tuple[np.ndarray, float]:
    """Non-negative lengths ``a (K,)`` of straight pushes along unit ``directions (K, 2)``
    whose sum best matches ``travel (2,)``, and the distance (m) they leave to it (every
    subset of pushes solved by least squares; K ≤ 3 in practice)."""
    K = len(directions)
    best, best_gap = np.zeros(K), float(np.linalg.norm(travel))
    # larger subsets first, so that equal fits share the travel (least-norm lengths)
    for mask in sorted(range(1, 2**K), key=lambda m: -bin(m).count("1")):
        idx = [k for k in range(K) if mask >> k & 1]
        A = directions[idx].T
        a, *_ = np.linalg.lstsq(A, travel, rcond=None)
        if (a < -1e-9).any():
            continue
        gap = float(np.linalg.norm(A @ a - travel))
        if gap < best_gap - 1e-6:
            best, best_gap = np.zeros(K), gap
            best[idx] = np.maximum(a, 0.0)
    return best, best_gap


def push_ends(prog: PushProgram, start: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """Where the guess leaves the object after each push ``(K, 2)``: along the route
    (:func:`object_route`), or, with init points in the object's frame (face normals of a
    box), by straight pushes away from each push's init point (:func:`face_push_lengths`)."""
    pushes = [ph for ph in prog.skeleton.phases if ph.mode == "push"]
    if prog.space.init_frame == "object":
        yaw = prog.obj.pose[2]
        angles = [prog.space.init_angle(ph.init, start, goal, yaw) + math.pi for ph in pushes]
        dirs = np.array([[math.cos(a), math.sin(a)] for a in angles]).reshape(-1, 2)
        lengths, _ = face_push_lengths(dirs, goal - start)
        # no push travels further than a phase allows at the guess's speed (per axis)
        longest = (prog.T - 2) * prog.settings.guess_speed / np.abs(dirs).max(axis=1)
        lengths = np.minimum(lengths, longest)
        return start + np.cumsum(lengths[:, None] * dirs, axis=0)
    route = object_route(prog, start, goal)
    return np.array([_along(route, (k + 1) / len(pushes)) for k in range(len(pushes))])


def _along(route: np.ndarray, fraction: float) -> np.ndarray:
    """The point at ``fraction`` of the route's length."""
    seg = np.linalg.norm(np.diff(route, axis=0), axis=1)
    target = fraction * seg.sum()
    for k, d in enumerate(seg):
        if target <= d or k == len(seg) - 1:
            return route[k] + (route[k + 1] - route[k]) * min(1.0, target / max(d, 1e-12))
        target -= d
    return route[-1]


def initial_guess(prog: PushProgram, ends: np.ndarray | None = None
                  ) -> dict[str, np.ndarray]:
    """Paper app. I.2: the pusher moves on a circle around the object to the phase's
    init point, then pushes; the object slides towards the goal in push phases (to
    ``ends (K, 2)`` after each push when given, else along :func:`push_ends`)."""
    T, N = prog.T, prog.N
    start = np.array(prog.obj.pose, dtype=float)
    goal = guess_goal(prog, start[:2])
    vias = [ph.via for ph in prog.skeleton.phases if ph.mode == "push"]
    if ends is None and vias and all(v is not None for v in vias):
        ends = np.array(vias, dtype=float)
    if ends is None and prog.skeleton.pushes:
        ends = push_ends(prog, start[:2], goal)
    q1 = np.tile(start, (N + 1, 1))
    q2 = np.zeros((N + 1, 2))
    q2[0] = prog.pusher.pose[:2]
    speed = prog.settings.guess_speed  # per step and axis
    done = 0
    p_touch = None
    for k, ph in enumerate(prog.skeleton.phases):
        a, b = k * T, (k + 1) * T
        center = q1[a, :2]
        target = init_point(prog, ph.init, center)
        touching = (ph.mode == "reach" and k == len(prog.skeleton.phases) - 1
                    and prog.task.goal == "touch")
        if touching:  # the touch goal's reach ends on the object, not at the init point
            target = center + contact_offset(prog, q1[a], target - center)
            unit = (target - center) / max(float(np.linalg.norm(target - center)), 1e-9)
            p_touch = target - prog.pusher.shape.radius * unit
        if ph.mode == "reach":
            # a new actor starts where it waited (its own start), not at the last tip
            switched = k > 0 and ph.actor != prog.skeleton.phases[k - 1].actor
            r0 = (np.array(prog.scene.bodies[ph.actor].pose[:2]) if switched else q2[a]) - center
            r1 = target - center
            ang0, ang1 = math.atan2(r0[1], r0[0]), math.atan2(r1[1], r1[0])
            dang = (ang1 - ang0 + math.pi) % (2 * math.pi) - math.pi
            rad0, rad1 = np.linalg.norm(r0), np.linalg.norm(r1)
            for s in range(1, T + 1):
                u = s / T
                ang, rad = ang0 + u * dang, rad0 + u * (rad1 - rad0)
                q2[a + s] = center + rad * np.array([math.cos(ang), math.sin(ang)])
            q1[a + 1:b + 1] = q1[a]
        else:  # the pusher steps into contact, then the two move towards the goal
            done += 1
            end = ends[done - 1]
            offset = contact_offset(prog, q1[a], q2[a] - q1[a, :2])
            contact = q1[a, :2] + offset
            k = min(T - 1, math.ceil(np.abs(contact - q2[a]).max() / speed))
            for s in range(1, k + 1):  # approach, the object still
                q2[a + s] = q2[a] + (contact - q2[a]) * s / k
                q1[a + s] = q1[a]
            # push at most at the data's speeds (the goal constraint asks for the rest)
            travel = end - q1[a, :2]
            travel *= min(1.0, (T - k) * speed / max(np.abs(travel).max(), 1e-9))
            for s in range(k + 1, T + 1):
                q1[a + s] = q1[a]
                q1[a + s, :2] = q1[a, :2] + travel * (s - k) / (T - k)
                q2[a + s] = q1[a + s, :2] + offset
    steps = np.asarray(prog.push_steps, dtype=int)
    p = 0.5 * (q1[steps, :2] + q2[steps]) if len(steps) else np.zeros((0, 2))
    if len(steps):  # never at the pusher's centre (φ_pusher's gradient vanishes there)
        near = np.linalg.norm(p - q2[steps], axis=1) < 0.5 * prog.pusher.shape.radius
        p[near] = contact_point_guess(prog, q1[steps][near], q2[steps][near])
    guess = {"q_obj": q1, "q_pusher": q2, "p": p}
    if p_touch is not None:
        guess["p_touch"] = p_touch[None]
    return guess
