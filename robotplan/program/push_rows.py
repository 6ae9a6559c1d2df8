"""The functionals of a push program as rows: H_F, H_coll, H_PoC, H_g, the quasi-static
push and the costs (paper eq. 2; :class:`PushRows`)."""

from __future__ import annotations

from functools import partial

import numpy as np
import torch

from robotplan.functionals import Collision, ContactPoint, GoalRegion
from robotplan.functionals.collision import (
    FixedCollision,
    SweptClearance,
    crossing_depth,
    face_contact_overlap,
)
from robotplan.functionals.goal import PoseError
from robotplan.functionals.sticking import (
    PushingDirection,
    PushLever,
    QuasiStaticPush,
    StickingContact,
    centroid,
    turning_radius,
)
from robotplan.geometry.transforms import carry_with_body
from robotplan.program.bridge import bridge, stepwise
from robotplan.program.dynamics_rows import DynamicsRows
from robotplan.program.row_table import RowSpec
from robotplan.program.settings import ProgramSettings
from robotplan.scene.bodies import Body

__all__ = ["ROW_BUILDERS", "PushRows", "region_goal"]

ROW_BUILDERS = {  # a row of skeletons/rows.yaml → the PushRows method that adds it
    "hold_object": "_hold_object_while_reaching",
    "H_F": "_row_dynamics",
    "step_limits": "_row_step_limits",
    "friction_cone": "_row_friction_cone",
    "sticking": "_add_sticking",
    "pushing": "_add_pushing",
    "quasi_static": "_row_quasi_static",
    "object_motion": "_row_object_motion",
    "H_coll": "_add_collision",
    "swept": "_add_swept",
    "H_coll_obstacles": "_add_obstacle_collision",
    "H_PoC": "_add_contact",
    "goal": "_add_region_goal",
    "H_pose": "_add_pose_goal",
    "H_touch": "_add_touch_goal",
    "acceleration": "_add_costs",
    "lever": "_add_lever_cost",
}


def region_goal(body: Body, region: Body, settings: ProgramSettings) -> GoalRegion:
    """H_g of ``body`` in the goal ``region`` as the program's goal row has it: the region
    shrunk by ``goal.inset`` (at most a third of the room the body has at its centre), so
    that a plan ends deeper inside and tolerates execution error; the row bounds H_g over
    the body's area by ``goal.tol``."""
    origin = torch.zeros(1, 2, dtype=torch.float64)
    extent = np.ptp(body.shape.outline(), axis=0).max() / 2
    room = -float(region.shape.sdf(origin)[0]) - extent
    inset = min(settings.row("goal").inset, max(0.0, room / 3))
    return GoalRegion(body, region, a=settings.row("goal").a, inset=inset)


class PushRows(DynamicsRows):
    """The rows of one pushed object (``obj``, poses ``Q1``) and one actor (``pusher``,
    positions ``Q2``), contact points ``P`` in push steps."""

    def add_row(self, spec: RowSpec) -> None:
        """Add the row ``spec`` of the table (``skeletons/rows.yaml``) to the program."""
        getattr(self, ROW_BUILDERS[spec.row])(spec)

    def _row_step_limits(self, spec: RowSpec) -> None:
        """The kinematic stage's step limits (the row's ``step`` and ``turn``)."""
        limits = self.settings.row("step_limits")
        self._add_step_limits(limits.step, limits.turn)

    def _row_friction_cone(self, spec: RowSpec) -> None:
        """The learned stage's quasi-static rows: the cone, the turning law with
        ``friction_cone.turn``."""
        if self.settings.row("quasi_static").friction > 0 and len(self.push_steps):
            self._add_quasi_static(turn=self.settings.row("friction_cone").turn, scale=spec.scale)

    def _row_quasi_static(self, spec: RowSpec) -> None:
        if len(self.push_steps) and self.settings.row("quasi_static").friction > 0:
            self._add_quasi_static(turn=True, scale=spec.scale)

    def _row_object_motion(self, spec: RowSpec) -> None:
        self._add_motion_cost(self.Q1)

    def _hold_object_while_reaching(self, spec: RowSpec) -> None:
        """A reach phase moves the pusher without touching (H_coll keeps it off), so the
        object stays where it is: q_obj,t = q_obj,t−1 in reach steps. Without this, the
        cost on H_F alone lets the optimiser drift the object a few mm per step."""
        T = self.T
        for k, ph in enumerate(self.skeleton.phases):
            if ph.mode != "reach":
                continue
            for t in range(k * T + 1, (k + 1) * T + 1):
                self._hold(self.Q1, t)

    def _clear_overlap(self) -> float:
        """H_coll of the actor ``H_coll.clearance`` off a face (m²)."""
        s = self.settings
        return face_contact_overlap(self.pusher, s.row("H_coll").a, -s.row("H_coll").clearance)

    def _add_collision(self, spec: RowSpec) -> None:
        """H_coll in every step: at most a pressed-in face contact in push steps, and
        ``H_coll.clearance`` of free space in the other steps (the pusher follows straight
        lines between the planned points; brushing the object on the way turns it)."""
        k, coll = spec.scale, self.settings.row("H_coll")
        H = Collision(self.obj, self.pusher, a=coll.a)
        touch = max(coll.contact_area,
                    face_contact_overlap(self.pusher, coll.a, coll.contact_depth))
        ub = np.full(self.N, self._clear_overlap())
        ub[self.push_steps - 1] = touch
        if self.task.goal == "touch":
            ub[-1] = touch  # the touch goal's last state is a contact, not a reach
        self._add_rows(H, [self.Q1[1:], self.Q2[1:]], 1, k, (0.0, ub * k), spec.row)

    def _add_swept(self, spec: RowSpec) -> None:
        """Along each free move of a free pusher, its gap to the object at a few points (and
        after the solve at points ``swept.check_spacing`` apart: :meth:`swept_shortfall`)."""
        s, scale = self.settings, spec.scale
        pushing = set(self.push_steps.tolist())
        free = np.array([t for t in range(1, self.N + 1) if t not in pushing], dtype=int)
        if self.planar_pusher and s.row("swept").samples > 0 and len(free):
            self._swept_check = (free, scale)
            # the object holds still in these steps (hold_object.active): its pose at t
            k = s.row("swept").samples
            self._add_rows(SweptClearance(self.obj, self.pusher, k),
                           [self.Q1[free], self.Q2[free - 1], self.Q2[free]], k, scale,
                           (-scale * s.row("swept").tolerance, np.inf), spec.row)

    def swept_shortfall(self, q_obj: np.ndarray, q_pusher: np.ndarray) -> float:
        """How far (in the swept row's scaled units) the plan's moves cross the object, at
        points ``swept.check_spacing`` apart: free moves beyond ``swept.check_depth`` (the
        row's samples miss it in long moves), push steps' moves seen from the object beyond
        ``swept.push_check_depth`` (rows hold at their end states only). 0 without the row."""
        check = getattr(self, "_swept_check", None)
        s = self.settings
        if check is None or s.row("swept").check_spacing is None:
            return 0.0
        free, scale = check
        q1, q2 = torch.from_numpy(q_obj), torch.from_numpy(q_pusher[:, :2])
        depth = partial(crossing_depth, self.obj, self.pusher, spacing=s.row("swept").check_spacing,
                        samples=s.row("swept").samples)
        beyond = depth(q1[free], q2[free - 1], q2[free]) - s.row("swept").check_depth
        push = self.push_steps
        if len(push):
            start = carry_with_body(q2[push - 1, None], q1[push - 1], q1[push])[:, 0]
            beyond = max(beyond, depth(q1[push], start, q2[push]) - s.row("swept").push_check_depth)
        return scale * max(0.0, beyond)

    def _add_obstacle_collision(self, spec: RowSpec) -> None:
        """H_coll of the object and of the actor with every obstacle, in every step."""
        a, k = self.settings.row("H_coll").a, spec.scale
        overlap = self.settings.row("H_coll_obstacles").overlap
        for obstacle in self.scene.obstacles:
            wall = self.scene.bodies[obstacle.name]
            self._add_rows(FixedCollision(self.obj, wall, a), [self.Q1[1:]], 1, k,
                           (0.0, overlap * k), f"H_coll_{obstacle.name}")
            self._add_rows(FixedCollision(self.pusher, wall, a), [self.Q2[1:]], 1, k,
                           (0.0, self._clear_overlap() * k), f"H_coll_{obstacle.name}_pusher")

    def _add_contact(self, spec: RowSpec) -> None:
        if len(self.push_steps):
            H = ContactPoint(self.obj, self.pusher)
            steps = self.push_steps
            self._add_rows(H, [self.Q1[steps], self.Q2[steps], self.P], 2, spec.scale, (0.0,
                           0.0), spec.row)

    def _add_lever_cost(self, spec: RowSpec) -> None:
        """``lever.weight`` · Σ (lever arm in cm)² over push steps (see PushLever)."""
        w = self.settings.row("lever").weight
        if w <= 0 or not len(self.push_steps):
            return
        H = PushLever(centroid(self.obj.shape.outline()))
        steps = self.push_steps
        fn, variables = stepwise(H, [self.Q1[steps], self.Q2[steps], self.P], spec.scale)

        def total(x: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
            r, J = fn(x, jac)
            return np.array([w * r @ r]), None if J is None else (2 * w * r @ J)[None]

        self._add_cost(total, variables, spec.row)

    def _add_quasi_static(self, turn: bool, scale: float) -> None:
        """QuasiStaticPush rows in every push step: the friction cone, and with ``turn`` the
        limit surface's turning rate (the kinematic stage, and the learned stage with
        ``friction_cone.turn``; otherwise the learned stage keeps the cone only and H_F alone
        decides how the object turns)."""
        c_B = centroid(self.obj.shape.outline())
        radius = turning_radius(self.obj.shape, self.settings.row("quasi_static").turn_gain)
        H = QuasiStaticPush(c_B, radius, self.settings.row("quasi_static").friction, turn=turn)
        k = self.push_steps
        self._add_quasi_static_rows(H, [self.Q1[k - 1], self.Q1[k], self.Q2[k], self.P],
                                    scale=scale)

    def _add_quasi_static_rows(self, H: QuasiStaticPush, blocks: list[np.ndarray],
                               suffix: str = "", *, scale: float) -> None:
        """``H``'s rows on ``blocks``: [turn (= 0)], cone edge, cone edge (≥ 0), at
        ``scale`` (the table's: cm)."""
        m = 3 if H.turn else 2
        lb, ub = np.zeros((1, m)), np.full((1, m), np.inf)
        if H.turn:
            ub[0, 0] = 0.0
        self._add_rows(H, blocks, m, scale, (lb, ub),
                       ("quasi_static" if H.turn else "friction_cone") + suffix)

    def _add_sticking(self, spec: RowSpec) -> None:
        """The kinematic stand-in for H_F: the contact point sticks to the object between
        consecutive push steps of a phase."""
        steps = list(self.push_steps)
        pairs = [(i - 1, i) for i in range(1, len(steps)) if steps[i] == steps[i - 1] + 1
                 and (steps[i] - 1) % self.T != 0]
        if pairs:
            a, b = np.array(pairs).T
            ta, tb = self.push_steps[a], self.push_steps[b]
            self._add_rows(StickingContact(), [self.Q1[ta], self.P[a], self.Q1[tb], self.P[b]],
                           2, spec.scale, (0.0, 0.0), spec.row)

    def _add_pushing(self, spec: RowSpec) -> None:
        """In push steps the actor moves into the contact point."""
        if len(self.push_steps):
            self._add_rows(PushingDirection(), [self.Q2[self.push_steps - 1],
                                                self.Q2[self.push_steps], self.P],
                           1, spec.scale, (0.0, np.inf), spec.row)

    def _add_touch_goal(self, spec: RowSpec) -> None:
        """The touching tip is the last phase's actor; it ends on the object (H_PoC)."""
        self.P_touch = self.prog.NewContinuousVariables(1, 2, "p_touch")
        H = ContactPoint(self.obj, self.scene.bodies[self.task.touch_actor])
        self._add_rows(H, [self.Q1[-1:], self.Q2[-1:], self.P_touch], 2, spec.scale,
                       (0.0, 0.0), spec.row)

    def _add_pose_goal(self, spec: RowSpec) -> None:
        """The object's own footprint at the target pose: each component of the pose error
        within tol/√3, so that at most ``H_pose.tol`` of the area is off target."""
        outline = self.goal_body.shape.outline()
        H = PoseError(outline, tuple(self.scene.goal.pose))
        k = spec.scale
        bound = k * H.tolerance(outline, self.settings.row("H_pose").tol) / np.sqrt(3)
        self._add_rows(H, [self.goal_Q[self.N:]], 3, k, (-bound, bound), spec.row)

    def _add_region_goal(self, spec: RowSpec) -> None:
        """H_g (eq. 8) over the object's area at the last state ≤ ``goal.tol``."""
        if self.region is None:
            return
        body = self.goal_body
        H = region_goal(body, self.region, self.settings)
        scale = spec.scale / body.area

        def fn(x: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
            X = torch.from_numpy(x.reshape(1, 3))
            if not jac:
                return H(X)[:, 0].numpy() * scale, None
            r, (J,) = H.jacobians(X)
            return r[:, 0].numpy() * scale, J[:, 0].numpy() * scale

        self.prog.AddConstraint(bridge(fn, self.timings, "H_g"), np.zeros(1),
                                np.array([spec.scale * self.settings.row("goal").tol]),
                                self.goal_Q[self.N], "H_g")

    def _add_costs(self, spec: RowSpec) -> None:
        def accel_cost(Q: np.ndarray, weight: float, prefix: bool) -> None:
            n = Q.shape[0]
            if n < 2:
                return
            rows = []
            for t in range(0 if prefix else 1, n - 1):  # a_t = q_{t+1} − 2 q_t + q_{t−1}
                r = np.zeros(n)
                r[t + 1] += 1
                r[t] -= 2
                r[max(t - 1, 0)] += 1  # q_{−1} = q_0
                rows.append(r)
            D = np.kron(np.array(rows), np.eye(2))
            self.prog.AddQuadraticCost(2 * weight * D.T @ D, np.zeros(2 * n), Q.ravel(),
                                       is_convex=True)

        accel_cost(self.Q2, self.settings.row("acceleration").actor, prefix=True)
        if len(self.P):
            accel_cost(self.P, self.settings.row("acceleration").contact, prefix=False)
