"""Finding a hanging pose (paper §7.1.1–7.1.2, app. A.5): optimisation restarted from random
poses (*optimisation + sampling*), one optimisation (*optimisation only*), or pure sampling
of poses until H_hang < κ and H_coll is within bounds (*sampling only*, per threshold κ).
All share one budget of functional evaluations (the paper's 20,000)."""

from __future__ import annotations

import time

import numpy as np

from robotplan.geometry.transforms import uniform_poses
from robotplan.program.hang_program import (
    HANG_DEFAULTS,
    HangProblem,
    HangSettings,
    HangSolution,
    solve_hang_once,
)

__all__ = ["optimise_hang", "sample_hang"]

SAMPLE_BATCH = 64  # poses scored per network call while sampling


def _random_starts(problem: HangProblem, rng: np.random.Generator, n: int) -> np.ndarray:
    return uniform_poses(rng, (problem.lo + problem.hi) / 2, float(problem.hi[0] - problem.lo[0]),
                         n)


def optimise_hang(problem: HangProblem, rng: np.random.Generator,
                  settings: HangSettings = HANG_DEFAULTS, restarts: int | None = None
                  ) -> HangSolution:
    """SNOPT from random poses until a feasible pose, ``restarts`` solves (default
    ``settings.restarts``; 1 = optimisation only) or the evaluation budget is spent. Returns
    the first feasible solution, else the one with the least H_hang."""
    t0 = time.perf_counter()
    problem.evaluations = 0
    best: HangSolution | None = None
    n = settings.restarts if restarts is None else restarts
    solves = 0
    for X0 in _random_starts(problem, rng, n):
        sol = solve_hang_once(problem, X0, settings)
        solves += 1
        if best is None or sol.feasible or sol.h_hang < best.h_hang:
            best = sol
        if sol.feasible or problem.evaluations >= settings.evaluations:
            break
    assert best is not None
    best.restarts, best.evaluations = solves, problem.evaluations
    best.seconds = time.perf_counter() - t0
    best.method = "optimisation" if n > 1 else "optimisation only"
    return best


def sample_hang(problem: HangProblem, rng: np.random.Generator, kappa: float,
                settings: HangSettings = HANG_DEFAULTS) -> HangSolution:
    """Random poses, scored in batches, until one has H_hang < κ and H_coll within bounds, or
    the evaluation budget is spent (then the least H_hang drawn, not feasible)."""
    t0 = time.perf_counter()
    problem.evaluations = 0
    best_h, best_X, best_c = np.inf, None, np.inf
    while problem.evaluations < settings.evaluations:
        n = min(SAMPLE_BATCH, settings.evaluations - problem.evaluations)
        X = _random_starts(problem, rng, n)
        h = problem.hang_values(X)
        c = np.full(n, np.inf)
        below = np.nonzero(h <= kappa)[0]  # H_coll only where H_hang predicts success
        if len(below):
            c[below] = problem.collision_cm3(X[below])
        ok = problem.feasible(h, c, settings, kappa)
        if ok.any():
            i = int(np.argmax(ok))
            return HangSolution(X[i], float(h[i]), float(c[i]), True, problem.evaluations,
                                time.perf_counter() - t0, method=f"sampling κ={kappa}")
        i = int(np.argmin(h))
        if h[i] < best_h:
            best_h, best_X, best_c = float(h[i]), X[i], float(c[i])
    return HangSolution(best_X, best_h, best_c, False, problem.evaluations,
                        time.perf_counter() - t0, method=f"sampling κ={kappa}")
