"""The trajectory optimisation of one skeleton as a Drake ``MathematicalProgram`` (paper
eq. 2): :class:`PushProgram`.

Decision variables over N = K·T steps (states 0…N,
:class:`~robotplan.pushing.program.variables.ProgramVariables`): the pushed object's planar poses,
the actor's positions and the contact points of push steps; a chained object's poses and
contact points, a touch goal's point, each arm's joint angles where the task has them.
State 0 is the scene's start. The rows are those of the row table
(``skeletons/rows.yaml``) for the program's stages, added by the one builder
(:func:`~robotplan.pushing.program.builder.add_rows`): the kinematic stage (``model=None``:
sticking contact, pushing direction and the quasi-static law instead of H_F) or the
learned one (H_F, eq. 5); the chain's rows for a skeleton with chained pushes; the arms'
rows, after their joint variables, for a task with arms.
:func:`~robotplan.pushing.program.solve.solve_skeleton` solves the kinematic program from the
circle-and-push guess and starts the learned one from its solution.
"""

from __future__ import annotations

import time

import numpy as np
from pydrake.solvers import IpoptSolver, MathematicalProgram, SnoptSolver, SolverOptions

from robotplan.functionals.kinematics import arm_kinematics
from robotplan.pushing.models.dynamics import PushDynamics
from robotplan.pushing.program.builder import add_rows
from robotplan.pushing.program.chain_guess import chain_guess
from robotplan.pushing.program.guess import initial_guess
from robotplan.pushing.program.rows_arm import joint_guess
from robotplan.pushing.program.rows_dynamics import residual_mm2
from robotplan.pushing.program.rows_push import swept_shortfall
from robotplan.pushing.program.settings import (
    ARM_PROGRAM_SETTINGS,
    DEFAULT_SETTINGS,
    ProgramSettings,
)
from robotplan.pushing.program.skeleton import Skeleton, SkeletonSpace
from robotplan.pushing.program.solution import (
    FEASIBLE,
    SNOPT_MINOR_DEFAULT,
    WARM_USABLE,
    Solution,
    rank,
)
from robotplan.pushing.program.variables import ProgramVariables, StepSets
from robotplan.scene.task import PushTask

__all__ = ["PushProgram"]


class PushProgram:
    """One skeleton of a push task as a nonlinear program."""

    def __init__(self, task: PushTask, skeleton: Skeleton, model: PushDynamics | None,
                 space: SkeletonSpace, settings: ProgramSettings | None = None,
                 guess: dict[str, np.ndarray] | None = None) -> None:
        """``model=None`` builds the kinematic program; ``guess`` replaces the
        circle-and-push initial guess; ``settings`` default to the free pushers' or, with
        arms, the arms' program settings."""
        scene = task.scene
        if settings is None:
            settings = ARM_PROGRAM_SETTINGS if task.arms else DEFAULT_SETTINGS
        self.task, self.scene, self.skeleton, self.space = task, scene, skeleton, space
        self.settings, self.model = settings, model
        first = skeleton.phases[0]
        self.obj, self.pusher = scene.bodies[first.object], scene.bodies[first.actor]
        self.region = task.region
        self.T = space.steps_per_phase
        self.steps = StepSets(skeleton, self.T, task.touch_actor)
        self.N = self.steps.N
        self.push_steps = self.steps.named("push")
        chained = skeleton.chained
        self.target = scene.bodies[chained] if chained else None
        self.chain_steps = self.steps.named("chain_push")
        self.timings: dict[str, float] = {}  # seconds inside each functional's callback
        self.prog = MathematicalProgram()
        self.variables = ProgramVariables.make(
            self.prog, self.steps, chain=chained is not None, touch=task.goal == "touch",
            goal_chained=chained is not None and task.goal_object == chained)
        self.goal_body = self.target if self.variables.goal_chained else self.obj
        self.dynamics = self.chain_dynamics = None
        self.swept_check: tuple[np.ndarray, float, float] | None = None
        self.guess = guess if guess is not None else (
            chain_guess(self) if chained else initial_guess(self))
        self.keep_start = guess is not None  # a given start is a plan worth keeping
        learned = model is not None
        stages = ("both", "learned" if learned else "kinematic")
        if chained:
            stages += ("chain", "chain_learned" if learned else "chain_kinematic")
        add_rows(self, stages)
        self.kin = {r.name: arm_kinematics(r) for r in scene.robots} if task.arms else {}
        if self.kin:
            radii = {scene.bodies[name].shape.radius for name in self.kin}
            if len(radii) > 1:
                raise ValueError("robots: arms with different tip radii are not planned yet")
            self.tip_radius = radii.pop()
            self.variables.add_joints(self.prog, {n: k.dof for n, k in self.kin.items()})
            if "q_joints" not in self.guess:
                self.guess["q_joints"] = joint_guess(self)
            add_rows(self, ("arms",))

    # ------------------------------------------------------------------ solve
    def _guess_pairs(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """(variables, initial values) for SetInitialGuess."""
        v, g = self.variables, self.guess
        pairs = [(v.q_obj, g["q_obj"]), (v.q_actor, g["q_pusher"]), (v.contact, g["p"])]
        if v.touch is not None:
            pairs.append((v.touch, g.get("p_touch", g["q_pusher"][-1:])))
        if v.chained is not None:
            pairs += [(v.chained, g["q_chain"]), (v.chain_contact, g["p_chain"])]
        pairs += [(Q, g["q_joints"][name]) for name, Q in v.joints.items()]
        return pairs

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

    def _solver(self, iterations: int) -> tuple[SnoptSolver | IpoptSolver, SolverOptions]:
        """The solver and its options for ``iterations`` major iterations."""
        s, prog = self.settings, self.prog
        opts = SolverOptions()
        if s.solver == "snopt":
            solver = SnoptSolver()
            opts.SetOption(solver.id(), "Major optimality tolerance", s.optimality_tol)
            opts.SetOption(solver.id(), "Major feasibility tolerance", s.feasibility_tol)
            opts.SetOption(solver.id(), "Major iterations limit", iterations)
            rows = sum(b.evaluator().num_constraints() for b in prog.GetAllConstraints())
            opts.SetOption(solver.id(), "Iterations limit",
                           max(SNOPT_MINOR_DEFAULT, s.minor_iterations_per_row * rows))
            return solver, opts
        solver = IpoptSolver()
        opts.SetOption(solver.id(), "tol", s.optimality_tol)
        opts.SetOption(solver.id(), "acceptable_tol", 10 * s.optimality_tol)
        opts.SetOption(solver.id(), "max_iter", iterations)
        return solver, opts

    def _chunks(self) -> list[int]:
        """The major iterations of each solve of this stage (``warm_chunk``)."""
        s = self.settings
        if self.dynamics is not None or not s.warm_chunk:
            return [s.iterations if self.dynamics is not None else s.warm_iterations]
        full, rest = divmod(s.warm_iterations, s.warm_chunk)
        return [s.warm_chunk] * full + ([rest] if rest else [])

    def solve(self) -> Solution:
        s, prog = self.settings, self.prog
        self._set_start()
        start = x = prog.GetInitialGuess(prog.decision_variables())
        t0 = time.perf_counter()  # the clock of the per-functional timings
        for i, iterations in enumerate(self._chunks()):
            if i:  # from where the last chunk ended
                prog.SetInitialGuess(prog.decision_variables(), x)
            solver, opts = self._solver(iterations)
            result = solver.Solve(prog, None, opts)
            x = result.GetSolution(prog.decision_variables())
            violations, cost = self._evaluate_untimed(x)
            if max(violations.values(), default=0.0) <= s.warm_restart_above:
                break
        seconds = time.perf_counter() - t0
        status = self._status(result)
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
            start_violations, start_cost = self.evaluate(start)
            if rank(start_violations, start_cost) < rank(violations, cost):
                x, violations, cost = start, start_violations, start_cost
                status += ", kept the start"
        return self._solution(x, violations, cost, status, seconds, timings)

    def _solution(self, x: np.ndarray, violations: dict[str, float], cost: float, status: str,
                  seconds: float, timings: dict) -> Solution:
        """The full decision vector ``x`` with its worst violations and cost as a Solution."""
        v = self.variables
        q1, q2, p = (self._values(x, V) for V in (v.q_obj, v.q_actor, v.contact))
        violation = max(violations.values(), default=0.0)
        touch = None if v.touch is None else self._values(x, v.touch)
        others, contacts = {}, {}
        if v.chained is not None:
            others[self.target.name] = self._values(x, v.chained)
            contacts[self.target.name] = self._values(x, v.chain_contact).reshape(-1, 2)
        joints = {name: self._values(x, Q) for name, Q in v.joints.items()}
        return Solution(self.skeleton, violation <= FEASIBLE, status, violation, cost, seconds,
                        q1, q2, p.reshape(-1, 2), self.dynamics_mm2(q1, q2, others), timings,
                        violations, joints, touch, others, contacts)

    def _values(self, x: np.ndarray, V: np.ndarray) -> np.ndarray:
        """The entries of the full decision vector ``x`` for the variable array ``V``."""
        return x[self.prog.FindDecisionVariableIndices(V.ravel())].reshape(V.shape)

    def as_guess(self, sol: Solution) -> dict[str, np.ndarray]:
        """A solution of this program as the initial guess of another on the same skeleton."""
        guess = {"q_obj": sol.q_obj, "q_pusher": sol.q_pusher, "p": sol.contact}
        if sol.touch_point is not None:
            guess["p_touch"] = sol.touch_point
        if self.target is not None:
            name = self.target.name
            guess.update(q_chain=sol.q_others[name], p_chain=sol.contact_others[name])
        if self.kin:
            guess["q_joints"] = sol.q_joints
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
        kinematic program); with a chain, the object–chained pair's after the actor's
        (``others``: the chained object's poses by name)."""
        if self.dynamics is None:
            return np.zeros(0)
        first = residual_mm2(self.dynamics, self.scene, q_obj, q_pusher)
        if self.chain_dynamics is None or not others:
            return first
        return np.concatenate((first, residual_mm2(self.chain_dynamics, self.scene,
                                                   others[self.target.name], q_obj)))

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
            v = self.variables
            q1, q2 = self._values(x, v.q_obj), self._values(x, v.q_actor)
            worst["swept"] = max(worst["swept"], swept_shortfall(self, q1, q2))
        return worst, cost if np.isfinite(cost) else float("inf")
