"""Finding a hanging pose (paper §7.1.1–7.1.2, app. A.5): optimisation restarted from new
starts (*optimisation + sampling*; random poses in the paper, threaded on the arm by
default here: :mod:`robotplan.hanging.search.starts`), one optimisation (*optimisation
only*), or pure sampling of poses until H_hang < κ and H_coll is within bounds (*sampling
only*, per threshold κ).
All share one budget of functional evaluations (the paper's 20,000)."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from robotplan.geometry.transforms import perturbed_poses
from robotplan.hanging.program.problem import (
    HANG_DEFAULTS,
    HangProblem,
    HangSettings,
    HangSolution,
    solve_hang_once,
)
from robotplan.hanging.search.starts import start_pose, uniform_starts

__all__ = ["optimise_hang", "robust_median", "sample_hang"]

SAMPLE_BATCH = 64  # poses scored per network call while sampling


def robust_median(problem: HangProblem, pose: np.ndarray, rng: np.random.Generator,
                  settings: HangSettings) -> float:
    """The median H_hang over ``settings.robust_samples`` poses about ``pose`` (they count
    as evaluations)."""
    about = perturbed_poses(rng, pose, settings.robust_shift, settings.robust_turn,
                            settings.robust_samples)
    return float(np.median(problem.hang_values(about)))


def _better(sol: HangSolution, best: HangSolution | None) -> bool:
    """Feasible beats infeasible; among feasible poses the lower check network's value (where
    checked), then the lower neighbourhood median (where checked), else the lower H_hang."""
    if best is None or sol.feasible != best.feasible:
        return best is None or sol.feasible
    for key in ("check_h", "robust_h"):
        a, b = getattr(sol, key), getattr(best, key)
        if a is not None and b is not None and a != b:
            return a < b
    return sol.h_hang < best.h_hang


def optimise_hang(problem: HangProblem, rng: np.random.Generator,
                  settings: HangSettings = HANG_DEFAULTS, restarts: int | None = None,
                  accept: Callable[[HangSolution], bool] | None = None,
                  resume: HangSolution | None = None) -> HangSolution:
    """SNOPT from starts (:func:`~robotplan.hanging.search.starts.start_pose`: threaded on the
    arm with ``settings.threading``, else uniform) until a feasible pose, ``restarts``
    solves (default ``settings.restarts``; 1 = optimisation only) or the evaluation budget
    is spent. Returns the first feasible solution, else the one with the least H_hang. With
    ``settings.robust_samples`` a feasible pose ends the search only where H_hang is low
    about it too (:func:`robust_median` ≤ ``robust_kappa``), and with a check network
    (``problem.check``) only where that network's value is ≤ ``check_kappa`` too; else the
    search goes on and returns the first such pose, or the feasible one that came closest.

    ``accept``: a check of each feasible pose beyond the functionals (a drop in the
    simulator, the closed loop's); a pose it refuses does not end the search; when none
    passes, the search returns the feasible pose of least H_hang (of least median where
    checked).
    ``resume``: an earlier result of this search whose pose was refused: the search goes on
    from its solves and evaluations (same ``rng``), within the same budget."""
    t0 = time.perf_counter()
    problem.evaluations = resume.evaluations if resume is not None else 0
    best: HangSolution | None = replace(resume) if resume is not None else None
    n = settings.restarts if restarts is None else restarts
    solves = resume.restarts if resume is not None else 0
    spent = resume.seconds if resume is not None else 0.0
    while solves < n and problem.evaluations < settings.evaluations:
        X0, part = start_pose(problem, rng, settings)
        sol = solve_hang_once(problem, X0, settings, part)
        solves += 1
        done = sol.feasible
        if sol.feasible and settings.robust_samples:
            sol.robust_h = robust_median(problem, sol.pose, rng, settings)
            done = sol.robust_h <= settings.robust_kappa
        if sol.feasible and problem.check is not None:
            sol.check_h = problem.check_value(sol.pose)
            done = done and sol.check_h <= settings.check_kappa
        if _better(sol, best):
            best = sol
        if done and accept is not None:
            done = accept(sol)
            if done:
                best = sol
        if done:
            break
    assert best is not None, "no solve ran: restarts or evaluations of 0"
    best.restarts, best.evaluations = solves, problem.evaluations
    best.seconds = spent + time.perf_counter() - t0
    best.method = "optimisation" if n > 1 else "optimisation only"
    return best


def sample_hang(problem: HangProblem, rng: np.random.Generator, kappas: tuple[float, ...],
                settings: HangSettings = HANG_DEFAULTS) -> list[HangSolution]:
    """*Sampling only*, one run per threshold κ on one stream of random poses: a run stops at
    the first pose with H_hang ≤ κ and H_coll within bounds, or when the budget of
    evaluations is spent (then it reports the least H_hang drawn, not feasible). The runs
    share their draws, so each is the paper's procedure for its κ and all cost one stream."""
    t0 = time.perf_counter()
    problem.evaluations = 0
    open_ = dict(enumerate(kappas))
    out: dict[int, HangSolution] = {}
    best_h, best_X, best_c = np.inf, None, np.inf
    while open_ and problem.evaluations < settings.evaluations:
        n = min(SAMPLE_BATCH, settings.evaluations - problem.evaluations)
        X = uniform_starts(problem, rng, n)
        h = problem.hang_values(X)
        c = np.full(n, np.inf)
        below = np.nonzero(h <= max(open_.values()))[0]  # H_coll only where it can matter
        if len(below):
            c[below] = problem.collision_cm3(X[below])
        for k, kappa in list(open_.items()):
            ok = problem.feasible(h, c, settings, kappa)
            if ok.any():
                i = int(np.argmax(ok))
                out[k] = HangSolution(X[i], float(h[i]), float(c[i]), True,
                                      problem.evaluations - n + i + 1,
                                      time.perf_counter() - t0, method=f"sampling κ={kappa}")
                del open_[k]
        i = int(np.argmin(h))
        if h[i] < best_h:
            best_h, best_X, best_c = float(h[i]), X[i], float(c[i])
    for k, kappa in open_.items():
        out[k] = HangSolution(best_X, best_h, best_c, False, problem.evaluations,
                              time.perf_counter() - t0, method=f"sampling κ={kappa}")
    return [out[k] for k in range(len(kappas))]
