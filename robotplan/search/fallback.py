"""A re-plan's tail and its fresh search side by side.

A closed-loop re-plan first tries the current plan's tail (one program, warm started) and
searches afresh only when that does not solve. For a pose goal the fresh search is the
fitted pushes' tier: a fit in closed form and one or two short programs. Run one after the
other, a tail that does not solve (0.55–0.95 s) comes on top of the fresh search's ~1.3 s;
run side by side, one process each, the fresh search's result is ready about when the
tail's verdict is, and is dropped unheard when the tail solves
(measured: docs/experiments.md#side-by-side). The result is the one the sequence gives:
the tail's when it solves, else both merged.
"""

from __future__ import annotations

from multiprocessing import get_context
from pathlib import Path

from robotplan.program.skeleton import Skeleton, SkeletonSpace
from robotplan.scene import Scene
from robotplan.search.planner import SearchResult, merge_results
from robotplan.search.scene_search import search_scene

__all__ = ["side_by_side", "tail_and_fresh"]


def side_by_side(scene: Scene, workers: int, guesses: dict | None) -> bool:
    """Whether a re-plan runs its tail and its fresh search side by side: a free pusher's
    pose goal warm started from a tail, with a core for each."""
    return (guesses is not None and workers >= 2 and scene.goal.type == "pose"
            and not scene.robots)


def _fresh(args: tuple) -> tuple[SearchResult, list[SkeletonSpace]]:
    """The fresh search in a helper process; the spaces in the candidates' order (ids do
    not survive the pipe)."""
    scene, model_dir, solver, max_pushes, progress, quiet, time_budget, program = args
    result, spaces = search_scene(scene, model_dir, solver, 1, None, max_pushes, progress,
                                  False, quiet, time_budget, program=program, replan=True)
    return result, [spaces[id(s)] for s in result.candidates]


def tail_and_fresh(scene: Scene, model_dir: Path, solver: str, skeleton: Skeleton,
                   guesses: dict, max_pushes: int, progress: bool, exhaustive: bool,
                   quiet: bool, time_budget: float | None, program: dict | None
                   ) -> tuple[SearchResult, dict[int, SkeletonSpace]]:
    """The tail (``skeleton`` from ``guesses``) in this process and the fresh search in a
    forked helper, one program at a time each; the tail's result when it solves, else both
    merged, and each candidate's space (by ``id`` of its solution)."""
    args = (scene, model_dir, solver, max_pushes, progress, quiet, time_budget, program)
    with get_context("fork").Pool(1) as helper:
        pending = helper.apply_async(_fresh, (args,))
        result, spaces = search_scene(scene, model_dir, solver, 1, skeleton, max_pushes,
                                      progress, exhaustive, quiet, time_budget, guesses,
                                      program, replan=True)
        if result.solved:
            return result, spaces
        again, again_spaces = pending.get()
    spaces.update({id(s): sp for s, sp in zip(again.candidates, again_spaces, strict=True)})
    return merge_results(result, again), spaces
