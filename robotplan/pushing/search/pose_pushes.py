"""Pushes that turn an object to a target pose (x, y, yaw), found in closed form before any
program is solved.

A pose goal needs pushes off the centroid: a sphere pushing a face along its normal at lever
b from the centroid turns the object. Under the quasi-static sticking push of the kinematic
stage (:class:`robotplan.functionals.sticking.QuasiStaticPush`, ``c² Δθ = r × Δc``) such a
push is a constant twist in the object's frame: the centroid moves along the face normal
n_B (body frame) and the object turns κ = (r_B × n_B) / c² per metre, so the centroid
follows a circular arc. A push is therefore three numbers, the face, the contact point's
position along it and the length pushed, and the pose after K pushes is a closed-form
composition of arcs. :func:`fit_pose_pushes` fits the lengths and contact points of every
sequence of up to ``max_pushes`` faces to the target pose by least squares;
:mod:`robotplan.pushing.search.pose_search` turns the fits into skeletons with a full initial guess.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
import torch

from robotplan.base.batch_least_squares import least_squares_batch
from robotplan.functionals.sticking import centroid, turning_radius
from robotplan.geometry.transforms import wrap_angle
from robotplan.scene import Scene
from robotplan.scene.task import PushTask

__all__ = ["FIT_SHARE", "FIT_TOLERANCE", "INIT_DIRECTIONS_DEG", "STANDOFF", "Face", "PosePushes",
           "TurningBody", "centroid_room", "faces_of", "fit_pose_pushes", "fit_rank", "push_arc",
           "rotation", "sticking_share"]

MIN_FACE = 0.02  # m: shorter edges of the outline (a disc's facets) are not pushed
FACE_MARGIN = 0.2  # share of a face kept free at either end: contacts nearer a corner slide
STANDOFF = 0.015  # m between the pusher and the face where a reach ends (≥ H_coll.clearance)
FIT_TOLERANCE = 0.004  # m of pose error (yaw as c·Δθ) a fit may leave to the program
# share of the pose error from the start that a fit may leave: near the target a push that
# leaves 4 mm is one the program cannot close to the pose goal's tolerance, so a small
# correction gets the two pushes a turn in place needs (docs/experiments.md#close-fits)
FIT_SHARE = 0.4
LENGTH_WEIGHT = 0.05  # least-squares weight of each push's length: shorter pushes first
MAX_LENGTH = 0.35  # m pushed at most in one push
KEEP_FITS = 4  # fits kept, one per sequence of face classes: a pose tier's programs
PUSH_COST = 0.1  # m of pushing one more push (its reach around the object) counts as
ROOM_SAMPLES = 6  # points per push at which the object must leave the pusher room on the table
INIT_DIRECTIONS_DEG = (0.0, 90.0, 180.0, 270.0)  # face normal classes in the object frame
# contact shares along the face the least squares start from, all solved at once
# (docs/experiments.md#batched-fits)
FIT_STARTS = (0.5, 0.25, 0.75)


@dataclass(frozen=True)
class Face:
    """A straight edge of the object's outline, body frame: from ``a`` along unit ``t`` for
    ``length`` m, inward unit normal ``n``; ``init``: the nearest of the object-frame
    directions INIT_DIRECTIONS_DEG to its outward normal."""

    a: np.ndarray
    t: np.ndarray
    n: np.ndarray
    length: float
    init: int

    def point(self, u: float) -> np.ndarray:
        """The point at share ``u`` ∈ [0, 1] of the face."""
        return self.a + u * self.length * self.t


def faces_of(scene: Scene, obj: str, actor: str) -> list[Face]:
    """The faces of ``obj`` a sphere ``actor`` can push along their normal: edges of at least
    MIN_FACE whose middle part the sphere can touch from outside without meeting the rest of
    the object (an L's or T's inner faces may be too narrow for it)."""
    shape = scene.bodies[obj].shape
    radius = scene.bodies[actor].shape.radius
    outline = shape.outline(n_arc=32)
    x, y = outline[:, 0], outline[:, 1]
    ccw = (x * np.roll(y, -1) - np.roll(x, -1) * y).sum() > 0
    faces = []
    for a, b in zip(outline, np.roll(outline, -1, axis=0), strict=True):
        length = float(np.linalg.norm(b - a))
        if length < MIN_FACE:
            continue
        t = (b - a) / length
        n = np.array([-t[1], t[0]]) if ccw else np.array([t[1], -t[0]])
        us = np.linspace(FACE_MARGIN, 1 - FACE_MARGIN, 5)
        centres = torch.as_tensor(a + np.outer(us * length, t) - (radius + 1e-3) * n)
        phi, _ = shape.sdf_and_grad(centres)
        if float(phi.min()) < radius:
            continue
        out = math.degrees(math.atan2(-n[1], -n[0])) % 360.0
        init = int(np.argmin([abs((out - d + 180.0) % 360.0 - 180.0)
                              for d in INIT_DIRECTIONS_DEG]))
        faces.append(Face(a, t, n, length, init))
    return faces


def rotation(yaw: float) -> np.ndarray:
    """R(yaw) ``(2, 2)``."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s], [s, c]])


def push_arc(c0: np.ndarray, yaw0: float, r_B: np.ndarray, n_B: np.ndarray, radius: float,
             s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centroids ``(S, 2)`` and yaws ``(S,)`` after pushing ``s (S,)`` m at ``r_B`` (contact
    point from the centroid, body frame) along the inward normal ``n_B``, from the centroid
    ``c0`` at ``yaw0``: θ = θ0 + κ s and c = c0 + R(θ0) ∫₀ˢ R(κσ) n_B dσ, κ = (r × n)/c²."""
    cs, ys = _arcs(np.asarray(c0, dtype=float)[None], np.array([yaw0], dtype=float),
                   np.asarray(r_B, dtype=float)[None], n_B, radius, np.asarray(s)[None])
    return cs[0], ys[0]


def _arcs(c0: np.ndarray, yaw0: np.ndarray, r_B: np.ndarray, n_B: np.ndarray, radius: float,
          s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`push_arc` for a batch: ``c0 (B, 2)``, ``yaw0 (B,)``, ``r_B (B, 2)``, ``n_B (2,)``
    or ``(B, 2)``, ``s (B, S)`` give centroids ``(B, S, 2)`` and yaws ``(B, S)``."""
    nx, ny = np.broadcast_to(n_B, r_B.shape).T[:, :, None]
    kappa = (r_B[:, 0] * ny[:, 0] - r_B[:, 1] * nx[:, 0]) / radius**2
    ks = kappa[:, None] * s
    small = np.abs(ks) < 1e-6
    safe = np.where(small, 1.0, ks)
    sin_term = np.where(small, 1.0 - ks**2 / 6, np.sin(safe) / safe) * s
    cos_term = np.where(small, ks / 2, (1.0 - np.cos(safe)) / safe) * s
    lx = sin_term * nx - cos_term * ny
    ly = cos_term * nx + sin_term * ny
    cos0, sin0 = np.cos(yaw0)[:, None], np.sin(yaw0)[:, None]
    world = np.stack((cos0 * lx - sin0 * ly, sin0 * lx + cos0 * ly), -1)
    return c0[:, None, :] + world, yaw0[:, None] + ks


@dataclass(frozen=True)
class PosePushes:
    """A fitted sequence of pushes: per push its face, the contact point's share along it,
    the length pushed (m) and the turn (rad); ``error``: the pose error it leaves (m, yaw as
    c·Δθ); ``tolerance``: the error within which it counts as reaching the target."""

    faces: tuple[Face, ...]
    shares: tuple[float, ...]
    lengths: tuple[float, ...]
    error: float
    turns: tuple[float, ...] = ()
    tolerance: float = FIT_TOLERANCE

    @property
    def total_length(self) -> float:
        return float(sum(self.lengths))

    @property
    def within(self) -> bool:
        return self.error <= self.tolerance


class TurningBody:
    """The pushed object's quasi-static constants: centroid (body frame) and limit surface
    radius c over √turn_gain, as the program's turning law has them."""

    def __init__(self, scene: Scene, obj: str, turn_gain: float) -> None:
        shape = scene.bodies[obj].shape
        self.c_B = centroid(shape.outline())
        self.radius = turning_radius(shape, turn_gain)

    def origin(self, c_W: np.ndarray, yaw: np.ndarray) -> np.ndarray:
        """Object-frame origins ``(S, 2)`` of centroids ``c_W (S, 2)`` at ``yaw (S,)``."""
        cB = self.c_B
        return c_W - np.stack((np.cos(yaw) * cB[0] - np.sin(yaw) * cB[1],
                               np.sin(yaw) * cB[0] + np.cos(yaw) * cB[1]), -1)


@dataclass(frozen=True)
class FaceStack:
    """Sequences of K faces as arrays, one row per sequence: starts ``a``, tangents ``t``
    and inward normals ``n`` ``(S, K, 2)``, lengths ``(S, K)`` (body frame)."""

    a: np.ndarray
    t: np.ndarray
    n: np.ndarray
    length: np.ndarray

    @classmethod
    def of(cls, sequences: list[tuple[Face, ...]]) -> FaceStack:
        return cls(*(np.array([[getattr(f, name) for f in seq] for seq in sequences])
                     for name in ("a", "t", "n", "length")))

    def rows(self, index: np.ndarray) -> FaceStack:
        return FaceStack(self.a[index], self.t[index], self.n[index], self.length[index])


def _path(body: TurningBody, faces: FaceStack, c0: np.ndarray, yaw0: float,
          params: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """For a batch of pushes ``params (B, 2K)`` (share, length per push) along the face
    sequences ``faces`` (B rows): the end centroids ``(B, 2)`` and yaws ``(B,)``, the
    centroids ``(B, K · ROOM_SAMPLES, 2)`` passed on the way and each push's turn ``(B, K)``."""
    B = len(params)
    c, yaw = np.tile(np.asarray(c0, dtype=float), (B, 1)), np.full(B, float(yaw0))
    passed, turns = [], []
    steps = np.arange(1, ROOM_SAMPLES + 1) / ROOM_SAMPLES
    for k in range(faces.length.shape[1]):
        share, length = params[:, 2 * k], params[:, 2 * k + 1]
        r_B = faces.a[:, k] + (share * faces.length[:, k])[:, None] * faces.t[:, k] - body.c_B
        cs, ys = _arcs(c, yaw, r_B, faces.n[:, k], body.radius, length[:, None] * steps)
        passed.append(cs)
        turns.append(ys[:, -1] - yaw)
        c, yaw = cs[:, -1], ys[:, -1]
    return c, yaw, np.concatenate(passed, axis=1), np.stack(turns, -1)


def centroid_room(task: PushTask) -> tuple[np.ndarray, np.ndarray]:
    """The box ``(low, high)`` (table frame, m) the fitted pushes keep the object's centroid
    in: the object's reach plus a pusher's width and standoff from the table's edges, so
    that the pusher can get behind it."""
    scene, obj = task.scene, task.obj
    shape = scene.bodies[obj].shape
    room = (shape.bound_radius + float(np.linalg.norm(centroid(shape.outline())))
            + 2 * scene.bodies[task.actors[0]].shape.radius + STANDOFF)
    ws = scene.workspace
    return (np.asarray(ws.center) - np.asarray(ws.size) / 2 + room,
            np.asarray(ws.center) + np.asarray(ws.size) / 2 - room)


def fit_pose_pushes(task: PushTask, goal: tuple[float, float, float], max_pushes: int = 2,
                    turn_gain: float = 1.0, classes: tuple[int, ...] | None = None
                    ) -> list[PosePushes]:
    """The KEEP_FITS best fits (the least pushing among those within tolerance of ``goal``
    and on the table, FIT_TOLERANCE or FIT_SHARE of the start's pose error, whichever is
    less; else the closest), one per sequence of face classes, of up to ``max_pushes``
    pushes by the task's pusher bringing its object to ``goal`` under the quasi-static push
    (turning law ``c² Δθ = turn_gain · r × Δc``); ``classes``: only the sequences of
    ``max_pushes`` faces of these init classes."""
    scene, obj, actor = task.scene, task.obj, task.actors[0]
    body = TurningBody(scene, obj, turn_gain)
    pose = np.asarray(scene.bodies[obj].pose, dtype=float)
    c0 = pose[:2] + rotation(pose[2]) @ body.c_B
    target_c = np.asarray(goal[:2], dtype=float) + rotation(goal[2]) @ body.c_B
    target_yaw = pose[2] + wrap_angle(goal[2] - pose[2])
    start_error = float(np.linalg.norm([*(c0 - target_c), body.radius * (target_yaw - pose[2])]))
    tolerance = min(FIT_TOLERANCE, FIT_SHARE * start_error)
    faces = faces_of(scene, obj, actor)
    lo_xy, hi_xy = centroid_room(task)
    fits: dict[tuple[int, ...], PosePushes] = {}
    for k in range(1 if classes is None else max_pushes, max_pushes + 1):
        seqs = [seq for seq in itertools.product(faces, repeat=k)
                if classes is None or tuple(f.init for f in seq) == classes]
        if not seqs:
            continue
        stack, S = FaceStack.of(seqs), len(seqs)

        def residuals(points: np.ndarray, problems: np.ndarray, stack=stack, S=S) -> np.ndarray:
            B, R, n = points.shape
            c, yaw, passed, _turns = _path(body, stack.rows(np.repeat(problems % S, R)), c0,
                                           pose[2], points.reshape(B * R, n))
            miss = np.column_stack((c - target_c, body.radius * (yaw - target_yaw)))
            off = np.maximum(passed - hi_xy, 0.0) + np.maximum(lo_xy - passed, 0.0)
            return np.hstack((miss, off.reshape(B * R, -1),  # the pose and room on the table
                              LENGTH_WEIGHT * points.reshape(B * R, n)[:, 1::2])
                             ).reshape(B, R, -1)

        # every start of every sequence at once: problem j·S + i starts sequence i at share j
        x0 = np.vstack([np.tile([u, 0.1], (S, k)) for u in FIT_STARTS])
        solved = least_squares_batch(residuals, x0, np.tile([FACE_MARGIN, 0.0], k),
                                     np.tile([1 - FACE_MARGIN, MAX_LENGTH], k))
        miss = np.linalg.norm(solved.fun[:, :-k], axis=1)
        # per sequence the least cost among its starts within tolerance, else among all
        rank = (miss > tolerance) + np.minimum(solved.cost, 0.5)
        best = rank.reshape(len(FIT_STARTS), S).argmin(0) * S + np.arange(S)
        x, turns = solved.x[best], _path(body, stack, c0, pose[2], solved.x[best])[3]
        for i, seq in enumerate(seqs):
            fit = PosePushes(seq, tuple(x[i, 0::2]), tuple(x[i, 1::2]), float(miss[best[i]]),
                             tuple(float(t) for t in turns[i]), tolerance)
            key = tuple(f.init for f in seq)
            if key not in fits or fit_rank(fit) < fit_rank(fits[key]):
                fits[key] = fit
    return sorted(fits.values(), key=fit_rank)[:KEEP_FITS]


def sticking_share(body: TurningBody, face: Face, share: float, step: float) -> float:
    """Where along ``face`` (share of its length) the pusher sticks so that the arc pushed
    at ``share`` meets the program's discrete turning law in steps of ``step`` m,
    ``c² Δθ = r × Δc`` with ``r`` from the step's end centroid
    (:class:`~robotplan.functionals.sticking.QuasiStaticPush`): the arc's chord turns the
    object a little more or less than its end contact point would. Every chord of the arc
    is the same in the object's frame, so one share holds in every step. Kept within the
    face; ``share`` where the face is parallel to the step."""
    r_B = face.point(share) - body.c_B
    cs, ys = push_arc(np.zeros(2), 0.0, r_B, face.n, body.radius, np.array([step]))
    d, R = cs[0], rotation(float(ys[0]))
    base, along = R @ (face.a - body.c_B), face.length * (R @ face.t)
    lever = along[0] * d[1] - along[1] * d[0]
    if abs(lever) < 1e-12:
        return share
    u = (body.radius**2 * float(ys[0]) - (base[0] * d[1] - base[1] * d[0])) / lever
    return min(1.0, max(0.0, u))


def fit_rank(fit: PosePushes) -> tuple[bool, float]:
    """Within tolerance first, then the least pushing (PUSH_COST per push; or, outside the
    tolerance, the closest)."""
    return (not fit.within,
            fit.total_length + PUSH_COST * len(fit.faces) if fit.within else fit.error)
