"""Cheap pruning of an arm skeleton before any program is solved: can each arm reach
where the skeleton's guess needs its tip?"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import torch

from robotplan.functionals.kinematics import arm_kinematics
from robotplan.pushing.program.guess import initial_guess
from robotplan.pushing.program.settings import ARM_PROGRAM_SETTINGS, ProgramSettings
from robotplan.pushing.program.skeleton import Skeleton, SkeletonSpace
from robotplan.pushing.program.variables import StepSets
from robotplan.scene.task import PushTask

__all__ = ["GOAL_GAP_SLACK", "reach_check"]


# m beyond the goal region's inradius that straight face pushes may end from its centre and
# still be tried: turning the object on the way covers that much
# (measured: docs/experiments.md#goal-gap-slack)
GOAL_GAP_SLACK = 0.1


def reach_check(task: PushTask, skeleton: Skeleton, space: SkeletonSpace,
                settings: ProgramSettings = ARM_PROGRAM_SETTINGS, slack: float = 0.03
                ) -> str | None:
    """Cheap pruning before any program is solved: the circle-and-push guess of the
    skeleton, and every state where an arm's tip must be at push height (its pushes, a
    touch goal's end) within that arm's horizontal reach (``robot.yaml``, ± ``slack``).
    Returns why not, or None."""
    scene, T = task.scene, space.steps_per_phase
    first = skeleton.phases[0]
    push_steps = StepSets(skeleton, T).named("push")
    view = SimpleNamespace(task=task, scene=scene, skeleton=skeleton, space=space,
                           settings=settings, T=T, N=T * len(skeleton.phases),
                           obj=scene.bodies[first.object], pusher=scene.bodies[first.actor],
                           region=task.region, push_steps=push_steps)
    guess = initial_guess(view)
    tips = guess["q_pusher"]
    checks: list[tuple[np.ndarray, str]] = []
    pushes = [k for k, ph in enumerate(skeleton.phases) if ph.mode == "push"]
    for k in pushes:
        checks += [(tips[t], skeleton.phases[k].actor) for t in range(k * T, (k + 1) * T + 1)]
    if task.goal == "touch":
        checks.append((tips[-1], skeleton.phases[-1].actor))
    elif pushes:  # the last push ends with its tip behind the object in the goal
        goal = np.array(task.region.pose[:2])
        last = pushes[-1]
        away = goal - guess["q_obj"][last * T, :2]
        away /= max(float(np.linalg.norm(away)), 1e-9)
        behind = goal - away * (view.obj.shape.bound_radius + view.pusher.shape.radius)
        checks.append((behind, skeleton.phases[last].actor))
    robots = {r.name: r for r in scene.robots}
    for point, name in checks:
        robot = robots[name]
        lo, hi = arm_kinematics(robot).model.reach
        dist = float(np.linalg.norm(point - np.array(robot.base[:2])))
        if not lo - slack <= dist <= hi + slack:
            return f"{name} cannot reach {point.round(2).tolist()} ({dist:.2f} m from its base)"
    region = task.region
    if space.init_frame == "object" and region is not None and skeleton.pushes:
        # the guess's straight pushes (from faces, init_frame: object) must end near the goal
        inradius = -float(region.shape.sdf(torch.zeros(1, 2, dtype=torch.float64))[0])
        gap = float(np.linalg.norm(guess["q_obj"][-1, :2] - np.array(region.pose[:2])))
        if gap > inradius + GOAL_GAP_SLACK:
            return f"its pushes end {gap:.2f} m from the goal's centre"
    return None
