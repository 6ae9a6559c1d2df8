"""Solving one skeleton: the kinematic program, then the learned one from its solution."""

from __future__ import annotations

import numpy as np

from robotplan.models.dynamics import PushDynamics
from robotplan.program.arm_program import ArmPushProgram
from robotplan.program.chain_program import ChainPushProgram
from robotplan.program.push_program import PushProgram
from robotplan.program.settings import DEFAULT_SETTINGS, ProgramSettings
from robotplan.program.skeleton import Skeleton, SkeletonSpace
from robotplan.program.solution import WARM_USABLE, Solution
from robotplan.scene import Scene

__all__ = ["program_class", "solve_skeleton", "warm_guess"]


def program_class(scene: Scene, skeleton: Skeleton) -> type[PushProgram]:
    """The program of a scene's actors: arm tips (joints), an object that pushes another
    (a chain), or a free pusher."""
    if scene.robots:
        return ArmPushProgram
    if skeleton.chained:
        return ChainPushProgram
    return PushProgram


def solve_skeleton(scene: Scene, skeleton: Skeleton, model: PushDynamics, space: SkeletonSpace,
                   settings: ProgramSettings = DEFAULT_SETTINGS,
                   guess: dict[str, np.ndarray] | None = None) -> Solution:
    """Solve one skeleton: the kinematic program first (``warm_start``), then the learned
    program from its solution; seconds and timings cover both (``"warm_start"``: stage 1).
    A given ``guess`` (an earlier plan of the same skeleton) starts the learned program
    directly."""
    program = program_class(scene, skeleton)
    warm_seconds = 0.0
    if settings.warm_start and guess is None:
        kin = program(scene, skeleton, None, space, settings)
        warm = kin.solve()
        warm_seconds = warm.seconds
        if warm.violation > WARM_USABLE:
            # not even the kinematics can do it at the data's speeds: the learned program
            # would only wander (measured: docs/experiments.md#warm-usable)
            warm.status = f"kinematic stage infeasible ({warm.status})"
            return warm
        guess = kin.as_guess(warm)
    sol = program(scene, skeleton, model, space, settings, guess=guess).solve()
    if settings.warm_start and warm_seconds:
        sol.seconds += warm_seconds
        sol.timings = {"warm_start": round(warm_seconds, 3), **sol.timings}
    return sol


def warm_guess(scene: Scene, sol: Solution) -> dict[str, np.ndarray]:
    """An earlier solution of a skeleton as the initial guess of its learned program in
    ``scene``, whose bodies may have moved since: every trajectory keeps its shape and
    starts at the scene's present state (state 0 is pinned to it in the program)."""
    first = sol.skeleton.phases[0]
    q_obj = sol.q_obj.copy()
    q_obj[0] = scene.bodies[first.object].pose
    q_pusher = sol.q_pusher.copy()
    if not scene.robots:
        q_pusher[0] = scene.bodies[first.actor].pose[:2]
    guess = {"q_obj": q_obj, "q_pusher": q_pusher, "p": sol.contact}
    if sol.touch_point is not None:
        guess["p_touch"] = sol.touch_point
    if sol.q_joints:
        joints = {name: q.copy() for name, q in sol.q_joints.items()}
        for robot in scene.robots:
            if robot.q0 is not None and robot.name in joints:
                joints[robot.name][0] = robot.q0
        guess["q_joints"] = joints
    for name, q in sol.q_others.items():  # a chained object
        q_chain = q.copy()
        q_chain[0] = scene.bodies[name].pose
        guess.update(q_chain=q_chain, p_chain=sol.contact_others[name])
    return guess
