"""Execution of a push plan in a simulator (``physics.simulator``, pybullet by default):
open loop as in the paper (§7.2.3), where the actors follow the planned states with
``keep_every`` (20) linear interpolation steps between consecutive ones, at the push data's
time step; the result comes from the simulator alone.

Free moves (reach steps, where the plan holds the object still) are not bound to the
data's speeds in the program and can be long (up to 60 cm a step); squeezed into 20
simulation steps the pusher then moves at ~5 m/s, lags its target by up to 12 cm and clips
the object it was meant to pass. They run at most ``REACH_SPEED`` per kept step instead
(:func:`reach_substeps`); push steps keep the 20 steps of the data."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from robotplan.execution.physics import PHYSICS, Physics
from robotplan.execution.scene_world import Observation, SceneWorld, obstacle_bodies
from robotplan.functionals.coverage import coverage
from robotplan.pushing.program.settings import ARM_PROGRAM_SETTINGS
from robotplan.pushing.program.solution import Solution
from robotplan.scene.task import PushTask

__all__ = ["REACH_SPEED", "STEP_SECONDS", "Execution", "execute_arms", "execute_push",
           "obstacle_bodies", "outcome", "plan_substeps", "reach_substeps", "recorded",
           "run_open_loop"]

REACH_SPEED = 0.03  # m per kept step (20 × 1/240 s) in free moves: the data's top push speed
STEP_SECONDS = PHYSICS.keep_every * PHYSICS.timestep  # a kept step of the push data


@dataclass
class Execution:
    object_poses: np.ndarray  # (M+1, 3) after each executed step
    pusher_positions: np.ndarray  # (M+1, 2)
    final_pose: np.ndarray  # (3,)
    coverage: float | None
    touch_distance: float | None
    tips: dict = field(default_factory=dict)  # robot → (M+1, 3) tip centres
    joints: dict = field(default_factory=dict)  # robot → (M+1, dof) measured joint angles
    obstacle_contact: bool = False  # the object touched an obstacle (within 1 mm) at any step
    others: dict = field(default_factory=dict)  # other object → (M+1, 3) poses
    # objects outside the pusher's ``touches`` that it touched at some simulation step
    forbidden_contacts: list = field(default_factory=list)
    times: np.ndarray | None = None  # (M+1,) s of the executed steps
    mode: str = "open_loop"
    replans: list = field(default_factory=list)  # robotplan.pushing.execution.closed_loop.Replan
    # (step, Solution): the plans executed, each from the executed step it started at
    plans: list = field(default_factory=list)
    # why a closed loop stopped before its plan's end (LoopSettings.stop_when_lost), or None
    stopped: str | None = None
    simulator: str = "pybullet"  # the world it ran in (Physics.simulator)


def reach_substeps(q_pusher: np.ndarray, push_step: np.ndarray, physics: Physics = PHYSICS
                   ) -> list[int]:
    """Simulation steps for each planned step t = 1…N of ``q_pusher (N+1, 2)``:
    ``keep_every`` in push steps (``push_step (N,)`` True), and in free moves enough
    multiples of it that the pusher moves at most ``REACH_SPEED`` per ``keep_every``."""
    moves = np.linalg.norm(np.diff(np.asarray(q_pusher)[:, :2], axis=0), axis=1)
    slow = np.maximum(1, np.ceil(moves / REACH_SPEED - 1e-9)).astype(int)
    return [physics.keep_every * (1 if push else int(k))
            for push, k in zip(push_step, slow, strict=True)]


def plan_substeps(task: PushTask, sol: Solution, physics: Physics = PHYSICS) -> list[int]:
    """Simulation steps of each planned step of ``sol``: a push step as the data
    (``keep_every``); a free pusher's reach step slowed to ``REACH_SPEED``, an arm's
    ``arm_joints.reach_slowdown`` times (the program lets its joints move that much more)."""
    steps = len(sol.q_pusher) - 1
    T = steps // len(sol.skeleton.phases)
    push = np.array([sol.skeleton.phases[t // T].mode == "push" for t in range(steps)])
    if task.arms:
        slow = round(ARM_PROGRAM_SETTINGS.row("arm_joints").reach_slowdown)
        return [physics.keep_every * (1 if p else slow) for p in push]
    return reach_substeps(sol.q_pusher, push, physics)


def run_open_loop(task: PushTask, drive: dict[str, np.ndarray], substeps: list[int],
                  physics: Physics = PHYSICS) -> Execution:
    """Drive the actors along ``drive`` (actor → ``(N+1, d)`` states: the free pusher's
    positions or each arm's joints) open loop, step t over ``substeps[t−1]`` simulation
    steps, with every object of the scene in the world (the task's object first)."""
    with SceneWorld(task, physics) as world:
        seen = [world.observe()]
        for t, n in enumerate(substeps, start=1):
            world.run_step({k: v[t - 1] for k, v in drive.items()},
                           {k: v[t] for k, v in drive.items()}, n)
            seen.append(world.observe())
        return recorded(task, seen, world.obstacle_contact, sorted(world.forbidden),
                        substeps, physics)


def execute_push(task: PushTask, q_pusher: np.ndarray, physics: Physics = PHYSICS,
                 substeps: list[int] | None = None) -> Execution:
    """Run the planned pusher positions ``q_pusher (N+1, 2)`` open loop; coverage is the
    goal object's. Step t takes ``substeps[t−1]`` simulation steps (default
    ``keep_every`` each; see :func:`reach_substeps`)."""
    if substeps is None:
        substeps = [physics.keep_every] * (len(q_pusher) - 1)
    return run_open_loop(task, {task.actors[0]: np.asarray(q_pusher)[:, :2]}, substeps,
                         physics)


def execute_arms(task: PushTask, q_joints: dict[str, np.ndarray],
                 step_substeps: list[int], physics: Physics = PHYSICS) -> Execution:
    """Run planned joint trajectories ``q_joints[robot] (N+1, dof)`` open loop: every arm's
    joint targets move linearly from state t−1 to t over ``step_substeps[t−1]`` simulation
    steps (20 for a push step, as the data)."""
    return run_open_loop(task, {k: np.asarray(v, dtype=float) for k, v in q_joints.items()},
                         step_substeps, physics)


def recorded(task: PushTask, seen: list[Observation], obstacle_contact: bool,
             forbidden: list[str], substeps: list[int], physics: Physics = PHYSICS
             ) -> Execution:
    """The execution of the observed states ``seen`` (one per executed step, the start
    first). ``pusher_positions`` are the free pusher's, or the tips of the arm that touches
    the goal's object last (the touch goal's, else the one nearest at the end)."""
    scene, obj = task.scene, task.obj
    poses = np.array([s.poses[obj] for s in seen])
    others = {name: np.array([s.poses[name] for s in seen])
              for name in seen[0].poses if name != obj}
    tips = {name: np.array([s.tips[name] for s in seen]) for name in seen[0].tips}
    joints = {name: np.array([s.joints[name] for s in seen]) for name in seen[0].joints}
    goal_obj = task.goal_object
    final = seen[-1].poses[goal_obj]
    body = scene.bodies[goal_obj]
    if seen[0].pusher is not None:
        pusher = np.array([s.pusher for s in seen])
        radius = task.pusher.radius
    else:
        last = _last_arm(task, body, final, tips)
        pusher, radius = tips[last][:, :2], scene.bodies[last].shape.radius
    cov, touch = outcome(task, body, final, pusher[-1], radius)
    steps = np.asarray(substeps, dtype=float) * physics.timestep
    return Execution(poses, pusher, poses[-1], cov, touch, tips, joints, obstacle_contact,
                     others, forbidden, np.concatenate(([0.0], np.cumsum(steps))),
                     simulator=physics.simulator)


def _last_arm(task: PushTask, body, final: np.ndarray, tips: dict[str, np.ndarray]) -> str:
    if task.touch_actor is not None:
        return task.touch_actor
    import torch

    gaps = {k: float(body.sdf(torch.tensor(v[-1:, :2]), torch.tensor(final))[0])
            for k, v in tips.items()}
    return min(gaps, key=gaps.get)


def outcome(task: PushTask, body, final: np.ndarray, tip_xy: np.ndarray, radius: float
            ) -> tuple[float | None, float | None]:
    """Coverage of the goal region, or the gap (m) between the touching tip and the object."""
    if task.region is not None:
        return coverage(body, final, task.region), None
    import torch

    gap = body.sdf(torch.tensor(np.asarray(tip_xy, dtype=float)[None]),
                   torch.tensor(np.asarray(final, dtype=float)))
    return None, max(0.0, float(gap[0]) - radius)
