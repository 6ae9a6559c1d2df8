"""Where one optimisation of the mug-hanging program starts: a uniform random pose in X_h (the
paper's restarts), or a pose threaded on the hook's arm (robotplan's default, with the row
H_thread ≥ 0 of :mod:`robotplan.hanging.functionals.threading`; docs/experiments.md#hang-threading).

A threaded pose puts the centre of the handle's opening on a point of the arm drawn uniformly
along its length (beyond ``THREAD_SKIP`` from the post's axis and ``THREAD_END`` from each
part's ends, where H_thread of that part is ≤ 0), the handle's plane across the
arm there (the mug's y axis along the arm, either way), the mug's axis as near to up as that
allows, then swung about the arm by up to ``THREAD_SWING`` and turned and shifted a little.
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.common.eigen_geometry import AngleAxis
from pydrake.math import RotationMatrix

from robotplan.geometry.transforms import uniform_poses
from robotplan.hanging.program.problem import HANG_DEFAULTS, HangProblem, HangSettings
from robotplan.sdf.mug_hook import Hook, Mug

__all__ = ["start_pose", "threaded_poses", "uniform_starts"]

THREAD_SKIP = 0.03  # m along the arm from the post's axis: the post and the cup need room
THREAD_END = 0.01  # m from a part's ends: the arm's radius and room to cross
THREAD_SWING = math.pi / 4  # rad: the mug swung about the arm, uniform in ±this
THREAD_TURN = 0.1  # rad per axis (Gaussian): a turn of the whole mug
THREAD_SHIFT = 0.004  # m per axis (Gaussian)


def uniform_starts(problem: HangProblem, rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` poses ``(n, 7)`` uniform in X_h (position) and SO(3)."""
    return uniform_poses(rng, (problem.lo + problem.hi) / 2, float(problem.hi[0] - problem.lo[0]),
                         n)


def _turn(axis: np.ndarray, angle: float) -> np.ndarray:
    """The rotation ``(3, 3)`` by ``angle`` (rad) about the unit vector ``axis``."""
    return RotationMatrix(AngleAxis(angle, axis)).matrix()


def threaded_poses(mug: Mug, hook: Hook, rng: np.random.Generator,
                   n: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` mug poses X_HM ``(n, 7)`` threaded on the arm (module docstring) and the arm
    part ``(n,)`` each is threaded on."""
    arm = hook.arm_points()
    parts = np.diff(arm, axis=0)
    lengths = np.linalg.norm(parts, axis=1)
    # the usable stretch of each part, [lo, hi] along it
    lo = np.full(len(lengths), THREAD_END)
    lo[0] = max(THREAD_SKIP, THREAD_END)
    hi = lengths - THREAD_END
    room = np.clip(hi - lo, 0.0, None)
    if room.sum() <= 0:
        raise ValueError("the hook's arm has no stretch to thread a mug on")
    x0, z0, a, _ = mug.opening()
    centre_M = np.array([x0 + (a + mug.radius - x0) / 2, 0.0, z0])  # mid-opening, beyond the wall
    poses, which = [], []
    for _ in range(n):
        k = int(rng.choice(len(room), p=room / room.sum()))
        along = parts[k] / lengths[k]
        y = along * rng.choice((-1.0, 1.0))
        z = np.array([0.0, 0.0, 1.0]) - y[2] * y
        z /= np.linalg.norm(z)
        R = _turn(y, rng.uniform(-THREAD_SWING, THREAD_SWING)) @ np.stack(
            (np.cross(y, z), y, z), axis=1)
        turn = rng.normal(0.0, THREAD_TURN, 3)
        angle = float(np.linalg.norm(turn))
        if angle > 0:
            R = R @ _turn(turn / angle, angle)
        point = arm[k] + rng.uniform(lo[k], lo[k] + room[k]) * along
        position = point - R @ centre_M + rng.normal(0.0, THREAD_SHIFT, 3)
        q = RotationMatrix(R).ToQuaternion()  # w ≥ 0
        poses.append(np.array([*position, q.w(), q.x(), q.y(), q.z()]))
        which.append(k)
    return np.array(poses), np.array(which)


def start_pose(problem: HangProblem, rng: np.random.Generator,
               settings: HangSettings = HANG_DEFAULTS) -> tuple[np.ndarray, int | None]:
    """Where one optimisation starts ``(7,)``, and the arm part it is threaded on (None: not
    threaded, no H_thread row).

    With ``settings.threading``: of ``settings.thread_pool`` threaded poses, the one of least
    H_hang within the collision bound (of least H_coll when none is). Else a uniform random
    pose, or with ``settings.start_pool`` > 1 the pool's pose of least H_hang within the
    collision bound (of least H_hang overall when none is). A pool's evaluations count."""
    if settings.threading:
        pool, parts = threaded_poses(problem.mug, problem.hook, rng, settings.thread_pool)
    else:
        pool, parts = uniform_starts(problem, rng, settings.start_pool), None
        if len(pool) == 1:
            return pool[0], None
    h, c = problem.evaluate(pool)
    threaded = parts is not None
    # a threaded start must clear the hook whatever the program's rows; a uniform one only
    # where the program bounds H_coll
    if threaded or settings.collision != "none":
        clear = c <= settings.collision_bound(threaded)
    else:
        clear = np.ones(len(c), bool)
    # none clear: a threaded start nearest to clearing the hook, a uniform one of least H_hang
    fallback = c if threaded else h
    i = int(np.argmin(np.where(clear, h, np.inf)) if clear.any() else np.argmin(fallback))
    return pool[i], int(parts[i]) if threaded else None
