"""Programs over joints (paper app. E): the push program with robot arms as the pushers.

Besides the object poses, every arm's joint angles ``q_<robot> (N+1, dof)`` are decision
variables. The planar pusher variables of
:class:`~robotplan.program.push_program.PushProgram` become the tip of the arm that acts in
each step (the phase's actor): ``FK_xy(q_t) = x_t``
(:class:`~robotplan.functionals.kinematics.TipCoupling`), so H_F, H_coll, H_PoC and the goal
see the tip exactly as they see a free pusher. Per arm and step:

* joint limits (bounds) and joint-velocity limits (linear; reach steps are executed
  ``arm_joints.reach_slowdown`` times slower, so they may move that much more);
* the acting tip at push height in its push phases (and at a touch goal), above the
  table while reaching; an idle arm keeps its tip ``tip_height.idle_lift`` above the objects;
* the flange above the objects' tops and the check links above ``tip_height.link_min``: no link
  but the tip reaches down to the objects or the table;
* with two arms, their check points (tips included) ``arm_separation.gap`` apart (smooth minimum).

Costs: the squared joint steps of every arm, besides the push program's own.
"""

from __future__ import annotations

import numpy as np
import torch

from robotplan.functionals.kinematics import (
    ArmSeparation,
    CheckPointHeights,
    TipCoupling,
    TipHeight,
    arm_kinematics,
    track_tip_path,
)
from robotplan.program.push_program import PushProgram
from robotplan.program.settings import ARM_PROGRAM_SETTINGS, ProgramSettings
from robotplan.program.skeleton import Skeleton, SkeletonSpace
from robotplan.program.solution import Solution
from robotplan.scene import Scene
from robotplan.scene.task import PushTask

__all__ = ["ArmPushProgram", "reach_check"]


# m beyond the goal region's inradius that straight face pushes may end from its centre and
# still be tried: turning the object on the way covers that much
# (measured: docs/experiments.md#goal-gap-slack)
GOAL_GAP_SLACK = 0.1


def objects_top(scene: Scene) -> float:
    return max((o.height for o in (*scene.objects, *scene.obstacles)), default=0.0)


class ArmPushProgram(PushProgram):
    """:class:`PushProgram` whose pushers are the tips of the scene's arms."""

    planar_pusher = False  # a tip may pass over the object while reaching

    def __init__(self, task: PushTask, skeleton: Skeleton, model, space: SkeletonSpace,
                 settings: ProgramSettings = ARM_PROGRAM_SETTINGS,
                 guess: dict[str, np.ndarray] | None = None) -> None:
        scene = task.scene
        self.kin = {r.name: arm_kinematics(r) for r in scene.robots}
        self.QJ: dict[str, np.ndarray] = {}
        super().__init__(task, skeleton, model, space, settings, guess)
        N = self.N
        radii = {scene.bodies[name].shape.radius for name in self.kin}
        if len(radii) > 1:
            raise ValueError("robots: arms with different tip radii are not planned yet")
        self.tip_radius = radii.pop()
        self.actor_of_state = self._actors()
        for name, kin in self.kin.items():
            self.QJ[name] = self.prog.NewContinuousVariables(N + 1, kin.dof, f"q_{name}")
        if "q_joints" not in self.guess:
            self.guess["q_joints"] = self._joint_guess()
        for name in self.kin:
            self._add_arm(name)
        self._limit_tip_steps()
        names = list(self.kin)
        if len(names) == 2:
            a, b = names
            H = ArmSeparation(self.kin[a], self.kin[b])
            k = self.spec("arm_separation").scale  # cm
            self._add_rows(H, [self.QJ[a][1:], self.QJ[b][1:]], 1, k,
                           (settings.row("arm_separation").gap * k, np.inf), "arm_gap")

    # ------------------------------------------------------------ structure
    def _actors(self) -> list[str]:
        """The acting arm of every state (state 0: the first phase's)."""
        T = self.T
        phases = self.skeleton.phases
        return [phases[0].actor] + [phases[(t - 1) // T].actor for t in range(1, self.N + 1)]

    def _push_states(self, name: str) -> list[int]:
        """States where the arm's tip is at push height: its push phases, the state before
        each, and a touch goal's last state."""
        T, out = self.T, set()
        for k, ph in enumerate(self.skeleton.phases):
            if ph.mode == "push" and ph.actor == name:
                out.update(range(k * T, (k + 1) * T + 1))
        if self.task.touch_actor == name:
            out.add(self.N)
        return sorted(t for t in out if t >= 1)

    def _add_arm(self, name: str) -> None:
        kin, s, prog = self.kin[name], self.settings, self.prog
        Q, N, dof = self.QJ[name], self.N, kin.dof
        lower, upper = np.array(kin.model.joint_lower), np.array(kin.model.joint_upper)
        prog.AddBoundingBoxConstraint(np.tile(lower, N + 1), np.tile(upper, N + 1), Q.ravel())
        prog.AddBoundingBoxConstraint(kin.q0, kin.q0, Q[0])
        # joint-velocity limits per step (reach steps run arm_joints.reach_slowdown times longer)
        v = np.array(kin.model.velocity_limits) * s.row("arm_joints").step_seconds
        for t in range(1, N + 1):
            scale = 1.0 if self._is_push_step(t) else s.row("arm_joints").reach_slowdown
            prog.AddLinearConstraint(np.hstack((np.eye(dof), -np.eye(dof))), -v * scale,
                                     v * scale, np.concatenate((Q[t], Q[t - 1])))
            prog.AddQuadraticCost(2 * s.row("arm_joints").weight * np.block(
                [[np.eye(dof), -np.eye(dof)], [-np.eye(dof), np.eye(dof)]]), np.zeros(2 * dof),
                np.concatenate((Q[t], Q[t - 1])), is_convex=True)
        acting = [t for t in range(1, N + 1) if self.actor_of_state[t] == name]
        if acting:
            self._add_rows(TipCoupling(kin), [Q[acting], self.Q2[acting]], 2,
                           self.spec("tip_coupling").scale, (0.0, 0.0), f"tip_{name}")
        r, top = self.tip_radius, objects_top(self.scene)
        height, k = s.row("tip_height"), self.spec("tip_height").scale  # cm
        low = self._push_states(name)
        if low:
            self._add_rows(TipHeight(kin), [Q[low]], 1, k, (r * k, r * k),
                           f"push_height_{name}")
        reaching = [t for t in acting if t not in low]
        if reaching:
            self._add_rows(TipHeight(kin), [Q[reaching]], 1, k, (r * k, np.inf),
                           f"above_table_{name}")
        # idle: lifted over the objects, from the second state after it last acted
        idle = [t for t in range(2, N + 1) if self.actor_of_state[t] != name
                and self.actor_of_state[t - 1] != name]
        if idle:
            self._add_rows(TipHeight(kin), [Q[idle]], 1, k,
                           ((top + height.idle_lift + r) * k, np.inf), f"idle_lift_{name}")
        bounds = np.array([top + height.flange_clearance]
                          + [height.link_min] * (len(kin._frames) - 2))
        self._add_rows(CheckPointHeights(kin), [Q[1:]], len(bounds), k,
                       (bounds[None] * k, np.inf), f"links_{name}")

    def _limit_tip_steps(self) -> None:
        """|Δx| per step and axis of the acting tip ≤ tip_reach.step while reaching and ≤
        the data's speed (``step_limits.step``) while pushing, in both stages: without it the
        learned stage can sweep the tip across the box's face between two planned states
        (measured: docs/experiments.md#tip-reach-step)."""
        D = np.hstack((np.eye(2), -np.eye(2)))
        for t in range(1, self.N + 1):
            if self.actor_of_state[t] != self.actor_of_state[t - 1]:
                continue
            lim = (self.settings.row("step_limits").step if self._is_push_step(t)
                   else self.settings.row("tip_reach").step)
            self.prog.AddLinearConstraint(D, -np.full(2, lim), np.full(2, lim),
                                          np.concatenate((self.Q2[t], self.Q2[t - 1])))

    def _is_push_step(self, t: int) -> bool:
        return self.skeleton.phases[(t - 1) // self.T].mode == "push"

    # ------------------------------------------------------------ guess & solution
    def _joint_guess(self) -> dict[str, np.ndarray]:
        """Inverse kinematics along the guessed tip path of each arm: the planar guess at
        push height in its push states, descending while it reaches; idle, back home."""
        s, N, T = self.settings, self.N, self.T
        top, r = objects_top(self.scene), self.tip_radius
        high = top + s.row("tip_height").idle_lift + r + 0.03
        out = {}
        low_states = {name: set(self._push_states(name)) for name in self.kin}
        for name, kin in self.kin.items():
            targets = np.full((N + 1, 3), np.nan)
            for t in range(1, N + 1):
                if self.actor_of_state[t] != name:
                    continue
                xy = self.guess["q_pusher"][t]
                if t in low_states[name]:
                    targets[t] = (*xy, r)
                else:  # reaching: high first, down to push height at the phase's end
                    u = ((t - 1) % T + 1) / T
                    targets[t] = (*xy, r + (high - r) * (1.0 - u**3))
            targets[0] = np.nan
            for t in range(1, N + 1):  # idle: the home pose's tip
                if np.isnan(targets[t]).all() and self.actor_of_state[t] != name:
                    targets[t] = kin.tip(kin.q0)
            height = s.row("tip_height")
            out[name] = track_tip_path(kin, targets, kin.q0, top + height.flange_clearance,
                                       height.link_min)
        return out

    def _guess_pairs(self) -> list[tuple[np.ndarray, np.ndarray]]:
        pairs = super()._guess_pairs()
        if self.QJ:
            pairs += [(self.QJ[name], self.guess["q_joints"][name]) for name in self.QJ]
        return pairs

    def _joint_values(self, x: np.ndarray) -> dict[str, np.ndarray]:
        return {name: self._values(x, Q) for name, Q in self.QJ.items()}

    def as_guess(self, sol: Solution) -> dict[str, np.ndarray]:
        return {**super().as_guess(sol), "q_joints": sol.q_joints}


def reach_check(task: PushTask, skeleton: Skeleton, space: SkeletonSpace,
                settings: ProgramSettings = ARM_PROGRAM_SETTINGS, slack: float = 0.03
                ) -> str | None:
    """Cheap pruning before any program is solved: the circle-and-push guess of the
    skeleton, and every state where an arm's tip must be at push height (its pushes, a
    touch goal's end) within that arm's horizontal reach (``robot.yaml``, ± ``slack``).
    Returns why not, or None."""
    from types import SimpleNamespace

    from robotplan.program.guess import initial_guess

    scene, T = task.scene, space.steps_per_phase
    first = skeleton.phases[0]
    push_steps = np.array([k * T + s + 1 for k, ph in enumerate(skeleton.phases)
                           if ph.mode == "push" for s in range(T)], dtype=int)
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
