"""Skeleton search (paper §4, app. I.2): solve one program per candidate skeleton in parallel
processes, keep the one with the least constraint violation, then the least cost."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from multiprocessing import get_context
from pathlib import Path

import torch

from robotplan.program import ProgramSettings, PushProgram, Solution
from robotplan.scene import Scene
from robotplan.skeleton import Skeleton, load_skeleton_space

__all__ = ["SearchResult", "search_push"]

FEASIBLE = 1e-2  # largest scaled constraint violation that counts as solved

_worker: dict = {}


@dataclass
class SearchResult:
    best: Solution | None
    candidates: list[Solution] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def solved(self) -> bool:
        return self.best is not None and self.best.violation <= FEASIBLE


def _init_worker(scene: Scene, model_dir: str, settings: ProgramSettings) -> None:
    from robotplan.learned.dynamics import load_model

    torch.set_num_threads(1)  # one thread per process (DESIGN §4)
    _worker.update(scene=scene, model=load_model(model_dir), settings=settings,
                   space=load_skeleton_space())


def _solve(skeleton: Skeleton) -> Solution:
    w = _worker
    return PushProgram(w["scene"], skeleton, w["model"], w["space"], w["settings"]).solve()


def _rank(s: Solution) -> tuple[float, float]:
    return (max(s.violation, FEASIBLE), s.cost)


def search_push(scene: Scene, model_dir: str | Path, skeletons: list[Skeleton],
                settings: ProgramSettings | None = None, workers: int = 2,
                progress: bool = True) -> SearchResult:
    """Solve every skeleton (a process per core) and pick the best."""
    from tqdm import tqdm

    settings = settings or ProgramSettings()
    t0 = time.time()
    args = (scene, str(model_dir), settings)
    solutions: list[Solution] = []
    bar = tqdm(total=len(skeletons), unit="program", desc="skeletons", disable=not progress)
    if workers <= 1:
        _init_worker(*args)
        for sk in skeletons:
            solutions.append(_solve(sk))
            bar.update()
    else:
        with get_context("fork").Pool(workers, _init_worker, args) as pool:
            for sol in pool.imap_unordered(_solve, skeletons):
                solutions.append(sol)
                bar.update()
                bar.set_postfix(best_violation=f"{min(s.violation for s in solutions):.3g}")
    bar.close()
    order = {sk: i for i, sk in enumerate(skeletons)}
    solutions.sort(key=lambda s: order[s.skeleton])
    best = min(solutions, key=_rank) if solutions else None
    return SearchResult(best, solutions, time.time() - t0)
