"""The mug-hanging program (paper §7.1, problem (2)): a Drake ``MathematicalProgram`` over the
mug's pose X_HM = (x, y, z, qw, qx, qy, qz) in the hook frame, with the learned success
functional as the cost H_hang² and the row |H_hang| ≤ κ (the network is trained towards 0
where the mug hangs and has no data below 0, so the row keeps the optimiser out of there),
the collision functional H_coll (eq. 7, a = 1000) as the row H_coll ≤ ``collision_cm3``,
the unit quaternion, the position within X_h, and (``threading``, robotplan's default) the
analytic row H_thread ≥ 0 that keeps the hook's arm through the handle's opening. SNOPT
solves it from one initial pose, first without the row on H_hang (``approach_iterations``),
then whole;
:mod:`robotplan.hanging.search.optimise` restarts it and samples."""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass
from typing import Literal

import numpy as np
import torch
from pydrake.solvers import MathematicalProgram, SnoptSolver, SolverOptions

from robotplan.hanging.functionals.collision3d import FixedCollision3D
from robotplan.hanging.functionals.h_hang import HangSuccessFunctional
from robotplan.hanging.functionals.threading import HandleThreading
from robotplan.hanging.models.hang_model import HangSuccess
from robotplan.hanging.scene.ranges import GridSpec
from robotplan.models.encoder import represent_grids
from robotplan.program.bridge import bridge, stepwise
from robotplan.sdf.mug_hook import Hook, Mug

__all__ = ["HANG_DEFAULTS", "HangProblem", "HangSettings", "HangSolution", "solve_hang_once"]

CM3 = 1e6  # m³ → cm³: the collision row in units SNOPT's tolerances suit
MM = 1e3  # m → mm: the threading row in units SNOPT's tolerances suit


@dataclass(frozen=True)
class HangSettings:
    kappa: float = 0.15  # H_hang ≤ κ predicts success (the paper's κ1)
    collision_cm3: float = 0.01  # H_coll ≤ this (cm³ of smoothed overlap)
    restarts: int = 20  # the paper: up to 20 optimisations from random poses
    evaluations: int = 20_000  # the paper's budget of functional evaluations per scene
    major_iterations: int = 60
    # SNOPT iterations on the program without the row |H_hang| ≤ κ before the whole program
    # (0: the whole program from the random pose, the paper's). From a pose far from the
    # hook (H_hang ~ 100) the row's infeasibility stops SNOPT within a few dozen evaluations
    # in most solves; the cost alone carries the mug to the hook
    # (docs/experiments.md#hang-approach)
    approach_iterations: int = 60
    feasibility_tol: float = 1e-4
    # each optimisation starts from the best of this many uniform random poses (least H_hang
    # among those within the collision bound; 1: one random pose, the paper's restarts)
    start_pool: int = 1
    # a feasible pose is taken at once only where H_hang's median over this many poses about
    # it (Gaussian, robust_shift m and robust_turn rad per axis) is ≤ robust_kappa: the
    # network's accepted region is narrow where it errs; otherwise the restarts go on and
    # the feasible pose with the least such median wins at the end (0: off, the paper's;
    # on 12 scenes it solved as many, in ten times the time: docs/experiments.md#hang-robust)
    robust_samples: int = 0
    robust_shift: float = 0.01
    robust_turn: float = 0.0873  # 5°
    robust_kappa: float = 0.1
    # H_coll's row: on the shapes' SDFs; on what the model reads of them (ψ or ψ_s for an
    # occupancy model, the paper's ψ rows; the SDFs otherwise); or none, found poses judged
    # by H_hang alone (the paper's point-cloud rows "no collision", app. A.5)
    collision: Literal["sdf", "model", "none"] = "sdf"
    # a feasible pose is taken at once only where the check network (``HangProblem.check``,
    # a second H_hang trained with poses inside the hook) gives ≤ check_kappa too: SNOPT
    # finds the poses where one network errs, and a second one errs elsewhere; otherwise the
    # restarts go on and the feasible pose with the least check value wins at the end
    # (docs/experiments.md#hang-check)
    check_kappa: float = 0.2
    # optimisations start threaded on the hook's arm (the best of thread_pool such poses,
    # robotplan.hanging.search.starts) and keep the arm through the handle's opening by the row
    # H_thread ≥ 0; a found pose is threaded. The learned H_hang accepts poses beside the arm
    # that fall; threaded poses clear of the hook hang (docs/experiments.md#hang-threading).
    # False: uniform random starts and no such row, the paper's
    threading: bool = True
    thread_pool: int = 16
    # H_coll's bound for threaded poses: an arm through a narrow opening leaves smoothed
    # overlap where the surfaces are millimetres apart; threaded poses clear in pybullet
    # reach ~0.1 cm³, those that start inside the hook begin near 0.12
    # (docs/experiments.md#hang-threading)
    thread_collision_cm3: float = 0.05

    def collision_bound(self, threaded: bool) -> float:
        """H_coll's bound (cm³) for a threaded pose or another."""
        return self.thread_collision_cm3 if threaded else self.collision_cm3


HANG_DEFAULTS = HangSettings()


@dataclass
class HangSolution:
    pose: np.ndarray  # (7,) X_HM
    h_hang: float
    h_coll_cm3: float
    feasible: bool  # H_hang ≤ κ, H_coll within its bound, a unit quaternion
    evaluations: int  # functional evaluations spent (H_hang on one pose counts one)
    seconds: float
    method: str = "optimisation"
    restarts: int = 0
    # median H_hang over poses about this one (HangSettings.robust_samples), None: not checked
    robust_h: float | None = None
    # the check network's H_hang here (HangSettings.check_kappa), None: not checked
    check_h: float | None = None
    # H_thread here (mm; > 0: the arm through the handle), None: solved without its row
    thread_mm: float | None = None


class HangProblem:
    """The functionals of one scene, and a count of their evaluations. ``collision`` as
    :attr:`HangSettings.collision`: ``"model"`` evaluates H_coll on what the model reads of
    the SDFs (eq. 7 with ψ in place of φ). ``check``: a second network that a found pose must
    satisfy too (:attr:`HangSettings.check_kappa`), not a row of the program."""

    def __init__(self, model: HangSuccess, mug: Mug, hook: Hook,
                 collision: str = "sdf", check: HangSuccess | None = None) -> None:
        self.model, self.mug, self.hook = model, mug, hook
        self.check = None if check is None else HangSuccessFunctional(check, mug, hook)
        spec = model.spec
        grid = GridSpec(size=spec.size, cells=spec.cells, below_arm=spec.below_arm)
        centre = grid.centre(hook)
        self.lo, self.hi = centre - spec.size / 2, centre + spec.size / 2
        self.h_hang = HangSuccessFunctional(model, mug, hook)
        reach = mug.reach
        read = None
        if collision == "model" and spec.representation in ("occupancy", "smooth_occupancy"):
            def read(phi, rep=spec.representation, b=spec.occupancy_sharpness):
                return represent_grids(phi, rep, b)[0]
        self.h_coll = FixedCollision3D(mug, hook, (self.lo - reach, self.hi + reach),
                                       read=read)
        self.h_thread = HandleThreading(mug, hook)
        self.evaluations = 0

    def unchecked(self) -> HangProblem:
        """This problem without its check network (the functionals shared, not rebuilt)."""
        plain = copy.copy(self)
        plain.check = None
        return plain

    def hang_values(self, X: np.ndarray) -> np.ndarray:
        """H_hang ``(n,)`` at poses ``(n, 7)`` (n evaluations)."""
        return self._values(self.h_hang, X)

    def check_value(self, X: np.ndarray) -> float:
        """The check network's H_hang at pose ``(7,)`` (one evaluation)."""
        assert self.check is not None, "no check network"
        return float(self._values(self.check, X)[0])

    def _values(self, functional: HangSuccessFunctional, X: np.ndarray) -> np.ndarray:
        Xt = torch.from_numpy(np.atleast_2d(X).astype(np.float64))
        with torch.no_grad():
            h = functional(Xt)[:, 0].numpy()
        self.evaluations += len(Xt)
        return h

    def collision_cm3(self, X: np.ndarray) -> np.ndarray:
        """H_coll in cm³ ``(n,)`` at poses ``(n, 7)``."""
        Xt = torch.from_numpy(np.atleast_2d(X).astype(np.float64))
        with torch.no_grad():
            return self.h_coll(Xt)[:, 0].numpy() * CM3

    def evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """H_hang and H_coll in cm³, each ``(n,)``, at poses ``(n, 7)``."""
        return self.hang_values(X), self.collision_cm3(X)

    def feasible(self, h: np.ndarray, c: np.ndarray, settings: HangSettings,
                 kappa: float | None = None, thread_mm: np.ndarray | None = None) -> np.ndarray:
        """H_hang ≤ κ and H_coll ≤ its bound (and H_thread ≥ 0 where given, in mm), each
        within SNOPT's feasibility tolerance (the solver stops on the bound; a pose it calls
        feasible is one)."""
        tol = settings.feasibility_tol
        hangs = h <= (settings.kappa if kappa is None else kappa) + tol
        if thread_mm is not None:
            hangs = hangs & (thread_mm >= -tol)
        if settings.collision == "none":
            return hangs
        return hangs & (c <= settings.collision_bound(thread_mm is not None) + tol)

    @staticmethod
    def violation(sol: HangSolution, settings: HangSettings) -> float:
        """How far ``sol``'s pose lies outside the rows H_hang ≤ κ, H_coll ≤ its bound and
        H_thread ≥ 0 where solved with it (the rows of :meth:`feasible`, without the
        tolerance; H_thread in mm)."""
        over = max(sol.h_hang - settings.kappa, 0.0)
        if sol.thread_mm is not None:
            over = max(over, -sol.thread_mm)
        if settings.collision != "none":
            over = max(over, sol.h_coll_cm3 - settings.collision_bound(sol.thread_mm is not None))
        return over


def _counted(problem: HangProblem, fn):
    def wrapped(x: np.ndarray, jac: bool):
        problem.evaluations += 1
        return fn(x, jac)

    return wrapped


def _square(v):
    return v * v


def _snopt(problem: HangProblem, X0: np.ndarray, settings: HangSettings, with_row: bool,
           iterations: int, part: int | None = None) -> np.ndarray:
    """SNOPT on the program from ``X0``, with or without the row |H_hang| ≤ κ, and with the
    row H_thread ≥ 0 on arm part ``part`` (None: none); the end pose ``(7,)`` with a unit
    quaternion."""
    prog = MathematicalProgram()
    X = prog.NewContinuousVariables(7, "X_HM")
    prog.AddBoundingBoxConstraint(problem.lo, problem.hi, X[:3])
    prog.AddBoundingBoxConstraint(-np.ones(4), np.ones(4), X[3:])
    prog.AddConstraint(sum(v * v for v in X[3:]) == 1.0)
    block = X[None, :]
    hang_fn, hang_vars = stepwise(problem.h_hang, [block], 1.0)
    hang = bridge(_counted(problem, hang_fn))
    prog.AddCost(lambda x: _square(hang(x)[0]), hang_vars)
    if with_row:
        prog.AddConstraint(hang, [-settings.kappa], [settings.kappa], hang_vars)
    if settings.collision != "none":
        coll_fn, coll_vars = stepwise(problem.h_coll, [block], CM3)
        prog.AddConstraint(bridge(coll_fn), [0.0], [settings.collision_bound(part is not None)],
                           coll_vars)
    if part is not None:
        thread_fn, thread_vars = stepwise(HandleThreading(problem.mug, problem.hook, part),
                                          [block], MM)
        prog.AddConstraint(bridge(thread_fn), [0.0], [np.inf], thread_vars)
    q = np.asarray(X0[3:], dtype=float)
    prog.SetInitialGuess(X, np.concatenate([X0[:3], q / np.linalg.norm(q)]))
    solver = SnoptSolver()
    opts = SolverOptions()
    opts.SetOption(solver.id(), "Major iterations limit", iterations)
    opts.SetOption(solver.id(), "Major feasibility tolerance", settings.feasibility_tol)
    pose = solver.Solve(prog, None, opts).GetSolution(X)
    pose[3:] /= np.linalg.norm(pose[3:])
    return pose


def solve_hang_once(problem: HangProblem, X0: np.ndarray,
                    settings: HangSettings = HANG_DEFAULTS,
                    part: int | None = None) -> HangSolution:
    """One solve from pose ``X0 (7,)``: with ``settings.approach_iterations``, first the
    program without the row |H_hang| ≤ κ (the cost H_hang² and the collision row bring the
    mug towards the hook), then the whole program from where that ends. With ``part`` (the
    arm part ``X0`` is threaded on) both carry the row H_thread ≥ 0 on it, and a feasible pose
    meets it. H_coll is evaluated at the end pose also without its row, so that a drop can be
    judged against it."""
    t0 = time.perf_counter()
    start_evals = problem.evaluations
    if settings.approach_iterations:
        X0 = _snopt(problem, X0, settings, False, settings.approach_iterations, part)
    pose = _snopt(problem, X0, settings, True, settings.major_iterations, part)
    h, c = problem.evaluate(pose[None])
    thread = None if part is None else problem.h_thread.values(pose)[:1] * MM
    return HangSolution(pose, float(h[0]), float(c[0]),
                        bool(problem.feasible(h, c, settings, thread_mm=thread)[0]),
                        problem.evaluations - start_evals, time.perf_counter() - t0,
                        thread_mm=None if thread is None else float(thread[0]))
