"""The trajectory optimisation of one skeleton as a Drake ``MathematicalProgram`` (paper eq. 2).

Decision variables over N = K·T steps (states 0…N): the planar pose of the pushed object
``q_obj (N+1, 3)``, the pusher position ``q_pusher (N+1, 2)`` and, in push phases, contact
points ``p (·, 2)``. State 0 is the scene's start. Constraints (all through the fast
evaluators, one Python callback per functional covering every step):

* H_F (learned dynamics, eq. 5) in every step, as a bound on the mean squared SDF residual;
* H_coll (eq. 7) between pusher and object in every step, a bound on the overlap area;
* H_PoC (eq. 9, decision-variable form) in push steps: φ_obj(p) = φ_pusher(p) = 0;
* H_g (eq. 8) at the last state: at most ``goal_tol`` of the object's area outside the goal.

Costs: squared accelerations of the pusher and of the contact points, with the prefix
q_{−2} = q_{−1} = q_0.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import torch
from pydrake.autodiffutils import ExtractGradient, ExtractValue, InitializeAutoDiff
from pydrake.solvers import IpoptSolver, MathematicalProgram, SnoptSolver, SolverOptions

from robotplan.functionals import Collision, ContactPoint, GoalRegion
from robotplan.functionals.dynamics import LearnedDynamics, phase_quadrature
from robotplan.learned.dynamics import PushDynamics
from robotplan.scene import Scene
from robotplan.skeleton import Skeleton, SkeletonSpace

__all__ = ["ProgramSettings", "PushProgram", "Solution"]


@dataclass(frozen=True)
class ProgramSettings:
    a_coll: float = 500.0
    a_goal: float = 100.0
    dynamics_rmse: float = 0.0015  # m: allowed RMSE of φ1_t against F(…) over X per step
    # H_F as a cost (weight per mm² of mean squared residual per step) when > 0, else as a
    # constraint ≤ dynamics_rmse² per step: the model's own error (~4.5 mm in contact) makes
    # the bound either infeasible or loose enough to move the object without contact
    dynamics_weight: float = 0.01
    hold_while_reaching: bool = True  # q_obj,t = q_obj,t−1 in reach phases
    guess_speed: float = 0.027  # m per step and axis in the initial guess (data: ≤ 2.9 cm)
    # optional hard limits per step and axis (m, rad); off by default: on box_push they
    # left SNOPT at violation 1.2 (coverage 0.997) instead of 7e-5 (coverage 1.0)
    max_step: float | None = None
    max_turn: float | None = None
    coll_area: float = 2e-5  # m²: allowed smoothed overlap (touching itself gives ~1e-6)
    goal_tol: float = 0.003  # share of the object's area allowed outside the goal
    accel_weight: float = 1.0  # larger weights kept SNOPT from certifying optimality
    contact_accel_weight: float = 0.1
    solver: str = "snopt"
    optimality_tol: float = 2e-3
    feasibility_tol: float = 1e-4
    iterations: int = 100  # SNOPT major iterations; the best point so far is kept
    quad_coarse: float = 0.14  # H_F quadrature (see phase_quadrature)


@dataclass
class Solution:
    skeleton: Skeleton
    success: bool
    status: str
    violation: float
    cost: float
    seconds: float
    q_obj: np.ndarray
    q_pusher: np.ndarray
    contact: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    dynamics_mm2: np.ndarray = field(default_factory=lambda: np.zeros(0))  # H_F per step
    timings: dict = field(default_factory=dict)  # seconds per functional; "solver": the rest

    @property
    def dynamics_rms_mm(self) -> float:
        """RMS over steps of the model residual: √(mean_t H_F,t / |X|) in mm."""
        return float(np.sqrt(self.dynamics_mm2.mean())) if self.dynamics_mm2.size else 0.0


def _bridge(fn, timings: dict[str, float] | None = None, name: str = ""):
    """Drake calls constraints with floats or AutoDiffXd; answer both from fn (and add the
    seconds spent to ``timings[name]``)."""

    def wrapped(x: np.ndarray) -> np.ndarray:
        t0 = time.perf_counter()
        if x.dtype != object:
            out = fn(np.asarray(x, dtype=float), False)[0]
        else:
            values, J = fn(ExtractValue(x).ravel(), True)
            out = InitializeAutoDiff(values.reshape(-1, 1), J @ ExtractGradient(x)).ravel()
        if timings is not None:
            timings[name] = timings.get(name, 0.0) + time.perf_counter() - t0
        return out

    return wrapped


class PushProgram:
    """One skeleton of a single-pusher, single-object scene as a nonlinear program."""

    def __init__(self, scene: Scene, skeleton: Skeleton, model: PushDynamics,
                 space: SkeletonSpace, settings: ProgramSettings = ProgramSettings()) -> None:
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
        self.guess = self._initial_guess()
        # state 0 is the scene's start
        prog.AddBoundingBoxConstraint(np.array(self.obj.pose), np.array(self.obj.pose),
                                      self.Q1[0])
        prog.AddBoundingBoxConstraint(np.array(self.pusher.pose[:2]),
                                      np.array(self.pusher.pose[:2]), self.Q2[0])
        x0, x1, y0, y1 = scene.workspace.bounds
        for Q in (self.Q1[:, :2], self.Q2, self.P):
            if Q.size:
                prog.AddBoundingBoxConstraint(np.tile([x0, y0], (Q.shape[0], 1)).ravel(),
                                              np.tile([x1, y1], (Q.shape[0], 1)).ravel(),
                                              Q.ravel())
        if settings.hold_while_reaching:
            self._hold_object_while_reaching()
        self._add_dynamics(model)
        self._add_step_limits()
        self._add_collision()
        self._add_contact()
        self._add_goal()
        self._add_costs()

    # ------------------------------------------------------------------ guess
    def _init_point(self, index: int, center: np.ndarray) -> np.ndarray:
        goal = self.region.pose[:2] if self.region is not None else None
        ang = self.space.init_angle(index, self.obj.pose[:2], goal)
        dist = (self.obj.shape.bound_radius + self.pusher.shape.radius
                + self.space.init_clearance)
        return center + dist * np.array([math.cos(ang), math.sin(ang)])

    def _contact_offset(self, X_obj: np.ndarray, direction: np.ndarray,
                        depth: float = 0.001) -> np.ndarray:
        """Where along ``direction`` from the object's origin the pusher touches it (its
        centre at φ_obj = radius − depth), by bisection on the ray."""
        u = direction / max(float(np.linalg.norm(direction)), 1e-9)
        target = self.pusher.shape.radius - depth
        lo, hi = 0.0, self.obj.shape.bound_radius + self.pusher.shape.radius
        X = torch.as_tensor(X_obj, dtype=torch.float64)[None]
        for _ in range(30):
            mid = 0.5 * (lo + hi)
            point = torch.as_tensor(X_obj[:2] + mid * u, dtype=torch.float64)[None]
            if self.obj.sdf(point, X).item() < target:
                lo = mid
            else:
                hi = mid
        return hi * u

    def _initial_guess(self) -> dict[str, np.ndarray]:
        """Paper app. I.2: the pusher moves on a circle around the object to the phase's
        init point, then pushes; the object slides towards the goal in push phases."""
        T, N = self.T, self.N
        start = np.array(self.obj.pose, dtype=float)
        goal = (np.array(self.region.pose[:2]) if self.region is not None else start[:2])
        q1 = np.tile(start, (N + 1, 1))
        q2 = np.zeros((N + 1, 2))
        q2[0] = self.pusher.pose[:2]
        n_push = self.skeleton.pushes
        speed = self.settings.guess_speed  # per step and axis
        done = 0
        for k, ph in enumerate(self.skeleton.phases):
            a, b = k * T, (k + 1) * T
            center = q1[a, :2]
            target = self._init_point(ph.init, center)
            if ph.mode == "reach":
                r0 = q2[a] - center
                r1 = target - center
                ang0, ang1 = math.atan2(r0[1], r0[0]), math.atan2(r1[1], r1[0])
                dang = (ang1 - ang0 + math.pi) % (2 * math.pi) - math.pi
                rad0, rad1 = np.linalg.norm(r0), np.linalg.norm(r1)
                for s in range(1, T + 1):
                    u = s / T
                    ang, rad = ang0 + u * dang, rad0 + u * (rad1 - rad0)
                    q2[a + s] = center + rad * np.array([math.cos(ang), math.sin(ang)])
                q1[a + 1:b + 1] = q1[a]
            else:  # the pusher steps into contact, then the two move towards the goal
                done += 1
                end = start[:2] + (goal - start[:2]) * done / n_push
                offset = self._contact_offset(q1[a], q2[a] - q1[a, :2])
                contact = q1[a, :2] + offset
                k = min(T - 1, math.ceil(np.abs(contact - q2[a]).max() / speed))
                for s in range(1, k + 1):  # approach, the object still
                    q2[a + s] = q2[a] + (contact - q2[a]) * s / k
                    q1[a + s] = q1[a]
                # push at most at the data's speeds (the goal constraint asks for the rest)
                travel = end - q1[a, :2]
                travel *= min(1.0, (T - k) * speed / max(np.abs(travel).max(), 1e-9))
                for s in range(k + 1, T + 1):
                    q1[a + s] = q1[a]
                    q1[a + s, :2] = q1[a, :2] + travel * (s - k) / (T - k)
                    q2[a + s] = q1[a + s, :2] + offset
        p = np.array([0.5 * (q1[t, :2] + q2[t]) for t in self.push_steps]).reshape(-1, 2)
        return {"q_obj": q1, "q_pusher": q2, "p": p}

    # ------------------------------------------------------------ functionals
    def _add_dynamics(self, model: PushDynamics) -> None:
        s = self.settings
        path = torch.as_tensor(self.guess["q_obj"][:, :2], dtype=torch.float32)
        quad = phase_quadrature(path, self.obj.shape.bound_radius, self.scene.workspace,
                                coarse=s.quad_coarse)
        self.dynamics = LearnedDynamics(model, self.obj, self.pusher, quad)
        N = self.N
        area = float(self.scene.workspace.size[0] * self.scene.workspace.size[1])
        scale = 1e6 / area  # H (m²) → mean squared residual in mm²

        def fn(x: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
            X1 = torch.from_numpy(x[:3 * (N + 1)].reshape(N + 1, 3))
            X2 = torch.from_numpy(x[3 * (N + 1):].reshape(N + 1, 2))
            H, J1, J2 = self.dynamics.evaluate(X1, X2, jacobian=jac)
            values = H.double().numpy() * scale
            if not jac:
                return values, None
            J = np.zeros((N, 5 * (N + 1)))
            rows = np.arange(N)
            J1n, J2n = J1.double().numpy() * scale, J2.double().numpy() * scale
            for which in (0, 1):
                states = rows + which
                for k in range(3):
                    J[rows, 3 * states + k] = J1n[:, which, k]
                for k in range(2):
                    J[rows, 3 * (N + 1) + 2 * states + k] = J2n[:, which, k]
            return values, J

        variables = np.concatenate((self.Q1.ravel(), self.Q2.ravel()))
        if s.dynamics_weight > 0:
            def total(x: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
                values, J = fn(x, jac)
                w = s.dynamics_weight
                return (np.array([w * values.sum()]),
                        None if J is None else w * J.sum(axis=0, keepdims=True))

            bridged = _bridge(total, self.timings, "H_F")
            self.prog.AddCost(lambda x: bridged(x)[0], variables, description="H_F")
            return
        bound = (s.dynamics_rmse * 1e3) ** 2
        self.prog.AddConstraint(_bridge(fn, self.timings, "H_F"), np.zeros(N), np.full(N, bound),
                                variables, "H_F")

    def _hold_object_while_reaching(self) -> None:
        """A reach phase moves the pusher without touching (H_coll keeps it off), so the
        object stays where it is: q_obj,t = q_obj,t−1 in reach steps. Without this, the
        cost on H_F alone let the optimiser drift the object a few mm per step."""
        T = self.T
        for k, ph in enumerate(self.skeleton.phases):
            if ph.mode != "reach":
                continue
            for t in range(k * T + 1, (k + 1) * T + 1):
                self.prog.AddLinearEqualityConstraint(
                    np.hstack((np.eye(3), -np.eye(3))), np.zeros(3),
                    np.concatenate((self.Q1[t], self.Q1[t - 1])))

    def _add_step_limits(self) -> None:
        """Travel per step and axis ≤ ``max_step`` for the pusher and the object, object
        rotation ≤ ``max_turn``: the speeds of the push data, and a trust region that keeps
        the solver among the states the learned model knows."""
        N, s = self.N, self.settings

        def differences(Q: np.ndarray, limits: list[float]) -> None:
            d = len(limits)
            D = np.zeros((d * N, d * (N + 1)))
            for t in range(N):
                for k in range(d):
                    D[d * t + k, d * (t + 1) + k], D[d * t + k, d * t + k] = 1.0, -1.0
            lim = np.tile(limits, N)
            self.prog.AddLinearConstraint(D, -lim, lim, Q.ravel())

        if s.max_step is not None:
            differences(self.Q2, [s.max_step] * 2)
        if s.max_step is not None and s.max_turn is not None:
            differences(self.Q1, [s.max_step, s.max_step, s.max_turn])

    def _per_step_pair(self, H, name: str, scale: float, ub: float) -> None:
        N = self.N

        def fn(x: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
            X1 = torch.from_numpy(x[:3 * N].reshape(N, 3))
            X2 = torch.from_numpy(x[3 * N:].reshape(N, 2))
            if not jac:
                return H(X1, X2)[:, 0].numpy() * scale, None
            r, (J1, J2) = H.jacobians(X1, X2)
            J = np.zeros((N, 5 * N))
            rows = np.arange(N)
            for k in range(3):
                J[rows, 3 * rows + k] = J1[:, 0, k].numpy() * scale
            for k in range(2):
                J[rows, 3 * N + 2 * rows + k] = J2[:, 0, k].numpy() * scale
            return r[:, 0].numpy() * scale, J

        self.prog.AddConstraint(_bridge(fn, self.timings, name), np.zeros(N), np.full(N, ub),
                                np.concatenate((self.Q1[1:].ravel(), self.Q2[1:].ravel())),
                                name)

    def _add_collision(self) -> None:
        H = Collision(self.obj, self.pusher, a=self.settings.a_coll)
        self._per_step_pair(H, "H_coll", 1e4, self.settings.coll_area * 1e4)  # in cm²

    def _add_contact(self) -> None:
        n = len(self.push_steps)
        if n == 0:
            return
        H = ContactPoint(self.obj, self.pusher)
        steps = self.push_steps

        def fn(x: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
            X1 = torch.from_numpy(x[:3 * n].reshape(n, 3))
            X2 = torch.from_numpy(x[3 * n:5 * n].reshape(n, 2))
            p = torch.from_numpy(x[5 * n:].reshape(n, 2))
            if not jac:
                return H(X1, X2, p).numpy().ravel() * 100, None
            r, (J1, J2, Jp) = H.jacobians(X1, X2, p)
            J = np.zeros((2 * n, 7 * n))
            for i in range(n):
                for c in range(2):
                    row = 2 * i + c
                    J[row, 3 * i:3 * i + 3] = J1[i, c].numpy()
                    J[row, 3 * n + 2 * i:3 * n + 2 * i + 2] = J2[i, c].numpy()
                    J[row, 5 * n + 2 * i:5 * n + 2 * i + 2] = Jp[i, c].numpy()
            return r.numpy().ravel() * 100, J * 100  # cm

        self.prog.AddConstraint(_bridge(fn, self.timings, "H_PoC"), np.zeros(2 * n),
                                np.zeros(2 * n),
                                np.concatenate((self.Q1[steps].ravel(), self.Q2[steps].ravel(),
                                                self.P.ravel())), "H_PoC")

    def _add_goal(self) -> None:
        if self.region is None:
            return
        H = GoalRegion(self.obj, self.region, a=self.settings.a_goal)
        scale = 1.0 / self.obj.area

        def fn(x: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
            X = torch.from_numpy(x.reshape(1, 3))
            if not jac:
                return H(X)[:, 0].numpy() * scale, None
            r, (J,) = H.jacobians(X)
            return r[:, 0].numpy() * scale, J[:, 0].numpy() * scale

        self.prog.AddConstraint(_bridge(fn, self.timings, "H_g"), np.zeros(1),
                                np.array([self.settings.goal_tol]),
                                self.Q1[self.N], "H_g")

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
        prog.SetInitialGuess(self.Q1, self.guess["q_obj"])
        prog.SetInitialGuess(self.Q2, self.guess["q_pusher"])
        if len(self.P):
            prog.SetInitialGuess(self.P, self.guess["p"])
        opts = SolverOptions()
        if s.solver == "snopt":
            solver = SnoptSolver()
            opts.SetOption(solver.id(), "Major optimality tolerance", s.optimality_tol)
            opts.SetOption(solver.id(), "Major feasibility tolerance", s.feasibility_tol)
            opts.SetOption(solver.id(), "Major iterations limit", s.iterations)
        else:
            solver = IpoptSolver()
            opts.SetOption(solver.id(), "tol", s.optimality_tol)
            opts.SetOption(solver.id(), "acceptable_tol", 10 * s.optimality_tol)
            opts.SetOption(solver.id(), "max_iter", s.iterations)
        t0 = time.perf_counter()  # the clock of the per-functional timings
        result = solver.Solve(prog, None, opts)
        seconds = time.perf_counter() - t0
        timings = self._timing_report(seconds)  # before the checks below call back again
        if s.solver == "snopt":
            info = result.get_solver_details().info
            status = f"snopt info {info}"
        else:
            status = str(result.get_solution_result())
        q1 = result.GetSolution(self.Q1)
        q2 = result.GetSolution(self.Q2)
        p = result.GetSolution(self.P) if len(self.P) else np.zeros((0, 2))
        violation = self.violation(result)
        cost = float(result.get_optimal_cost()) if np.isfinite(
            result.get_optimal_cost()) else float("inf")
        return Solution(self.skeleton, violation < 1e-2, status, violation, cost, seconds,
                        q1, q2, p, self.dynamics_mm2(q1, q2), timings)

    def _timing_report(self, seconds: float) -> dict:
        out = {k: round(v, 3) for k, v in self.timings.items()}
        out["solver"] = round(max(0.0, seconds - sum(self.timings.values())), 3)
        return out

    def dynamics_mm2(self, q_obj: np.ndarray, q_pusher: np.ndarray) -> np.ndarray:
        """H_F per step as the mean squared SDF residual over the table, mm²."""
        H, _, _ = self.dynamics.evaluate(torch.from_numpy(q_obj), torch.from_numpy(q_pusher),
                                         jacobian=False)
        area = float(self.scene.workspace.size[0] * self.scene.workspace.size[1])
        return H.double().numpy() * 1e6 / area

    def violation(self, result) -> float:
        """Largest violation over all constraints, each in its own (scaled) units."""
        worst = 0.0
        for binding in self.prog.GetAllConstraints():
            c = binding.evaluator()
            v = np.asarray(result.EvalBinding(binding), dtype=float).ravel()
            lb, ub = c.lower_bound(), c.upper_bound()
            worst = max(worst, float(np.max(np.maximum(lb - v, 0.0), initial=0.0)),
                        float(np.max(np.maximum(v - ub, 0.0), initial=0.0)))
        return worst
