"""Pushing through another object (paper Fig. 9, appendix C): the pusher may touch only
``obj`` (its ``touches``), and ``obj`` pushes the ``target`` in the skeleton's chained
phases. Both pairs get the same functionals as a single push, the second pair with the
object in the pusher's role.

Besides :class:`~robotplan.program.push_program.PushProgram`'s variables: the target's poses
``q_chain (N+1, 3)`` and, in chained push steps, the contact points ``p_chain (·, 2)``
between ``obj`` and the target. Constraints added:

* the target holds still outside chained push steps;
* H_coll(obj, target) ≤ a pressed-in face contact in every step (they may touch, not pass
  through each other); H_coll(pusher, target) ≤ the free-space level in every step and
  SweptClearance along the pusher's free moves (the pusher never touches the target);
  H_coll(target, obstacle) as for ``obj``;
* H_PoC(obj, target) = 0 at ``p_chain`` in chained push steps;
* kinematic stage: ``p_chain`` sticks to both objects, and the target moves as a
  quasi-static push at ``p_chain`` along its inward normal (QuasiStaticObjectPush);
  learned stage: H_F(target | obj) in every step (the learned model with ``obj``'s SDF as
  φ2), with the same quasi-static rows as the single push keeps (``friction_cone.active``).
"""

from __future__ import annotations

import numpy as np
import torch

from robotplan.functionals import Collision, ContactPoint
from robotplan.functionals.base import sdf_pose_gradients
from robotplan.functionals.collision import FixedCollision, SweptClearance, face_contact_overlap
from robotplan.functionals.sticking import (
    QuasiStaticObjectPush,
    StickingContact,
    turning_radius,
)
from robotplan.models.dynamics import PushDynamics
from robotplan.program.guess import guess_goal, initial_guess
from robotplan.program.push_program import PushProgram
from robotplan.program.settings import DEFAULT_SETTINGS, ProgramSettings
from robotplan.program.skeleton import Skeleton, SkeletonSpace
from robotplan.program.solution import Solution
from robotplan.scene.task import PushTask

__all__ = ["ChainPushProgram", "chain_guess", "objects_touch", "touching_distance"]


class ChainPushProgram(PushProgram):
    """A skeleton with chained push phases (``Phase.chain``) as one nonlinear program."""

    def __init__(self, task: PushTask, skeleton: Skeleton, model: PushDynamics | None,
                 space: SkeletonSpace, settings: ProgramSettings = DEFAULT_SETTINGS,
                 guess: dict[str, np.ndarray] | None = None) -> None:
        super().__init__(task, skeleton, model, space, settings, guess)
        self._add_chain(model)

    # ------------------------------------------------------------------ hooks
    def _add_variables(self) -> None:
        name = self.skeleton.chained
        self.target = self.scene.bodies[name]
        T = self.T
        self.chain_steps = np.array([k * T + s + 1 for k, ph in enumerate(self.skeleton.phases)
                                     if ph.mode == "push" and ph.chain for s in range(T)],
                                    dtype=int)
        self.Q3 = self.prog.NewContinuousVariables(self.N + 1, 3, "q_chain")
        self.P3 = self.prog.NewContinuousVariables(len(self.chain_steps), 2, "p_chain")
        if self.task.goal_object == name:
            self.goal_body, self.goal_Q = self.target, self.Q3

    def _initial_guess(self) -> dict[str, np.ndarray]:
        return chain_guess(self)

    def _guess_pairs(self) -> list[tuple[np.ndarray, np.ndarray]]:
        return [*super()._guess_pairs(), (self.Q3, self.guess["q_chain"]),
                (self.P3, self.guess["p_chain"])]

    def as_guess(self, sol: Solution) -> dict[str, np.ndarray]:
        name = self.target.name
        return {**super().as_guess(sol), "q_chain": sol.q_others[name],
                "p_chain": sol.contact_others[name]}

    def _other_values(self, x: np.ndarray) -> tuple[dict, dict]:
        name = self.target.name
        return ({name: self._values(x, self.Q3)},
                {name: self._values(x, self.P3).reshape(-1, 2)})

    def dynamics_mm2(self, q_obj: np.ndarray, q_pusher: np.ndarray,
                     others: dict | None = None) -> np.ndarray:
        """H_F per step of both pairs, pusher–obj then obj–target (mm²)."""
        first = super().dynamics_mm2(q_obj, q_pusher)
        if self.chain_dynamics is None or not others:
            return first
        return np.concatenate((first, self._residual_mm2(
            self.chain_dynamics, others[self.target.name], q_obj)))

    # ------------------------------------------------------------ constraints
    def _add_chain(self, model) -> None:
        s, prog, N = self.settings, self.prog, self.N
        obj, target, Q1, Q3, P3 = self.obj, self.target, self.Q1, self.Q3, self.P3
        pose = np.array(target.pose, dtype=float)
        prog.AddBoundingBoxConstraint(pose, pose, Q3[0])
        self._bound_to_workspace(Q3[:, :2], P3)
        chained = set(self.chain_steps.tolist())
        for t in range(1, N + 1):  # the target holds still unless obj pushes it
            if t not in chained:
                self._hold(Q3, t)
        # the two objects may touch along a face, pressed in by at most H_coll.contact_depth
        face = min(np.ptp(b.shape.outline(), axis=0).min() for b in (obj, target))
        coll = s.row("H_coll")
        touch = face * (1.0 / coll.a + coll.contact_depth)
        k = self.spec("H_coll_chain").scale  # cm²
        self._add_rows(Collision(obj, target, a=coll.a), [Q1[1:], Q3[1:]], 1, k, (0.0,
                       touch * k), "H_coll_chain")
        clear = face_contact_overlap(self.pusher, coll.a, -coll.clearance)
        k = self.spec("H_coll_pusher_chain").scale
        self._add_rows(Collision(target, self.pusher, a=coll.a), [Q3[1:], self.Q2[1:]], 1,
                       k, (0.0, clear * k), "H_coll_pusher_chain")
        pushing = set(self.push_steps.tolist())
        free = np.array([t for t in range(1, N + 1) if t not in pushing], dtype=int)
        if s.row("swept").samples > 0 and len(free):
            n, k = s.row("swept").samples, self.spec("swept_chain").scale
            self._add_rows(SweptClearance(target, self.pusher, n),
                           [Q3[free], self.Q2[free - 1], self.Q2[free]], n, k,
                           (-k * s.row("swept").tolerance, np.inf), "swept_chain")
        k = self.spec("H_coll_obstacles_chain").scale
        for spec in self.scene.obstacles:
            wall = self.scene.bodies[spec.name]
            self._add_rows(FixedCollision(target, wall, coll.a), [Q3[1:]], 1, k, (0.0,
                           s.row("H_coll_obstacles").overlap * k), f"H_coll_{spec.name}_chain")
        self.chain_dynamics = None
        if not len(self.chain_steps):
            return
        steps = self.chain_steps
        self._add_rows(ContactPoint(obj, target), [Q1[steps], Q3[steps], P3], 2,
                       self.spec("H_PoC_chain").scale, (0.0, 0.0), "H_PoC_chain")  # cm
        if model is None:
            i = np.arange(1, len(steps))
            pairs = i[(steps[i] == steps[i - 1] + 1) & ((steps[i] - 1) % self.T != 0)]
            if len(pairs):
                a, b = steps[pairs - 1], steps[pairs]
                k = self.spec("sticking_chain").scale
                for Q in (Q1, Q3):  # the contact point sticks to both objects
                    self._add_rows(StickingContact(), [Q[a], P3[pairs - 1], Q[b], P3[pairs]], 2,
                                   k, (0.0, 0.0), "sticking_chain")
            self._add_object_push(turn=True, row="quasi_static_chain")
            self._add_motion_cost(Q3)
            return
        self.chain_dynamics = self._add_dynamics(model, (target, Q3), (obj, Q1),
                                                 self.guess["q_chain"], "H_F_chain")
        if s.row("friction_cone").active and s.row("quasi_static").friction > 0:
            self._add_object_push(turn=s.row("friction_cone").turn, row="friction_cone_chain")

    def _add_object_push(self, turn: bool, row: str) -> None:
        """QuasiStaticObjectPush rows of the target at ``p_chain`` in chained push steps, at
        the scale of the table's ``row``."""
        target, k = self.target, self.chain_steps
        push = self.settings.row("quasi_static")
        radius = turning_radius(target.shape, push.turn_gain)
        H = QuasiStaticObjectPush(target, radius, push.friction, turn=turn)
        self._add_quasi_static_rows(H, [self.Q3[k - 1], self.Q3[k], self.P3], "_chain",
                                    scale=self.spec(row).scale)


def _world_outline(body, X: np.ndarray) -> torch.Tensor:
    """``body``'s outline ``(V, 2)`` at the planar pose ``X (3,)``, as a float64 tensor."""
    return torch.as_tensor(body.outline_world(X), dtype=torch.float64)


def objects_touch(a, b, gap: float = 0.002) -> bool:
    """Whether bodies ``a`` and ``b`` at their scene poses come within ``gap`` (m): a vertex
    of one outline within ``gap`` of the other body."""
    Xa, Xb = (np.asarray(body.pose, dtype=float) for body in (a, b))
    return bool(min(float(b.sdf(_world_outline(a, Xa)[None], torch.as_tensor(Xb)[None]).min()),
                    float(a.sdf(_world_outline(b, Xb)[None], torch.as_tensor(Xa)[None]).min()))
                <= gap)


def touching_distance(a, b, X_b: np.ndarray, direction: np.ndarray, yaw_a: float) -> float:
    """How far (m) from ``b``'s origin (pose ``X_b``) along the unit ``direction`` body
    ``a`` (yaw ``yaw_a``) sits when it just touches ``b`` from outside: bisection on the
    outlines' vertices (neither has a vertex inside the other)."""
    Xb = torch.as_tensor(X_b, dtype=torch.float64)[None]
    verts_b = _world_outline(b, X_b)[None]

    def apart(d: float) -> bool:
        X_a = np.array([*(X_b[:2] + d * direction), yaw_a])
        va = _world_outline(a, X_a)[None]
        return bool(b.sdf(va, Xb).min() >= 0
                    and a.sdf(verts_b, torch.as_tensor(X_a)[None]).min() >= 0)

    lo, hi = 0.0, a.shape.bound_radius + b.shape.bound_radius
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if apart(mid) else (mid, hi)
    return hi


def chain_guess(prog: ChainPushProgram) -> dict[str, np.ndarray]:
    """The circle-and-push guess (app. I.2) for a chain: the pushes alone carry ``obj``
    straight towards the target's centre until they touch (a sideways push would turn
    it), the chained pushes carry both on along that line to its point nearest the goal
    (the optimiser bends it where needed); the target moves with ``obj``
    in chained phases; ``p_chain`` is ``obj``'s centre projected onto the target's
    surface."""
    obj, target = prog.obj, prog.target
    s_obj = np.array(obj.pose[:2], dtype=float)
    X_t = np.array(target.pose, dtype=float)
    goal = guess_goal(prog, X_t[:2]) if prog.region is not None else X_t[:2]
    u = X_t[:2] - s_obj
    u = u / max(float(np.linalg.norm(u)), 1e-9)
    # on along the same line, as near the goal as it comes: a push through both objects'
    # centres moves the target within the friction cone without turning it
    travel = max(0.0, float((goal - X_t[:2]) @ u)) * u
    touch = X_t[:2] - touching_distance(obj, target, X_t, -u, obj.pose[2]) * u
    pushes = [ph for ph in prog.skeleton.phases if ph.mode == "push"]
    alone = sum(ph.chain is None for ph in pushes)
    ends, i_alone, i_chain = [], 0, 0
    for ph in pushes:
        if ph.chain is None:
            i_alone += 1
            ends.append(s_obj + (touch - s_obj) * i_alone / alone)
        else:
            i_chain += 1
            ends.append(touch + travel * i_chain / (len(pushes) - alone))
    guess = initial_guess(prog, np.array(ends))
    q1 = guess["q_obj"]
    q3 = np.tile(X_t, (prog.N + 1, 1))
    T = prog.T
    for k, ph in enumerate(prog.skeleton.phases):
        a = k * T
        q3[a + 1:a + T + 1] = q3[a]
        if ph.mode == "push" and ph.chain:
            q3[a + 1:a + T + 1, :2] += q1[a + 1:a + T + 1, :2] - q1[a, :2]
    steps = prog.chain_steps
    p = np.zeros((len(steps), 2))
    if len(steps):
        X = torch.as_tensor(q3[steps], dtype=torch.float64)
        centres = torch.as_tensor(q1[steps, :2], dtype=torch.float64)[:, None, :]
        phi, _, grad = sdf_pose_gradients(target, centres, X)
        n = grad[:, 0] / grad[:, 0].norm(dim=-1, keepdim=True).clamp_min(1e-9)
        p = (centres[:, 0] - phi[:, :1] * n).numpy()
    return {**guess, "q_chain": q3, "p_chain": p}
