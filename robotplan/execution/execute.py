"""Open-loop execution of a push plan in pybullet (paper §7.2.3): the pusher follows the
planned positions with ``keep_every`` (20) linear interpolation steps between consecutive
ones, in the same world as the push data; the result comes from the simulator alone.

Free moves (reach steps, where the plan holds the object still) are not bound to the
data's speeds in the program and can be long (up to 60 cm a step); squeezed into 20
simulation steps the pusher then moves at ~5 m/s, lags its target by up to 12 cm and clips
the object it was meant to pass. They run at most ``REACH_SPEED`` per kept step instead
(:func:`reach_substeps`); push steps keep the 20 steps of the data."""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np

from robotplan.execution.sim import PHYSICS, Physics, PushWorld
from robotplan.functionals.coverage import coverage
from robotplan.scene import Scene

__all__ = ["REACH_SPEED", "Execution", "execute_arms", "execute_push", "reach_substeps"]

OBSTACLE_GAP = 0.001  # m: closer than this counts as the object touching an obstacle
REACH_SPEED = 0.03  # m per kept step (20 × 1/240 s) in free moves: the data's top push speed


@dataclass
class Execution:
    object_poses: np.ndarray  # (N+1, 3) at the planned steps
    pusher_positions: np.ndarray  # (N+1, 2)
    final_pose: np.ndarray  # (3,)
    coverage: float | None
    touch_distance: float | None
    tips: dict = field(default_factory=dict)  # robot → (N+1, 3) tip centres
    joints: dict = field(default_factory=dict)  # robot → (N+1, dof) measured joint angles
    obstacle_contact: bool = False  # the object touched an obstacle (within 1 mm) at any step
    others: dict = field(default_factory=dict)  # other object → (N+1, 3) poses
    # objects outside the pusher's ``touches`` that it touched at some simulation step
    forbidden_contacts: list = field(default_factory=list)
    times: np.ndarray | None = None  # (N+1,) s of the planned steps, where the caller set them


def obstacle_bodies(scene: Scene) -> list:
    return [(o.shape, o.height, o.pose) for o in scene.obstacles]


def reach_substeps(q_pusher: np.ndarray, push_step: np.ndarray, physics: Physics = PHYSICS
                   ) -> list[int]:
    """Simulation steps for each planned step t = 1…N of ``q_pusher (N+1, 2)``:
    ``keep_every`` in push steps (``push_step (N,)`` True), and in free moves enough
    multiples of it that the pusher moves at most ``REACH_SPEED`` per ``keep_every``."""
    moves = np.linalg.norm(np.diff(np.asarray(q_pusher)[:, :2], axis=0), axis=1)
    slow = np.maximum(1, np.ceil(moves / REACH_SPEED - 1e-9)).astype(int)
    return [physics.keep_every * (1 if push else int(k))
            for push, k in zip(push_step, slow, strict=True)]


def execute_push(scene: Scene, obj: str, pusher: str, q_pusher: np.ndarray,
                 physics: Physics = PHYSICS, substeps: list[int] | None = None) -> Execution:
    """Run the planned pusher positions ``q_pusher (N+1, 2)`` open loop, with every object
    of the scene in the world (``obj`` first); coverage is the goal object's. Step t
    interpolates linearly over ``substeps[t−1]`` simulation steps (default ``keep_every``
    each; see :func:`reach_substeps`)."""
    body, tool = scene.bodies[obj], scene.bodies[pusher]
    spec = next(o for o in scene.objects if o.name == obj)
    others = [o for o in scene.objects if o.name != obj]
    allowed = next(p.touches for p in scene.pushers if p.name == pusher)
    watch = [i for i, o in enumerate(others) if allowed is not None and o.name not in allowed]
    with PushWorld(physics) as world:
        world.reset(body.shape, spec.height, body.pose, tool.shape.radius, tool.pose[:2],
                    obstacle_bodies(scene), [(scene.bodies[o.name].shape, o.height,
                                         scene.bodies[o.name].pose) for o in others])
        poses = [world.object_pose()[0]]
        other_poses = [world.other_poses()]
        pushers = [world.pusher_position()]
        hit, forbidden = False, set()
        if substeps is None:
            substeps = [physics.keep_every] * (len(q_pusher) - 1)
        for (a, b), n in zip(itertools.pairwise(q_pusher), substeps, strict=True):
            for s in range(1, n + 1):
                world.step(tuple(a + (b - a) * s / n))
                hit = hit or world.touches_obstacle(OBSTACLE_GAP)
                forbidden.update(others[i].name for i in watch if world.pusher_touches_other(i))
            poses.append(world.object_pose()[0])
            other_poses.append(world.other_poses())
            pushers.append(world.pusher_position())
    by_name = {o.name: np.array([p[i] for p in other_poses]) for i, o in enumerate(others)}
    goal_obj = getattr(scene.goal, "object", obj)
    final = poses[-1] if goal_obj == obj else by_name[goal_obj][-1]
    cov, touch = _outcome(scene, scene.bodies[goal_obj], final, pushers[-1], tool.shape.radius)
    return Execution(np.array(poses), np.array(pushers), poses[-1], cov, touch,
                     obstacle_contact=hit, others=by_name, forbidden_contacts=sorted(forbidden))


def _outcome(scene: Scene, body, final: np.ndarray, tip_xy: np.ndarray, radius: float
             ) -> tuple[float | None, float | None]:
    """Coverage of the goal region, or the gap (m) between the touching tip and the object."""
    if scene.goal_region is not None:
        return coverage(body, final, scene.goal_region), None
    import torch

    gap = body.sdf(torch.tensor(np.asarray(tip_xy, dtype=float)[None]),
                   torch.tensor(np.asarray(final, dtype=float)))
    return None, max(0.0, float(gap[0]) - radius)


def execute_arms(scene: Scene, obj: str, q_joints: dict[str, np.ndarray],
                 step_substeps: list[int], physics: Physics = PHYSICS) -> Execution:
    """Run planned joint trajectories ``q_joints[robot] (N+1, dof)`` open loop: every arm's
    joint targets move linearly from state t−1 to t over ``step_substeps[t−1]`` simulation
    steps (20 for a push step, as the data). ``pusher_positions`` are the tips of the arm
    that touches the object last (the touch goal's, else the one nearest at the end)."""
    from robotplan.execution.sim_arms import add_arm

    body = scene.bodies[obj]
    spec = next(o for o in scene.objects if o.name == obj)
    with PushWorld(physics) as world:
        world.reset(body.shape, spec.height, body.pose, None, obstacles=obstacle_bodies(scene))
        hit = False
        arms = {r.name: add_arm(world, r) for r in scene.robots}
        poses = [world.object_pose()[0]]
        tips = {name: [arm.tip_position()] for name, arm in arms.items()}
        angles = {name: [arm.joint_angles()] for name, arm in arms.items()}
        for t, substeps in enumerate(step_substeps, start=1):
            for s in range(1, substeps + 1):
                for name, arm in arms.items():
                    a, b = q_joints[name][t - 1], q_joints[name][t]
                    arm.drive(a + (b - a) * s / substeps)
                world.pb.stepSimulation(physicsClientId=world.client)
                hit = hit or world.touches_obstacle(OBSTACLE_GAP)
            poses.append(world.object_pose()[0])
            for name, arm in arms.items():
                tips[name].append(arm.tip_position())
                angles[name].append(arm.joint_angles())
    final = poses[-1]
    tips = {k: np.array(v) for k, v in tips.items()}
    goal = scene.goal
    if goal.type == "touch":
        last = goal.actor
    else:
        import torch

        gaps = {k: float(body.sdf(torch.tensor(v[-1:, :2]), torch.tensor(final))[0])
                for k, v in tips.items()}
        last = min(gaps, key=gaps.get)
    radius = scene.bodies[last].shape.radius
    cov, touch = _outcome(scene, body, final, tips[last][-1, :2], radius)
    return Execution(np.array(poses), tips[last][:, :2], final, cov, touch, tips,
                     {k: np.array(v) for k, v in angles.items()}, hit)
