"""Solving one skeleton: the kinematic program, then the learned one from its solution."""

from __future__ import annotations

import numpy as np

from robotplan.pushing.models.dynamics import PushDynamics
from robotplan.pushing.program.push_program import PushProgram
from robotplan.pushing.program.settings import DEFAULT_SETTINGS, ProgramSettings
from robotplan.pushing.program.skeleton import Skeleton, SkeletonSpace
from robotplan.pushing.program.solution import WARM_USABLE, Solution
from robotplan.scene.task import PushTask

__all__ = ["TURN_LENGTH", "solve_skeleton", "warm_guess"]

TURN_LENGTH = 0.1  # m of travel a radian of turn counts as when a re-anchored plan fades


def solve_skeleton(task: PushTask, skeleton: Skeleton, model: PushDynamics, space: SkeletonSpace,
                   settings: ProgramSettings = DEFAULT_SETTINGS,
                   guess: dict[str, np.ndarray] | None = None) -> Solution:
    """Solve one skeleton: the kinematic program first (``warm_start``), then the learned
    program from its solution; seconds and timings cover both (``"warm_start"``: stage 1).
    A given ``guess`` (an earlier plan of the same skeleton) is repaired by the kinematic
    program (``warm_from_guess``) and starts the learned program, which is not run when
    the start is kept (:func:`_kept_start`); with ``accept_good_start`` neither is a
    start (given, or the kinematic plan) that the learned rows accept. Without
    ``learned_stage`` the kinematic program's solution is the plan."""
    states = len(skeleton.phases) * space.steps_per_phase + 1
    if guess is not None and len(guess["q_obj"]) != states:
        raise ValueError(f"a guess of {len(guess['q_obj'])} states for {skeleton.describe()} "
                         f"at {space.steps_per_phase} steps per phase ({states} states)")
    if not settings.learned_stage:
        return PushProgram(task, skeleton, None, space, settings, guess=guess).solve()
    warm_seconds = 0.0
    given = guess is not None
    learned = start = None  # the learned program of the given start, and that start
    if given and settings.accept_good_start:
        # a start that already meets every row needs no solver: a re-plan's re-anchored
        # plan, or pushes fitted in closed form to the goal
        learned = PushProgram(task, skeleton, model, space, settings, guess=guess)
        start = learned.start_solution()
        kept = _accepted_start(start, settings)
        if kept is not None:
            return kept
    if settings.warm_start and guess is None:
        kin = PushProgram(task, skeleton, None, space, settings)
        warm = kin.solve()
        warm_seconds = warm.seconds
        if warm.violation > WARM_USABLE:
            # not even the kinematics can do it at the data's speeds: the learned program
            # would only wander (measured: docs/experiments.md#warm-usable)
            warm.status = f"kinematic stage infeasible ({warm.status})"
            return warm
        guess = kin.as_guess(warm)
    elif settings.warm_start and guess is not None and settings.warm_from_guess:
        # an earlier plan re-anchored at a moved start: the kinematic program repairs it
        # first, where it can (measured: docs/experiments.md#closed-loop)
        kin = PushProgram(task, skeleton, None, space, settings, guess=guess)
        warm = kin.solve()
        warm_seconds = warm.seconds
        if warm.violation <= WARM_USABLE:
            guess = kin.as_guess(warm)
            learned = start = None  # a repaired start
    if learned is None:
        learned = PushProgram(task, skeleton, model, space, settings, guess=guess)
    sol = None
    if given and (settings.accept_good_start or settings.learned_start_violation is not None):
        sol = _kept_start(start or learned.start_solution(), settings)
    elif settings.accept_good_start:  # the kinematic plan, where the learned rows accept it
        sol = _accepted_start(learned.start_solution(), settings)
    sol = sol or learned.solve()
    if settings.warm_start and warm_seconds:
        sol.seconds += warm_seconds
        sol.timings = {"warm_start": round(warm_seconds, 3), **sol.timings}
    return sol


def _kept_start(start: Solution, settings: ProgramSettings) -> Solution | None:
    """A re-plan's repaired start as its solution, without the learned solve: when the
    learned rows already accept it (``accept_good_start``: every row met, residual at most
    ``good_rms_mm``) or when it misses the constraints by more than
    ``learned_start_violation``, from where the learned stage's few iterations do not get
    (measured: docs/experiments.md#replan-learned-stage). None: run the learned stage."""
    accepted = _accepted_start(start, settings)
    if accepted is not None:
        return accepted
    bound = settings.learned_start_violation
    if bound is not None and start.violation > bound:
        start.status = (f"learned stage not run: its start misses the constraints by "
                        f"{start.violation:.3g} (> {bound:g})")
        return start
    return None


def _accepted_start(start: Solution, settings: ProgramSettings) -> Solution | None:
    """``start`` as the solution when ``accept_good_start`` and it meets every row with a
    learned-dynamics residual of at most ``good_rms_mm``; else None."""
    if (settings.accept_good_start and start.success
            and start.dynamics_rms_mm <= settings.good_rms_mm):
        start.status = (f"learned stage not run: its start meets every row, residual "
                        f"{start.dynamics_rms_mm:.1f} mm")
        return start
    return None


def _carried(points: np.ndarray, centres: np.ndarray, turns: np.ndarray,
             shifts: np.ndarray) -> np.ndarray:
    """``points (n, 2)`` moved with the rigid motions that turn by ``turns (n,)`` about
    ``centres (n, 2)`` and then shift by ``shifts (n, 2)``."""
    c, s = np.cos(turns), np.sin(turns)
    rel = points - centres
    return centres + shifts + np.stack((c * rel[:, 0] - s * rel[:, 1],
                                        s * rel[:, 0] + c * rel[:, 1]), axis=1)


def _step_rows(sol: Solution, chained: bool = False) -> np.ndarray:
    """The state index of each contact row of ``sol`` (its push steps, or its chained
    push steps)."""
    T = (len(sol.q_obj) - 1) // len(sol.skeleton.phases)
    return np.array([k * T + s + 1 for k, ph in enumerate(sol.skeleton.phases)
                     if ph.mode == "push" and (ph.chain is not None or not chained)
                     for s in range(T)], dtype=int)


def warm_guess(task: PushTask, sol: Solution) -> dict[str, np.ndarray]:
    """An earlier solution of a skeleton as the initial guess of its learned program in
    ``task.scene``, whose bodies may have moved since. The rigid motion that takes the earlier
    start of the pushed object to its present pose carries the whole plan (object, actor,
    contact points) at its start and fades out linearly to nothing at its end, so the
    guess starts at the present state and still ends where the earlier plan did. The fade
    follows the object's planned travel (metres, a radian counting ``TURN_LENGTH``), so the
    object still holds where the plan holds it (reach phases)."""
    scene, first = task.scene, sol.skeleton.phases[0]
    now = np.asarray(scene.bodies[first.object].pose, dtype=float)
    moves = np.abs(np.diff(sol.q_obj, axis=0))
    travel = np.concatenate(([0.0], np.cumsum(np.hypot(moves[:, 0], moves[:, 1])
                                              + TURN_LENGTH * moves[:, 2])))
    fade = 1.0 - travel / travel[-1] if travel[-1] > 1e-9 else np.ones(len(travel))
    turn = (now[2] - sol.q_obj[0, 2] + np.pi) % (2 * np.pi) - np.pi
    turns, shifts = fade * turn, fade[:, None] * (now[:2] - sol.q_obj[0, :2])
    centres = sol.q_obj[:, :2]

    def carry(points: np.ndarray, at: np.ndarray) -> np.ndarray:
        return _carried(points, centres[at], turns[at], shifts[at])

    N = len(sol.q_obj) - 1
    every = np.arange(N + 1)
    q_obj = sol.q_obj.copy()
    q_obj[:, :2] = centres + shifts
    q_obj[:, 2] += turns
    q_obj[0] = now
    q_pusher = sol.q_pusher.copy()
    q_pusher[:, :2] = carry(sol.q_pusher[:, :2], every)
    if not task.arms:
        q_pusher[0] = scene.bodies[first.actor].pose[:2]
    rows = _step_rows(sol)
    guess = {"q_obj": q_obj, "q_pusher": q_pusher,
             "p": carry(sol.contact, rows) if len(rows) else sol.contact}
    if sol.touch_point is not None:
        guess["p_touch"] = carry(sol.touch_point, np.array([N]))
    carried = bool(np.abs(shifts[0]).max() > 1e-3 or abs(turn) > 1e-2)
    if sol.q_joints and not carried:  # moved: the arm program solves IK along the new tips
        joints = {name: q.copy() for name, q in sol.q_joints.items()}
        for robot in scene.robots:
            if robot.q0 is not None and robot.name in joints:
                joints[robot.name][0] = robot.q0
        guess["q_joints"] = joints
    for name, q in sol.q_others.items():  # a chained object: moved only by its own offset
        q_chain = q.copy()
        q_chain[0] = scene.bodies[name].pose
        guess.update(q_chain=q_chain, p_chain=sol.contact_others[name])
    return guess
