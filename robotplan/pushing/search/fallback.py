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

from robotplan.pushing.program.skeleton import SkeletonSpace
from robotplan.pushing.search.planner import SearchResult, merge_results
from robotplan.pushing.search.request import SearchRequest
from robotplan.pushing.search.scene_search import search_scene

__all__ = ["side_by_side", "tail_and_fresh"]


def side_by_side(request: SearchRequest) -> bool:
    """Whether a re-plan runs its tail and its fresh search side by side: a free pusher's
    pose goal warm started from a tail, with a core for each."""
    return (request.guesses is not None and request.workers >= 2
            and request.task.goal == "pose" and not request.task.arms)


def _fresh(request: SearchRequest) -> tuple[SearchResult, list[SkeletonSpace]]:
    """The fresh search in a helper process; the spaces in the candidates' order (ids do
    not survive the pipe)."""
    result, spaces = search_scene(request)
    return result, [spaces[id(s)] for s in result.candidates]


def tail_and_fresh(request: SearchRequest) -> tuple[SearchResult, dict[int, SkeletonSpace]]:
    """The tail (``request.skeleton`` from ``request.guesses``) in this process and the
    fresh search in a forked helper, one program at a time each; the tail's result when it
    solves, else both merged, and each candidate's space (by ``id`` of its solution)."""
    tail = request.but(workers=1, replan=True)
    fresh = tail.but(skeleton=None, guesses=None, exhaustive=False, last_resort=None)
    with get_context("fork").Pool(1) as helper:
        pending = helper.apply_async(_fresh, (fresh,))
        result, spaces = search_scene(tail.but(last_resort=None))
        if result.solved:
            return result, spaces
        again, again_spaces = pending.get()
    spaces.update({id(s): sp for s, sp in zip(again.candidates, again_spaces, strict=True)})
    return merge_results(result, again), spaces
