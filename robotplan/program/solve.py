"""Solving one skeleton: the kinematic program, then the learned one from its solution."""

from __future__ import annotations

from robotplan.models.dynamics import PushDynamics
from robotplan.program.arm_program import ArmPushProgram
from robotplan.program.chain_program import ChainPushProgram
from robotplan.program.push_program import PushProgram
from robotplan.program.settings import DEFAULT_SETTINGS, ProgramSettings
from robotplan.program.skeleton import Skeleton, SkeletonSpace
from robotplan.program.solution import WARM_USABLE, Solution
from robotplan.scene import Scene

__all__ = ["program_class", "solve_skeleton"]


def program_class(scene: Scene, skeleton: Skeleton) -> type[PushProgram]:
    """The program of a scene's actors: arm tips (joints), an object that pushes another
    (a chain), or a free pusher."""
    if scene.robots:
        return ArmPushProgram
    if skeleton.chained:
        return ChainPushProgram
    return PushProgram


def solve_skeleton(scene: Scene, skeleton: Skeleton, model: PushDynamics, space: SkeletonSpace,
                   settings: ProgramSettings = DEFAULT_SETTINGS) -> Solution:
    """Solve one skeleton: the kinematic program first (``warm_start``), then the learned
    program from its solution; seconds and timings cover both (``"warm_start"``: stage 1)."""
    program = program_class(scene, skeleton)
    guess = None
    warm_seconds = 0.0
    if settings.warm_start:
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
    if settings.warm_start:
        sol.seconds += warm_seconds
        sol.timings = {"warm_start": round(warm_seconds, 3), **sol.timings}
    return sol
