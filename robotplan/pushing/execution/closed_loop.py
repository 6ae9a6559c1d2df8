"""Closed-loop execution: run a plan step by step in pybullet, observe the scene after each
planned step and re-plan from the observed state when it departs from the plan.

After each planned step t the executor observes every movable object's pose (as a
perception system delivers it: optionally noisy) and the actors' state. It re-plans the
phases not yet finished (:func:`robotplan.pushing.program.tail.solution_tail`, a shrinking
horizon, warm started from the current plan's tail; with ``fresh_after_miss`` a fresh
skeleton search when that does not plan; at a phase's end with ``fresh_beyond_drift`` also
when the object is beyond ``drift`` / ``drift_yaw``) when an object is further than
``drift`` / ``drift_yaw`` from the plan's state t, or further than the tighter
``phase_drift`` / ``phase_drift_yaw`` at the end of a phase; when the plan has run out and
the goal is not met it plans the last push again from the observed scene (unless
``redo_last_push`` is off), then afresh. With ``stop_when_lost``, an
object beyond ``drift`` / ``drift_yaw`` once the re-plans are spent ends the execution.
A re-plan is taken only if its plan is solved (every constraint met, plausible under the
learned dynamics; as a last resort every constraint met is enough: at the plan's end with
``adopt_feasible_at_end``, at a gross phase-end departure with
``last_resort_beyond_drift``); otherwise the current plan goes on, and mid-phase drift
does not trigger another re-plan before the next phase boundary.

The thresholds are :class:`LoopSettings`, with overlays per scene class in
``skeletons/loop.yaml`` (:func:`loop_settings_for`: a chain re-plans from larger departures
at a phase's end).

Between re-plans the acting free pusher or arm may steer (``steer_gain``, off by default
for free pushers): keep the planned push direction and move sideways with the object and
against its turn (:func:`steer_pusher`; an arm's joints follow its tip to first order).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np

from robotplan.execution.physics import PHYSICS, Physics
from robotplan.execution.scene_world import Observation, SceneWorld, actuation
from robotplan.geometry.transforms import wrap_angle
from robotplan.pushing.execution.execute import Execution, outcome, plan_substeps, recorded
from robotplan.pushing.execution.loop_settings import (
    LOOP_CLASSES,
    LoopSettings,
    load_loop_overlays,
    loop_settings_for,
)
from robotplan.pushing.execution.steering import steer_actor, steer_pusher
from robotplan.pushing.program.solution import Solution
from robotplan.pushing.program.tail import solution_tail
from robotplan.pushing.search.planner import adoptable
from robotplan.scene.task import PushTask

__all__ = ["LOOP_CLASSES", "LoopSettings", "Replan", "departure", "execute_closed_loop",
           "load_loop_overlays", "loop_settings_for", "steer_pusher"]


@dataclass
class Replan:
    """One call of the planner during execution."""

    time: float  # s of simulated time at which it was asked
    step: int  # executed steps before it
    reason: str
    solved: bool
    violation: float | None
    seconds: float
    skeleton: str
    # seconds of the best program's stages and functionals (Solution.timings)
    timings: dict | None = None
    # whether the loop went on with it: a solved plan, or as a last resort one that meets
    # the constraints (LoopSettings.adopt_feasible_at_end, last_resort_beyond_drift)
    adopted: bool = False

    def as_dict(self) -> dict:
        out = asdict(self)
        out["time"], out["seconds"] = round(self.time, 4), round(self.seconds, 3)
        return out


Replanner = Callable[[PushTask, "Solution | None", bool, "float | None", "float | None"],
                     object]
"""``replan(observed, tail, fresh, last_resort, deadline)``: a plan of the task in the
observed scene from the current plan's ``tail`` (or None), a fresh search following when the
tail does not solve only if ``fresh``, for a loop that adopts an unsolved plan within the
violation ``last_resort`` (or None), starting nothing after the ``time.monotonic()``
instant ``deadline``; an object with ``best`` (Solution | None) and ``solved``
(robotplan.api.PushPlan)."""


def departure(planned: dict[str, np.ndarray], seen: dict[str, np.ndarray], far: float,
              far_yaw: float) -> str | None:
    """Why the observed poses ``seen`` (name → x, y, yaw) leave the ``planned`` ones: the
    first object off by more than ``far`` m or ``far_yaw`` rad, or None."""
    for name, q in planned.items():
        gap = float(np.hypot(*(seen[name][:2] - q[:2])))
        turn = abs(wrap_angle(float(seen[name][2] - q[2])))
        if gap > far or turn > far_yaw:
            return f"{name} {1000 * gap:.1f} mm / {math.degrees(turn):.1f}° off the plan"
    return None


def _observed(task: PushTask, seen: Observation) -> PushTask:
    """The task in the scene as observed."""
    poses = {name: tuple(p) for name, p in seen.poses.items()}
    if seen.pusher is not None:
        poses[task.actors[0]] = (*seen.pusher, 0.0)
    return task.at(task.scene.with_state(poses, {k: tuple(v) for k, v in seen.joints.items()}))


def _goal_met(task: PushTask, seen: Observation, settings: LoopSettings) -> bool:
    goal_obj, bodies = task.goal_object, task.scene.bodies
    touching = task.touch_actor
    tip = seen.tips[touching][:2] if touching is not None else np.zeros(2)
    radius = bodies[touching].shape.radius if touching is not None else 0.0
    cov, gap = outcome(task, bodies[goal_obj], seen.poses[goal_obj], tip, radius)
    return settings.goal_met(task, cov, gap)


class _Loop:
    """The state of one closed-loop run (see :func:`execute_closed_loop`)."""

    def __init__(self, task: PushTask, sol: Solution, physics: Physics) -> None:
        self.task, self.obj, self.physics = task, task.obj, physics
        self.replans: list[Replan] = []
        self.plans: list[tuple[int, Solution]] = []
        self.executed: list[int] = []  # simulation steps of each executed step
        self.adopt(sol)

    def adopt(self, sol: Solution) -> None:
        self.plan, self.t = sol, 0
        self.drive = actuation(self.task, sol.q_pusher, sol.q_joints)
        self.substeps = plan_substeps(self.task, sol, self.physics)
        self.T = (len(sol.q_obj) - 1) // len(sol.skeleton.phases)
        self.calm_until = 0  # no mid-phase re-plan before this state
        self.plans.append((len(self.executed), sol))

    def planned_poses(self) -> dict[str, np.ndarray]:
        return {self.obj: self.plan.q_obj[self.t],
                **{k: v[self.t] for k, v in self.plan.q_others.items()}}

    def now(self) -> float:
        return sum(self.executed) * self.physics.timestep


def execute_closed_loop(task: PushTask, sol: Solution, replan: Replanner,
                        settings: LoopSettings | None = None, physics: Physics = PHYSICS,
                        observe: Callable[[Observation], Observation] | None = None,
                        report: Callable[[str], None] | None = None,
                        world_of: Callable[[PushTask, Physics], SceneWorld] = SceneWorld
                        ) -> Execution:
    """Execute ``sol`` in ``task.scene`` closing the loop through ``replan`` (see the module
    docstring). ``observe`` turns the true state into the perceived one (default: exact);
    ``report`` gets a line per re-plan. ``settings``: default those of the task's
    classes (:func:`loop_settings_for`). ``world_of(task, physics)``: the world it
    runs in (default pybullet's; :class:`~robotplan.pushing.execution.imagined_world.ImaginedWorld`
    to rehearse the plan in the learned model)."""
    settings = settings or loop_settings_for(task)
    observe = observe or (lambda seen: seen)
    loop = _Loop(task, sol, physics)
    obj, stopped = task.obj, None
    with world_of(task, physics) as world:
        truth = [world.observe()]
        seen = observe(truth[-1])
        command = {k: v[0] for k, v in loop.drive.items()}
        while True:
            if loop.t == len(loop.substeps):
                redo = _last_push(loop) if settings.redo_last_push else None
                if _goal_met(task, seen, settings) or not _ask(
                        loop, seen, redo, "goal not met at the plan's end",
                        replan, settings, report, fresh=True,
                        last_resort=settings.adopt_feasible_at_end):
                    break
                continue
            target = {k: v[loop.t + 1] for k, v in loop.drive.items()}
            if settings.steer_gain:
                steer_actor(world, loop, target, seen.poses[obj], settings)
            world.run_step(command, target, loop.substeps[loop.t])
            loop.executed.append(loop.substeps[loop.t])
            command, loop.t = target, loop.t + 1
            truth.append(world.observe())
            seen = observe(truth[-1])
            if loop.t == len(loop.substeps):
                continue
            at_boundary = loop.t % loop.T == 0
            if not at_boundary and loop.t < loop.calm_until:
                continue
            far, far_yaw = ((settings.phase_drift, settings.phase_drift_yaw) if at_boundary
                            else (settings.drift, settings.drift_yaw))
            reason = departure(loop.planned_poses(), seen.poses, far, far_yaw)
            if reason is not None:
                where = "at the end of a phase" if at_boundary else "mid-phase"
                tail = solution_tail(loop.plan, loop.t)
                # beyond drift / drift_yaw: mid-phase the departure itself
                beyond = departure(loop.planned_poses(), seen.poses, settings.drift,
                                   settings.drift_yaw) if at_boundary else reason
                gross = at_boundary and settings.fresh_beyond_drift and beyond is not None
                if not _ask(loop, seen, tail, f"{reason} {where}", replan, settings,
                            report, fresh=settings.fresh_after_miss or gross,
                            last_resort=settings.last_resort_beyond_drift and gross):
                    if (settings.stop_when_lost and beyond is not None
                            and len(loop.replans) >= settings.max_replans):
                        stopped = f"{beyond} {where} with no re-plans left"
                        if report is not None:
                            report(f"stopped at step {len(loop.executed)}: {stopped}")
                        break
                    loop.calm_until = (loop.t // loop.T + 1) * loop.T
        ex = recorded(task, truth, world.obstacle_contact, sorted(world.forbidden),
                      loop.executed, physics)
    ex.mode, ex.replans, ex.plans, ex.stopped = "closed_loop", loop.replans, loop.plans, stopped
    return ex


def _last_push(loop: _Loop) -> Solution | None:
    """The plan's last reach and push, to be done again from where the object is."""
    phases = loop.plan.skeleton.phases
    if len(phases) < 2 or [p.mode for p in phases[-2:]] != ["reach", "push"]:
        return None
    return solution_tail(loop.plan, (len(phases) - 2) * loop.T)


def _ask(loop: _Loop, seen: Observation, tail: Solution | None, reason: str,
         replan: Replanner, settings: LoopSettings, report, fresh: bool = False,
         last_resort: bool = False) -> bool:
    """Re-plan from ``seen`` (a fresh search after ``tail`` only if ``fresh``); adopt the
    new plan when it is solved or, as a ``last_resort``, when it meets the constraints.
    Whether it was adopted."""
    if len(loop.replans) >= settings.max_replans:
        return False
    t0 = time.perf_counter()
    bound = settings.last_resort_violation if last_resort else None
    wait = settings.replan_deadline
    result = replan(_observed(loop.task, seen), tail, fresh, bound,
                    time.monotonic() + wait if math.isfinite(wait) else None)
    best = getattr(result, "best", None)
    solved = bool(getattr(result, "solved", False)) and best is not None
    adopted = solved or adoptable(best, bound)
    record = Replan(loop.now(), len(loop.executed), reason, solved,
                    float(best.violation) if best is not None else None,
                    time.perf_counter() - t0, best.skeleton.describe() if best else "",
                    dict(best.timings) if best is not None and best.timings else None,
                    adopted)
    loop.replans.append(record)
    if report is not None:
        outcome_text = ("solved" if solved else "meets the constraints, taken as a last resort"
                        if adopted else "not solved: the current plan goes on")
        report(f"re-plan {len(loop.replans)} at step {record.step} ({record.time:.1f} s): "
               f"{reason}; {outcome_text} in {record.seconds:.1f} s")
    if adopted:
        loop.adopt(best)
    return adopted
