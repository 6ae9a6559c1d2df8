"""Skeleton search (paper §4, app. I.2): solve one program per candidate skeleton in parallel
processes, keep the one with the least constraint violation, then the least learned-dynamics
residual H_F, then the least cost. A plan is *solved* when it meets the constraints and its
H_F residual stays below the no-motion baseline (``PLAUSIBLE_RMS_MM``), and, around
obstacles, its objects keep ``OBSTACLE_MARGIN`` from them (open-loop pushing drifts).

Candidates are tried most promising first (init points behind the object as seen from the
goal) and the search stops at the first one that is *good enough*: feasible, with the
learned-dynamics residual of a typical real push (``ProgramSettings.good_rms_mm``), or, after
``PATIENCE_S`` seconds, as soon as it holds a solved plan. ``exhaustive=True`` solves every
candidate, as the paper does."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

import numpy as np

from robotplan.base.threads import one_thread
from robotplan.functionals.clearance import OBSTACLE_MARGIN, obstacle_clearance
from robotplan.pushing.program.settings import ProgramSettings
from robotplan.pushing.program.skeleton import Skeleton, SkeletonSpace, space_for
from robotplan.pushing.program.solution import FEASIBLE, Solution
from robotplan.pushing.program.solve import solve_skeleton
from robotplan.pushing.search.pool import Processes, run_in_pool
from robotplan.pushing.search.request import SearchRequest
from robotplan.scene import Scene
from robotplan.scene.task import PushTask

__all__ = [
    "PATIENCE_S",
    "Processes",
    "SearchResult",
    "adoptable",
    "is_solved",
    "meets_constraints",
    "merge_results",
    "past_budget",
    "run_in_pool",
    "search_push",
    "stops_search",
]

# residual RMS (mm) below which plans rank alike, and the default good-enough residual
GOOD_RMS_MM = ProgramSettings.good_rms_mm
# a plan whose H_F residual exceeds the no-motion baseline is one the learned dynamics call
# impossible: it breaks the dynamics, however well it meets the constraints
# (measured: docs/experiments.md#dynamics-residual)
PLAUSIBLE_RMS_MM = 10.0
PATIENCE_S = 30.0
"""Seconds after which a search that holds a solved plan stops at the next program it
collects, so that a search whose solved plans all miss GOOD_RMS_MM (most L-shapes: F_flow
errs more on them) does not run to its time budget (measured: docs/experiments.md#patience)."""

_worker: dict = {}


@dataclass
class SearchResult:
    best: Solution | None
    candidates: list[Solution] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def solved(self) -> bool:
        return self.best is not None and is_solved(self.best)

    def settled(self, last_resort: float | None = None) -> bool:
        """Whether this result ends a search: solved, or with a best plan the caller adopts
        unsolved (:func:`adoptable`)."""
        return self.solved or adoptable(self.best, last_resort)


_models: dict[tuple, object] = {}


def _dynamics(model_dir: str):
    """The learned dynamics of ``model_dir``, loaded once per process and version of the
    folder's files: the search loads it before it forks, so its workers (and the closed
    loop's re-plans, each a search) start without reading it again."""
    from robotplan.pushing.models.loading import load_dynamics

    folder = Path(model_dir)
    files = tuple(sorted((f.name, f.stat().st_mtime_ns, f.stat().st_size)
                         for f in folder.iterdir() if f.is_file()))
    key = (str(folder.resolve()), files)
    if key not in _models:
        _models.clear()  # one folder at a time: a process plans with one model
        _models[key] = load_dynamics(folder)
    return _models[key]


def _init_worker(task: PushTask, model_dir: str, settings: ProgramSettings,
                 space: SkeletonSpace, guesses: dict[Skeleton, dict] | None = None) -> None:
    one_thread()  # one process per core (robotplan.base.threads)
    _worker.update(task=task, model=_dynamics(model_dir), settings=settings,
                   space=space, guesses=guesses or {})


def _solve(skeleton: Skeleton) -> Solution:
    w = _worker
    sol = solve_skeleton(w["task"], skeleton, w["model"], w["space"], w["settings"],
                         guess=w["guesses"].get(skeleton))
    sol.clearance = plan_clearance(w["task"].scene, sol)
    return sol


def plan_clearance(scene: Scene, sol: Solution) -> float:
    """How close the plan's moved objects come to the obstacles (m; inf without any)."""
    obj = sol.skeleton.phases[0].object
    moved = {obj: sol.q_obj, **sol.q_others}
    return min((obstacle_clearance(scene, name, np.asarray(q)) for name, q in moved.items()
                if len(q)), default=math.inf)


def _clearance_short(s: Solution) -> float:
    """How much the plan misses OBSTACLE_MARGIN by (m; 0 when it keeps it)."""
    return max(0.0, OBSTACLE_MARGIN - s.clearance)


def plan_rank(s: Solution) -> tuple[float, float, float, float]:
    """The least constraint violation, then the least shortfall of the obstacle margin, then
    the least H_F residual (ties below the noise floor GOOD_RMS_MM), then the least cost."""
    rms = s.dynamics_rms_mm if s.dynamics_mm2.size else float("inf")
    return (max(s.violation, FEASIBLE), _clearance_short(s), max(rms, GOOD_RMS_MM), s.cost)


def meets_constraints(s: Solution, violation: float = FEASIBLE) -> bool:
    """Every constraint met (scaled violation at most ``violation``) and the obstacle margin
    kept, whatever the learned dynamics say of the plan."""
    return s.violation <= violation and _clearance_short(s) == 0.0


def adoptable(s: Solution | None, last_resort: float | None) -> bool:
    """Whether ``s`` is a plan a caller adopts unsolved (the closed loop's last resort): one
    that meets the constraints within ``last_resort`` (None: only solved plans are adopted)."""
    return last_resort is not None and s is not None and meets_constraints(s, last_resort)


def is_solved(s: Solution) -> bool:
    """Meets the constraints, is plausible under the learned dynamics and keeps the
    obstacle margin (what :attr:`SearchResult.solved` asks of the best plan)."""
    return meets_constraints(s) and s.dynamics_rms_mm <= PLAUSIBLE_RMS_MM


def good_enough(s: Solution, good_rms_mm: float = GOOD_RMS_MM) -> bool:
    """Solved, with a learned-dynamics residual of at most ``good_rms_mm`` (that of a
    typical real push)."""
    return is_solved(s) and s.dynamics_rms_mm <= good_rms_mm


def stops_search(sol: Solution, holds_solved: bool, elapsed: float,
                 time_budget: float | None, exhaustive: bool,
                 good_rms_mm: float = GOOD_RMS_MM) -> bool:
    """Whether the search stops on collecting ``sol``, ``elapsed`` seconds in: past the time
    budget with a solved plan in hand (``holds_solved``, ``sol`` included); otherwise (unless
    ``exhaustive``) on a good-enough plan (residual at most ``good_rms_mm``), or past
    PATIENCE_S seconds with a solved plan in hand. Past the budget without one it waits
    for the programs already running (:func:`search_push` starts no more): a pose goal's
    fitted programs run a minute or more each, and the one still running is often the one
    that plans (measured: docs/experiments.md#pose-goals)."""
    if past_budget(elapsed, time_budget) and holds_solved:
        return True
    return not exhaustive and (good_enough(sol, good_rms_mm)
                               or (holds_solved and elapsed > PATIENCE_S))


def past_budget(elapsed: float, time_budget: float | None) -> bool:
    """Whether ``elapsed`` seconds are past ``time_budget`` (None: no budget)."""
    return time_budget is not None and elapsed > time_budget


def order_candidates(task: PushTask, skeletons: list[Skeleton],
                     space: SkeletonSpace | None = None) -> list[Skeleton]:
    """Most promising first: pushes from init points behind the object (seen from the goal),
    then fewer pushes. Stable for ties."""
    scene, space, region = task.scene, space or space_for(task), task.region
    if region is None:
        return list(skeletons)

    def score(sk: Skeleton) -> tuple[float, int]:
        obj = scene.bodies[sk.phases[0].object]
        away = np.array(obj.pose[:2]) - np.array(region.pose[:2])
        away = away / max(float(np.linalg.norm(away)), 1e-9)
        dirs = [space.init_angle(p.init, obj.pose[:2], region.pose[:2], obj.pose[2])
                for p in sk.phases
                if p.mode == "push"]
        align = np.mean([away @ np.array([math.cos(a), math.sin(a)]) for a in dirs])
        return (-round(float(align), 6), sk.pushes)

    return sorted(skeletons, key=score)


def search_push(request: SearchRequest, skeletons: list[Skeleton],
                settings: ProgramSettings | None = None, space: SkeletonSpace | None = None,
                ordered: bool = False) -> SearchResult:
    """Solve the skeletons (``request.workers`` processes; this one where
    ``settings.parallel`` is off, or one program is queued and no deadline set), most
    promising first, and pick the best; unless ``request.exhaustive``, stop at the first
    good-enough plan (``settings.good_rms_mm``) or, after ``PATIENCE_S`` seconds, at the
    first program collected while a solved plan is in hand; start no program after
    ``request.time_budget`` seconds once one has been collected, and stop there once a
    solved plan is in hand, else when the programs running end (the best so far wins);
    start none past ``request.deadline``, and there drop those running in other processes.
    ``request.guesses``: the learned program's initial guess by skeleton (a warm start skips
    the kinematic stage). ``ordered``: the skeletons come most promising first already."""
    from tqdm import tqdm

    settings = settings or ProgramSettings()
    t0 = time.time()
    task, model_dir, workers = request.task, str(request.model_dir), request.workers
    time_budget, exhaustive = request.time_budget, request.exhaustive
    space = space or space_for(task)
    args = (task, model_dir, settings, space, dict(request.guesses or {}))
    queue = list(skeletons) if ordered else order_candidates(task, skeletons, space)
    solutions: list[Solution] = []
    holds_solved = False
    bar = tqdm(total=len(queue), unit="program", desc="skeletons",
               disable=not request.progress)

    def collect(sol: Solution) -> bool:
        nonlocal holds_solved
        solutions.append(sol)
        bar.update()
        bar.set_postfix(best_violation=f"{min(s.violation for s in solutions):.3g}")
        holds_solved = holds_solved or is_solved(sol)
        return stops_search(sol, holds_solved, time.time() - t0, time_budget, exhaustive,
                            settings.good_rms_mm)

    def may_start() -> bool:  # past the budget only while nothing has been collected
        return (not request.past_deadline()
                and (not past_budget(time.time() - t0, time_budget) or not solutions))

    # one queued program gains nothing from the processes but their start (~0.2 s), unless a
    # deadline must be able to drop it
    if (workers <= 1 or not settings.parallel
            or (len(queue) <= 1 and request.deadline is None)):
        _init_worker(*args)
        for sk in queue:
            if not may_start() or collect(_solve(sk)):
                break
    else:
        _dynamics(model_dir)  # loaded here, inherited by the forked workers
        run_in_pool(_solve, queue, Processes(workers, partial(_init_worker, *args),
                                             request.deadline), collect, may_start)
    bar.close()
    order = {sk: i for i, sk in enumerate(queue)}
    solutions.sort(key=lambda s: order[s.skeleton])
    best = min(solutions, key=plan_rank) if solutions else None
    return SearchResult(best, solutions, time.time() - t0)


def merge_results(a: SearchResult, b: SearchResult) -> SearchResult:
    """One result from two searches run one after the other."""
    every = a.candidates + b.candidates
    best = min(every, key=plan_rank) if every else None
    return SearchResult(best, every, a.seconds + b.seconds)
