"""The trajectory optimisation of one skeleton as a Drake ``MathematicalProgram`` (paper eq. 2).

Decision variables over N = K·T steps (states 0…N): the planar pose of the pushed object
``q_obj (N+1, 3)``, the pusher position ``q_pusher (N+1, 2)`` and, in push phases, contact
points ``p (·, 2)``. State 0 is the scene's start. Through the fast evaluators, one Python
callback per functional covering every step:

* H_F (learned dynamics, eq. 5) in every step: a cost on the mean squared SDF residual
  (``H_F.weight``), or a bound on it;
* H_coll (eq. 7) between pusher and object in every step, bounded by what a face contact
  costs in push steps and by ``H_coll.clearance`` of free space in the other steps; along
  each free move of a free pusher, its gap to the object (SweptClearance) at a few points;
* H_PoC (eq. 9, decision-variable form) in push steps: φ_obj(p) = φ_pusher(p) = 0;
* H_g (eq. 8) at the last state: at most ``goal.tol`` of the object's area outside the goal
  region shrunk by ``goal.inset``;
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

from robotplan.models.dynamics import PushDynamics
from robotplan.program.dynamics_rows import Dynamics, mm2_per_unit
from robotplan.program.guess import initial_guess
from robotplan.program.push_rows import PushRows
from robotplan.program.row_table import rows_for_stage
from robotplan.program.settings import DEFAULT_SETTINGS, ProgramSettings
from robotplan.program.skeleton import Skeleton, SkeletonSpace
from robotplan.program.solution import FEASIBLE, SNOPT_MINOR_DEFAULT, WARM_USABLE, Solution, rank
from robotplan.scene.task import PushTask

__all__ = ["PushProgram"]

class PushProgram(PushRows):
    """One skeleton of a single-pusher, single-object scene as a nonlinear program."""

    # the pusher moves in the table's plane between its states (a free sphere); an arm's tip
    # moves in 3-D and may pass over the object while reaching (ArmPushProgram)
    planar_pusher = True

    def __init__(self, task: PushTask, skeleton: Skeleton, model: PushDynamics | None,
                 space: SkeletonSpace, settings: ProgramSettings = DEFAULT_SETTINGS,
                 guess: dict[str, np.ndarray] | None = None) -> None:
        """``model=None`` builds the kinematic program (sticking contact and pushing
        direction instead of H_F); ``guess`` replaces the circle-and-push initial guess."""
        self.task, self.scene = task, task.scene
        self.skeleton, self.settings, self.space = skeleton, settings, space
        scene = task.scene
        first = skeleton.phases[0]
        self.obj = scene.bodies[first.object]
        self.pusher = scene.bodies[first.actor]
        self.region = task.region
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
        self.model, self.dynamics = model, None
        # the rows of the table (skeletons/rows.yaml) of this stage, in its order
        for spec in rows_for_stage(learned=model is not None, goal=task.goal):
            if spec.enabled is None or settings.value(spec.enabled):
                self.add_row(spec)

    # ------------------------------------------------------------------ hooks
    def _add_variables(self) -> None:
        """More decision variables, before the guess (none here; see ChainPushProgram)."""

    def _initial_guess(self) -> dict[str, np.ndarray]:
        return initial_guess(self)

    # ------------------------------------------------------------------ solve
    def _set_start(self) -> None:
        for V, value in self._guess_pairs():
            if V.size:
                self.prog.SetInitialGuess(V, value)

    def start_solution(self) -> Solution:
        """The program's initial guess as a solution, measured by this program's rows and
        residual without solving (a start good enough to keep needs no solver:
        ``ProgramSettings.accept_good_start``)."""
        self._set_start()
        t0 = time.perf_counter()
        x = self.prog.GetInitialGuess(self.prog.decision_variables())
        violations, cost = self._evaluate_untimed(x)
        return self._solution(x, violations, cost, "the start, not solved",
                              time.perf_counter() - t0, {})

    def solve(self) -> Solution:
        s = self.settings
        prog = self.prog
        self._set_start()
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
        return self._solution(x, violations, cost, status, seconds, timings)

    def _solution(self, x: np.ndarray, violations: dict[str, float], cost: float, status: str,
                  seconds: float, timings: dict) -> Solution:
        """The full decision vector ``x`` with its worst violations and cost as a Solution."""
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

    def _residual_mm2(self, dynamics: Dynamics, q_obj: np.ndarray, q_actor: np.ndarray
                      ) -> np.ndarray:
        """``dynamics``' H_F per step as the mean squared SDF residual over the table (mm²)."""
        H, _, _ = dynamics.evaluate(torch.from_numpy(q_obj), torch.from_numpy(q_actor),
                                    jacobian=False)
        return H.double().numpy() * mm2_per_unit(dynamics, self.scene)

    def evaluate(self, x: np.ndarray) -> tuple[dict[str, float], float]:
        """At the full decision vector ``x``: the largest violation of each named constraint
        (linear ones under "linear"; the swept row checked densely too), each in its own
        scaled units, and the total cost."""
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
        if "swept" in worst:
            q1, q2 = self._values(x, self.Q1), self._values(x, self.Q2)
            worst["swept"] = max(worst["swept"], self.swept_shortfall(q1, q2))
        return worst, cost if np.isfinite(cost) else float("inf")
