"""The trajectory optimisation of one skeleton as a Drake ``MathematicalProgram`` (paper eq. 2).

Decision variables over N = K·T steps (states 0…N): the planar pose of the pushed object
``q_obj (N+1, 3)``, the pusher position ``q_pusher (N+1, 2)`` and, in push phases, contact
points ``p (·, 2)``. State 0 is the scene's start. Through the fast evaluators, one Python
callback per functional covering every step:

* H_F (learned dynamics, eq. 5) in every step: a cost on the mean squared SDF residual
  (``dynamics_weight``), or a bound on it;
* H_coll (eq. 7) between pusher and object in every step, bounded by what a face contact
  costs in push steps and by ``reach_clearance`` of free space in the other steps; along
  each free move of a free pusher, its gap to the object (SweptClearance) at a few points;
* H_PoC (eq. 9, decision-variable form) in push steps: φ_obj(p) = φ_pusher(p) = 0;
* H_g (eq. 8) at the last state: at most ``goal_tol`` of the object's area outside the goal
  region shrunk by ``goal_inset``;
* the object holds still in reach phases.

Costs: squared accelerations of the pusher and of the contact points, with the prefix
q_{−2} = q_{−1} = q_0, and the lever arm of the push about the object's centroid.

:func:`solve_skeleton` solves in two stages: the kinematic program (``model=None``: sticking
contact and pushing direction instead of H_F, pusher ≤ 3 cm per push step) converges in a
few seconds from the circle-and-push guess; the learned program starts from its solution.
"""

from __future__ import annotations

import time

import numpy as np
import torch
from pydrake.solvers import IpoptSolver, MathematicalProgram, SnoptSolver, SolverOptions

from robotplan.functionals import Collision, ContactPoint, GoalRegion
from robotplan.functionals.collision import FixedCollision, SweptClearance, face_contact_overlap
from robotplan.functionals.dynamics import LearnedDynamics, phase_quadrature
from robotplan.functionals.sticking import (
    CornerClearance,
    PushingDirection,
    PushLever,
    QuasiStaticPush,
    StickingContact,
    centroid,
    convex_corners,
    limit_surface_radius,
)
from robotplan.models.dynamics import PushDynamics
from robotplan.program.bridge import bridge, stepwise, stepwise_sparsity
from robotplan.program.guess import initial_guess
from robotplan.program.settings import DEFAULT_SETTINGS, ProgramSettings
from robotplan.program.skeleton import Skeleton, SkeletonSpace
from robotplan.program.solution import FEASIBLE, SNOPT_MINOR_DEFAULT, WARM_USABLE, Solution, rank
from robotplan.scene import Scene
from robotplan.sdf.footprint import support_corners

__all__ = ["PushProgram"]

class PushProgram:
    """One skeleton of a single-pusher, single-object scene as a nonlinear program."""

    # the pusher moves in the table's plane between its states (a free sphere); an arm's tip
    # moves in 3-D and may pass over the object while reaching (ArmPushProgram)
    planar_pusher = True

    def __init__(self, scene: Scene, skeleton: Skeleton, model: PushDynamics | None,
                 space: SkeletonSpace, settings: ProgramSettings = DEFAULT_SETTINGS,
                 guess: dict[str, np.ndarray] | None = None) -> None:
        """``model=None`` builds the kinematic program (sticking contact and pushing
        direction instead of H_F); ``guess`` replaces the circle-and-push initial guess."""
        self.scene, self.skeleton, self.settings, self.space = scene, skeleton, settings, space
        first = skeleton.phases[0]
        self.obj = scene.bodies[first.object]
        self.pusher = scene.bodies[first.actor]
        self.region = scene.goal_region
        T = space.steps_per_phase
        self.T, self.N = T, T * len(skeleton.phases)
        N = self.N
        self.push_steps = np.array([k * T + s + 1 for k, ph in enumerate(skeleton.phases)
                                    if ph.mode == "push" for s in range(T)], dtype=int)
        self.timings: dict[str, float] = {}  # seconds inside each functional's callback
        prog = self.prog = MathematicalProgram()
        self.Q1 = prog.NewContinuousVariables(N + 1, 3, "q_obj")
        self.Q2 = prog.NewContinuousVariables(N + 1, 2, "q_pusher")
        self.P = prog.NewContinuousVariables(len(self.push_steps), 2, "p")
        self.P_touch: np.ndarray | None = None
        self.goal_body, self.goal_Q = self.obj, self.Q1  # the body H_g moves into the region
        self._add_variables()
        self.guess = guess if guess is not None else self._initial_guess()
        self.keep_start = guess is not None  # a given start is a plan worth keeping
        # state 0 is the scene's start
        prog.AddBoundingBoxConstraint(np.array(self.obj.pose), np.array(self.obj.pose),
                                      self.Q1[0])
        prog.AddBoundingBoxConstraint(np.array(self.pusher.pose[:2]),
                                      np.array(self.pusher.pose[:2]), self.Q2[0])
        self._bound_to_workspace(self.Q1[:, :2], self.Q2, self.P)
        if settings.hold_while_reaching:
            self._hold_object_while_reaching()
        self.dynamics = None
        if model is not None:
            self.dynamics = self._add_dynamics(model, self.obj, self.Q1, self.pusher, self.Q2,
                                               self.guess["q_obj"], "H_F")
            self._add_step_limits(settings.max_step, settings.max_turn)
            if settings.cone_in_learned and settings.push_friction > 0 and len(self.push_steps):
                self._add_quasi_static(turn=settings.turn_in_learned)
        else:
            self._add_kinematic_pushing()
            self._add_step_limits(settings.warm_max_step, settings.warm_max_turn)
        self._add_collision()
        self._add_contact()
        self._add_goal()
        self._add_costs()
        self._add_lever_cost()
        self._add_corner_clearance()

    # ------------------------------------------------------------------ hooks
    def _add_variables(self) -> None:
        """More decision variables, before the guess (none here; see ChainPushProgram)."""

    def _initial_guess(self) -> dict[str, np.ndarray]:
        return initial_guess(self)

    # ------------------------------------------------------------ functionals
    def _add_dynamics(self, model: PushDynamics, obj, Q_obj: np.ndarray, actor,
                      Q_actor: np.ndarray, path: np.ndarray, name: str) -> LearnedDynamics:
        """H_F of ``obj`` (poses ``Q_obj (N+1, 3)``) pushed by ``actor`` (``Q_actor (N+1, 2)``
        positions of a disc, or ``(N+1, 3)`` poses of an object) in every step, integrated
        around ``path (N+1, ≥2)``, the object's guessed centres."""
        s = self.settings
        quad = phase_quadrature(torch.as_tensor(path[:, :2], dtype=torch.float32),
                                obj.shape.bound_radius, self.scene.workspace,
                                coarse=s.quad_coarse)
        dynamics = LearnedDynamics(model, obj, actor, quad)
        N, d = self.N, Q_actor.shape[1]
        area = float(self.scene.workspace.size[0] * self.scene.workspace.size[1])
        scale = 1e6 / area  # H (m²) → mean squared residual in mm²

        def fn(x: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
            X1 = torch.from_numpy(x[:3 * (N + 1)].reshape(N + 1, 3))
            X2 = torch.from_numpy(x[3 * (N + 1):].reshape(N + 1, d))
            H, J1, J2 = dynamics.evaluate(X1, X2, jacobian=jac)
            values = H.double().numpy() * scale
            if not jac:
                return values, None
            J = np.zeros((N, (3 + d) * (N + 1)))
            rows = np.arange(N)
            J1n, J2n = J1.double().numpy() * scale, J2.double().numpy() * scale
            for which in (0, 1):
                states = rows + which
                for k in range(3):
                    J[rows, 3 * states + k] = J1n[:, which, k]
                for k in range(d):
                    J[rows, 3 * (N + 1) + d * states + k] = J2n[:, which, k]
            return values, J

        variables = np.concatenate((Q_obj.ravel(), Q_actor.ravel()))
        if s.dynamics_weight > 0:
            def total(x: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
                values, J = fn(x, jac)
                w = s.dynamics_weight
                return (np.array([w * values.sum()]),
                        None if J is None else w * J.sum(axis=0, keepdims=True))

            self._add_cost(total, variables, name)
            return dynamics
        bound = (s.dynamics_rmse * 1e3) ** 2
        self.prog.AddConstraint(bridge(fn, self.timings, name), np.zeros(N), np.full(N, bound),
                                variables, name)
        return dynamics

    def _hold_object_while_reaching(self) -> None:
        """A reach phase moves the pusher without touching (H_coll keeps it off), so the
        object stays where it is: q_obj,t = q_obj,t−1 in reach steps. Without this, the
        cost on H_F alone let the optimiser drift the object a few mm per step."""
        T = self.T
        for k, ph in enumerate(self.skeleton.phases):
            if ph.mode != "reach":
                continue
            for t in range(k * T + 1, (k + 1) * T + 1):
                self._hold(self.Q1, t)

    def _hold(self, Q: np.ndarray, t: int) -> None:
        """Pose row t of ``Q`` equals row t − 1."""
        d = Q.shape[1]
        self.prog.AddLinearEqualityConstraint(np.hstack((np.eye(d), -np.eye(d))), np.zeros(d),
                                              np.concatenate((Q[t], Q[t - 1])))

    def _bound_to_workspace(self, *arrays: np.ndarray) -> None:
        """Every row ``(x, y)`` of the variable arrays on the table."""
        x0, x1, y0, y1 = self.scene.workspace.bounds
        for Q in arrays:
            if Q.size:
                self.prog.AddBoundingBoxConstraint(np.tile([x0, y0], (Q.shape[0], 1)).ravel(),
                                                   np.tile([x1, y1], (Q.shape[0], 1)).ravel(),
                                                   Q.ravel())

    def _add_motion_cost(self, Q: np.ndarray) -> None:
        """``object_motion_weight`` · Σ_t |Δq_t|² of poses ``Q`` (yaw in ``turn_length`` m)."""
        w = self.settings.object_motion_weight
        scale = np.array([1.0, 1.0, self.settings.turn_length])
        D = np.hstack((np.diag(scale), -np.diag(scale)))
        for t in range(1, self.N + 1):
            self.prog.AddQuadraticCost(2 * w * D.T @ D, np.zeros(6),
                                       np.concatenate((Q[t], Q[t - 1])), is_convex=True)

    def _add_step_limits(self, max_step: float | None, max_turn: float | None) -> None:
        """Pusher travel per push step and axis ≤ ``max_step`` (the speeds of the push data)
        and object rotation per push step ≤ ``max_turn``. Reach steps move through free space
        and are not limited."""

        def differences(Q: np.ndarray, limits: list[float]) -> None:
            d, n = len(limits), len(self.push_steps)
            D = np.zeros((d * n, d * (self.N + 1)))
            for i, t in enumerate(self.push_steps):
                for k in range(d):
                    D[d * i + k, d * t + k], D[d * i + k, d * (t - 1) + k] = 1.0, -1.0
            lim = np.tile(limits, n)
            self.prog.AddLinearConstraint(D, -lim, lim, Q.ravel())

        if len(self.push_steps) and max_step is not None:
            differences(self.Q2, [max_step] * 2)
        if len(self.push_steps) and max_turn is not None:
            differences(self.Q1[:, 2:], [max_turn])

    def _add_rows(self, H, blocks: list[np.ndarray], m: int, scale: float,
                  lb: float | np.ndarray, ub: float | np.ndarray, name: str) -> None:
        """Constraint lb ≤ scale · H(row t) ≤ ub (m residuals each) for every row t of the
        variable blocks; bounds are scalars, one per row ``(n,)`` or one per residual
        ``(1, m)``."""
        fn, variables = stepwise(H, blocks, scale)
        n = blocks[0].shape[0]
        lb, ub = (np.broadcast_to(b[:, None] if b.ndim == 1 else b, (n, m)).ravel()
                  for b in (np.asarray(lb, dtype=float), np.asarray(ub, dtype=float)))
        binding = self.prog.AddConstraint(bridge(fn, self.timings, name), lb, ub, variables,
                                          name)
        if self.settings.sparse_jacobians:
            binding.evaluator().SetGradientSparsityPattern(stepwise_sparsity(fn, m))

    def _add_cost(self, total, variables: np.ndarray, name: str) -> None:
        """A scalar cost ``total(x, jac) → ((1,), J (1, n) | None)`` on ``variables``."""
        bridged = bridge(total, self.timings, name)
        self.prog.AddCost(lambda x: bridged(x)[0], variables, description=name)

    def _add_collision(self) -> None:
        """H_coll in every step: at most a pressed-in face contact in push steps, and
        ``reach_clearance`` of free space in the other steps (the pusher follows straight
        lines between the planned points; brushing the object on the way turned it)."""
        s = self.settings
        H = Collision(self.obj, self.pusher, a=s.a_coll)
        touch = max(s.coll_area, face_contact_overlap(self.pusher, s.a_coll, s.coll_depth))
        clear = face_contact_overlap(self.pusher, s.a_coll, -s.reach_clearance)
        ub = np.full(self.N, clear)
        ub[self.push_steps - 1] = touch
        if self.scene.goal.type == "touch":
            ub[-1] = touch  # the touch goal's last state is a contact, not a reach
        self._add_rows(H, [self.Q1[1:], self.Q2[1:]], 1, 1e4, 0.0, ub * 1e4,
                       "H_coll")  # in cm²
        pushing = set(self.push_steps.tolist())
        free = np.array([t for t in range(1, self.N + 1) if t not in pushing], dtype=int)
        if self.planar_pusher and s.swept_samples > 0 and len(free):
            # the object holds still in these steps (hold_while_reaching): its pose at t
            k = s.swept_samples
            self._add_rows(SweptClearance(self.obj, self.pusher, k),
                           [self.Q1[free], self.Q2[free - 1], self.Q2[free]], k, 100,
                           -100 * s.swept_tolerance, np.inf, "swept")  # cm
        for spec in self.scene.obstacles:
            wall = self.scene.bodies[spec.name]
            self._add_rows(FixedCollision(self.obj, wall, s.a_coll), [self.Q1[1:]], 1, 1e4,
                           0.0, s.obstacle_overlap * 1e4, f"H_coll_{spec.name}")
            self._add_rows(FixedCollision(self.pusher, wall, s.a_coll), [self.Q2[1:]], 1, 1e4,
                           0.0, clear * 1e4, f"H_coll_{spec.name}_pusher")

    def _add_contact(self) -> None:
        if len(self.push_steps):
            H = ContactPoint(self.obj, self.pusher)
            steps = self.push_steps
            self._add_rows(H, [self.Q1[steps], self.Q2[steps], self.P], 2, 100, 0.0, 0.0,
                           "H_PoC")  # cm

    def _add_lever_cost(self) -> None:
        """``lever_weight`` · Σ (lever arm in cm)² over push steps (see PushLever)."""
        w = self.settings.lever_weight
        if w <= 0 or not len(self.push_steps):
            return
        H = PushLever(centroid(self.obj.shape.outline()))
        steps = self.push_steps
        fn, variables = stepwise(H, [self.Q1[steps], self.Q2[steps], self.P], 100.0)

        def total(x: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
            r, J = fn(x, jac)
            return np.array([w * r @ r]), None if J is None else (2 * w * r @ J)[None]

        self._add_cost(total, variables, "lever")

    def _add_corner_clearance(self) -> None:
        """|p_B − corner| ≥ corner_clearance in every push step (see CornerClearance)."""
        if self.settings.corner_clearance <= 0 or not len(self.push_steps):
            return
        outline = self.obj.shape.outline()
        corners = convex_corners(outline)
        if not len(corners):
            return
        edges = np.linalg.norm(np.roll(outline, -1, axis=0) - outline, axis=1)
        shorter_face = np.minimum(edges, np.roll(edges, 1))[corners]  # the faces at a corner
        bound = np.minimum(self.settings.corner_clearance, shorter_face / 3)
        self._add_rows(CornerClearance(outline[corners]), [self.Q1[self.push_steps], self.P],
                       len(corners), 100, 100 * bound[None], np.inf, "corner")  # cm

    def _add_quasi_static(self, turn: bool) -> None:
        """QuasiStaticPush rows in every push step: the friction cone, and with ``turn`` the
        limit surface's turning rate (the kinematic stage, and the learned stage with
        ``turn_in_learned``; otherwise the learned stage keeps the cone only and H_F alone
        decides how the object turns)."""
        c_B = centroid(self.obj.shape.outline())
        radius = limit_surface_radius(support_corners(self.obj.shape), c_B)
        H = QuasiStaticPush(c_B, radius, self.settings.push_friction, turn=turn)
        k = self.push_steps
        self._add_quasi_static_rows(H, [self.Q1[k - 1], self.Q1[k], self.Q2[k], self.P])

    def _add_quasi_static_rows(self, H: QuasiStaticPush, blocks: list[np.ndarray],
                               suffix: str = "") -> None:
        """``H``'s rows on ``blocks``: [turn (= 0)], cone edge, cone edge (≥ 0), in cm."""
        m = 3 if H.turn else 2
        lb, ub = np.zeros((1, m)), np.full((1, m), np.inf)
        if H.turn:
            ub[0, 0] = 0.0
        self._add_rows(H, blocks, m, 100, lb, ub,
                       ("quasi_static" if H.turn else "friction_cone") + suffix)

    def _add_kinematic_pushing(self) -> None:
        """The kinematic stand-in for H_F: in push steps the contact point sticks to the
        object and the pusher moves into it; the object's travel is a small cost."""
        steps = list(self.push_steps)
        pairs = [(i - 1, i) for i in range(1, len(steps)) if steps[i] == steps[i - 1] + 1
                 and (steps[i] - 1) % self.T != 0]
        if pairs:
            a, b = np.array(pairs).T
            ta, tb = self.push_steps[a], self.push_steps[b]
            self._add_rows(StickingContact(), [self.Q1[ta], self.P[a], self.Q1[tb], self.P[b]],
                           2, 100, 0.0, 0.0, "sticking")
        if steps:
            self._add_rows(PushingDirection(), [self.Q2[self.push_steps - 1],
                                                self.Q2[self.push_steps], self.P],
                           1, 100, 0.0, np.inf, "pushing")
        if steps and self.settings.push_friction > 0:
            self._add_quasi_static(turn=True)
        self._add_motion_cost(self.Q1)

    def _add_goal(self) -> None:
        if self.scene.goal.type == "touch":
            # the touching tip is the last phase's actor; it ends on the object (H_PoC)
            self.P_touch = self.prog.NewContinuousVariables(1, 2, "p_touch")
            H = ContactPoint(self.obj, self.scene.bodies[self.scene.goal.actor])
            self._add_rows(H, [self.Q1[-1:], self.Q2[-1:], self.P_touch], 2, 100, 0.0, 0.0,
                           "H_touch")  # cm
            return
        if self.region is None:
            return
        origin = torch.zeros(1, 2, dtype=torch.float64)
        body = self.goal_body
        extent = np.ptp(body.shape.outline(), axis=0).max() / 2
        room = -float(self.region.shape.sdf(origin)[0]) - extent
        inset = min(self.settings.goal_inset, max(0.0, room / 3))
        H = GoalRegion(body, self.region, a=self.settings.a_goal, inset=inset)
        scale = 1.0 / body.area

        def fn(x: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
            X = torch.from_numpy(x.reshape(1, 3))
            if not jac:
                return H(X)[:, 0].numpy() * scale, None
            r, (J,) = H.jacobians(X)
            return r[:, 0].numpy() * scale, J[:, 0].numpy() * scale

        self.prog.AddConstraint(bridge(fn, self.timings, "H_g"), np.zeros(1),
                                np.array([self.settings.goal_tol]),
                                self.goal_Q[self.N], "H_g")

    def _add_costs(self) -> None:
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

        accel_cost(self.Q2, self.settings.accel_weight, prefix=True)
        if len(self.P):
            accel_cost(self.P, self.settings.contact_accel_weight, prefix=False)

    # ------------------------------------------------------------------ solve
    def solve(self) -> Solution:
        s = self.settings
        prog = self.prog
        for V, value in self._guess_pairs():
            if V.size:
                prog.SetInitialGuess(V, value)
        iterations = s.iterations if self.dynamics is not None else s.warm_iterations
        opts = SolverOptions()
        if s.solver == "snopt":
            solver = SnoptSolver()
            opts.SetOption(solver.id(), "Major optimality tolerance", s.optimality_tol)
            opts.SetOption(solver.id(), "Major feasibility tolerance", s.feasibility_tol)
            opts.SetOption(solver.id(), "Major iterations limit", iterations)
            rows = sum(b.evaluator().num_constraints() for b in prog.GetAllConstraints())
            opts.SetOption(solver.id(), "Iterations limit",
                           max(SNOPT_MINOR_DEFAULT, s.minor_iterations_per_row * rows))
        else:
            solver = IpoptSolver()
            opts.SetOption(solver.id(), "tol", s.optimality_tol)
            opts.SetOption(solver.id(), "acceptable_tol", 10 * s.optimality_tol)
            opts.SetOption(solver.id(), "max_iter", iterations)
        t0 = time.perf_counter()  # the clock of the per-functional timings
        result = solver.Solve(prog, None, opts)
        seconds = time.perf_counter() - t0
        status = self._status(result)
        x = result.GetSolution(prog.decision_variables())
        violations, cost = self._evaluate_untimed(x)
        for _ in range(s.warm_restarts if self.dynamics is None else 0):
            worst = max(violations.values(), default=0.0)
            if not s.warm_restart_above < worst <= WARM_USABLE:  # done, or hopeless
                break
            prog.SetInitialGuess(prog.decision_variables(), x)
            t1 = time.perf_counter()
            again = solver.Solve(prog, None, opts)
            seconds += time.perf_counter() - t1
            x2 = again.GetSolution(prog.decision_variables())
            v2, c2 = self._evaluate_untimed(x2)
            tie = s.warm_restart_above
            if rank(v2, c2, tie) < rank(violations, cost, tie):
                x, violations, cost = x2, v2, c2
                status += f", restarted: {self._status(again)}"
        timings = self._timing_report(seconds)
        if self.keep_start:
            # SNOPT returns its last iterate; from a warm start the start itself may be better
            start = prog.GetInitialGuess(prog.decision_variables())
            start_violations, start_cost = self.evaluate(start)
            if rank(start_violations, start_cost) < rank(violations, cost):
                x, violations, cost = start, start_violations, start_cost
                status += ", kept the start"
        q1, q2, p = (self._values(x, V) for V in (self.Q1, self.Q2, self.P))
        violation = max(violations.values(), default=0.0)
        touch = None if self.P_touch is None else self._values(x, self.P_touch)
        others, contacts = self._other_values(x)
        return Solution(self.skeleton, violation <= FEASIBLE, status, violation, cost, seconds,
                        q1, q2, p.reshape(-1, 2), self.dynamics_mm2(q1, q2, others), timings,
                        violations, self._joint_values(x), touch, others, contacts)

    def _guess_pairs(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """(variables, initial values) for SetInitialGuess."""
        pairs = [(self.Q1, self.guess["q_obj"]), (self.Q2, self.guess["q_pusher"]),
                 (self.P, self.guess["p"])]
        if self.P_touch is not None:
            pairs.append((self.P_touch, self.guess.get("p_touch", self.guess["q_pusher"][-1:])))
        return pairs

    def _other_values(self, x: np.ndarray) -> tuple[dict, dict]:
        """Other objects' poses and contact points by name (see ChainPushProgram)."""
        return {}, {}

    def _joint_values(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """Joint trajectories by robot (none for free pushers; see ArmPushProgram)."""
        return {}

    def _values(self, x: np.ndarray, V: np.ndarray) -> np.ndarray:
        """The entries of the full decision vector ``x`` for the variable array ``V``."""
        return x[self.prog.FindDecisionVariableIndices(V.ravel())].reshape(V.shape)

    def as_guess(self, sol: Solution) -> dict[str, np.ndarray]:
        """A solution of this program as the initial guess of another on the same skeleton."""
        guess = {"q_obj": sol.q_obj, "q_pusher": sol.q_pusher, "p": sol.contact}
        if sol.touch_point is not None:
            guess["p_touch"] = sol.touch_point
        return guess

    def _status(self, result) -> str:
        if self.settings.solver == "snopt":
            return f"snopt info {result.get_solver_details().info}"
        return str(result.get_solution_result())

    def _evaluate_untimed(self, x: np.ndarray) -> tuple[dict[str, float], float]:
        """:meth:`evaluate` without adding its calls to the solver's timings."""
        saved = dict(self.timings)
        out = self.evaluate(x)
        self.timings.clear()
        self.timings.update(saved)
        return out

    def _timing_report(self, seconds: float) -> dict:
        out = {k: round(v, 3) for k, v in self.timings.items()}
        out["solver"] = round(max(0.0, seconds - sum(self.timings.values())), 3)
        return out

    def dynamics_mm2(self, q_obj: np.ndarray, q_pusher: np.ndarray,
                     others: dict | None = None) -> np.ndarray:
        """H_F per step as the mean squared SDF residual over the table, mm² (none in the
        kinematic program; ``others``: other objects' poses, see ChainPushProgram)."""
        if self.dynamics is None:
            return np.zeros(0)
        return self._residual_mm2(self.dynamics, q_obj, q_pusher)

    def _residual_mm2(self, dynamics: LearnedDynamics, q_obj: np.ndarray, q_actor: np.ndarray
                      ) -> np.ndarray:
        """``dynamics``' H_F per step as the mean squared SDF residual over the table (mm²)."""
        H, _, _ = dynamics.evaluate(torch.from_numpy(q_obj), torch.from_numpy(q_actor),
                                    jacobian=False)
        area = float(self.scene.workspace.size[0] * self.scene.workspace.size[1])
        return H.double().numpy() * 1e6 / area

    def evaluate(self, x: np.ndarray) -> tuple[dict[str, float], float]:
        """At the full decision vector ``x``: the largest violation of each named constraint
        (linear ones under "linear"), each in its own scaled units, and the total cost."""
        worst: dict[str, float] = {}
        cost = sum(float(self.prog.EvalBinding(b, x)[0]) for b in self.prog.GetAllCosts())
        for binding in self.prog.GetAllConstraints():
            c = binding.evaluator()
            v = np.asarray(self.prog.EvalBinding(binding, x), dtype=float).ravel()
            lb, ub = c.lower_bound(), c.upper_bound()
            name = c.get_description() or "linear"
            worst[name] = max(worst.get(name, 0.0),
                              float(np.max(np.maximum(lb - v, 0.0), initial=0.0)),
                              float(np.max(np.maximum(v - ub, 0.0), initial=0.0)))
        return worst, cost if np.isfinite(cost) else float("inf")
