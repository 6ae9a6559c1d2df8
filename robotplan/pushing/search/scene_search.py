"""The skeleton search over a whole scene: candidate tiers (a given skeleton, a chain, the
free pusher, or each arm init frame pruned by reach), then routes around obstacles, or for a
free pusher's region goal pushes fitted to a pose inside the region; one Drake program per
candidate (:func:`robotplan.pushing.search.planner.search_push`)."""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from dataclasses import replace

from robotplan.functionals.clearance import OBSTACLE_MARGIN
from robotplan.pushing.models.loading import dynamics_kind
from robotplan.pushing.program.chain_guess import objects_touch
from robotplan.pushing.program.reach import reach_check
from robotplan.pushing.program.settings import ProgramSettings, with_overrides
from robotplan.pushing.program.settings import settings_for as program_settings
from robotplan.pushing.program.skeleton import (
    Skeleton,
    SkeletonSpace,
    actor_candidates,
    chain_candidates,
    parse_skeleton,
    space_for,
)
from robotplan.pushing.program.solution import Solution
from robotplan.pushing.search.planner import FEASIBLE, SearchResult, merge_results, search_push
from robotplan.pushing.search.pose_search import (
    search_pose_budgets,
    search_region_fits_budgets,
)
from robotplan.pushing.search.request import SearchRequest
from robotplan.pushing.search.route import routed_candidates
from robotplan.pushing.search.tiers import Tier, budget_settings, load_budgets, load_tiers
from robotplan.scene.task import PushTask

__all__ = ["budget_spent", "candidate_table", "candidate_tiers", "metres", "search_scene",
           "task_settings"]


def budget_spent(result: SearchResult, time_budget: float | None) -> bool:
    """Whether the search is past ``time_budget`` seconds with some plan in hand: then it
    starts no further tier or route search (each would solve at least one program per
    worker before looking at the clock). Without any plan it goes on."""
    return (time_budget is not None and result.best is not None
            and result.seconds >= time_budget)


def given_skeleton(task: PushTask, skeleton: str | Skeleton) -> Skeleton:
    """A skeleton the caller names (the CLI's notation, or a ``Skeleton``), checked against
    the task's chain."""
    obj, chain = task.obj, task.chained
    given = (skeleton if isinstance(skeleton, Skeleton)
             else parse_skeleton(skeleton, task.actors[0], obj))
    if given.chained is not None and (chain is None or given.chained != chain):
        raise ValueError(f"{skeleton!r}: {obj} may push {given.chained!r} only in a scene "
                         f"where the pusher touches {obj} and not the goal's object")
    if chain is not None and given.chained is None:
        raise ValueError(f"{skeleton!r}: the pusher may not touch {chain}: end with a "
                         f"push in which {obj} pushes it, e.g. 'push@0,push@0>{chain}'")
    return given


def candidate_tiers(request: SearchRequest) -> Iterator[tuple[list, SkeletonSpace]]:
    """The candidates tier by tier, each with its space; the search moves on to the next tier
    only when no candidate of a tier plans. One tier for a given skeleton, a chain or the
    free pusher; for arms one per init frame (the object's faces, then around the object as
    seen from the goal), every choice of arm pruned by reach before any program is solved,
    and a frame with nothing in reach skipped. Lazy: a frame is pruned when it is reached."""
    task, max_pushes = request.task, request.max_pushes
    space = space_for(task)
    if request.skeleton:
        yield [given_skeleton(task, request.skeleton)], space
    elif task.chained is not None:
        # one push more than max_pushes: the first push alone brings obj to the target
        bodies = task.scene.bodies
        apart = not objects_touch(bodies[task.obj], bodies[task.chained])
        yield chain_candidates(space, task.actors[0], task.obj, task.chained,
                               max_pushes + apart, min_alone=int(apart)), space
    elif not task.arms:
        yield space.candidates(task.actors[0], task.obj, max_pushes), space
    else:
        for frame in dict.fromkeys((space.init_frame, "goal")):
            framed = replace(space, init_frame=frame)
            kept = _arm_candidates(request, framed)
            if kept:
                yield kept, framed


def _arm_candidates(request: SearchRequest, space: SkeletonSpace) -> list:
    """Every choice of arm per phase and init point in ``space``, pruned by reach."""
    task = request.task
    every = actor_candidates(space, list(task.actors), task.obj, request.max_pushes,
                             task.touch_actor)
    kept = [sk for sk in every if reach_check(task, sk, space) is None]
    request.say(f"skeletons: {len(kept)} of {len(every)} within the arms' reach "
                f"(init points in the {space.init_frame} frame)")
    return kept


def _search_routes(request: SearchRequest, settings: ProgramSettings, space: SkeletonSpace
                   ) -> tuple[SkeletonSpace, SearchResult]:
    """Around obstacles, when the pushes of the plain search fail: straight face pushes
    along routes that keep the object clear of every obstacle to the goal region's centre
    (robotplan.pushing.search.route; none for a touch goal)."""
    task = request.task
    routed, skeletons = space, []
    if task.region is not None:
        routed, skeletons = routed_candidates(task, space, settings.guess_speed)
    request.say(f"no plan with up to {request.max_pushes} pushes; trying {len(skeletons)} "
                f"routes around the obstacles ({routed.steps_per_phase} steps per phase)")
    if not skeletons:
        return routed, SearchResult(None)
    routes = program_settings("routes", base=settings)
    return routed, search_push(request.but(guesses=None), skeletons, routes, routed)


def _margin_note(s: Solution) -> str:
    """Why a feasible plan around obstacles was not taken, if that is the reason."""
    if s.clearance >= OBSTACLE_MARGIN or s.violation > FEASIBLE:
        return ""
    return f", {100 * s.clearance:.1f} cm from an obstacle (margin {100 * OBSTACLE_MARGIN:g})"


def metres(value: float) -> float | None:
    return round(value, 4) if math.isfinite(value) else None


def candidate_table(result: SearchResult, dynamics: str = "flow") -> str:
    """One line per solved candidate; ``dynamics``: the kind of the learned row (its RMS
    column is H_q's for ``rigid``, else H_F's)."""
    rms = "H_q rms mm" if dynamics == "rigid" else "H_F rms mm"
    lines = [f"{'#':>2}  {'skeleton':<40} {'violation':>10} {'cost':>9} {rms:>10} "
             f"{'seconds':>8}  status"]
    for i, s in enumerate(result.candidates):
        mark = " <- best" if s is result.best else ""
        lines.append(f"{i:>2}  {s.skeleton.describe():<40} {s.violation:>10.3g} "
                     f"{s.cost:>9.3g} {s.dynamics_rms_mm:>10.2f} {s.seconds:>8.1f}  "
                     f"{s.status}{_margin_note(s)}{mark}")
    return "\n".join(lines)


def task_settings(task: PushTask, solver: str = "snopt", dynamics: str = "flow"
                 ) -> ProgramSettings:
    """The program settings of a task's actors (the arms' overlay, or the free pusher's),
    goal (the pose goals' overlay) and learned dynamics (F_q's overlay, ``rigid``)."""
    classes = tuple(c for c in task.classes if c in ("arms", "pose")) + (
        ("rigid",) if dynamics == "rigid" else ())
    return program_settings(*classes, solver=solver)


def _space_of_guesses(space: SkeletonSpace, candidates: list[Skeleton],
                      guesses: dict[Skeleton, dict] | None) -> SkeletonSpace:
    """``space`` with the steps per phase of the warm-start guesses among ``candidates``
    (a plan along a route has more than the default)."""
    for sk in candidates:
        guess = (guesses or {}).get(sk)
        if guess is not None:
            steps = (len(guess["q_obj"]) - 1) // len(sk.phases)
            if steps != space.steps_per_phase:
                return replace(space, steps_per_phase=steps)
    return space


def _settings_of(candidates: list[Skeleton], settings: ProgramSettings) -> ProgramSettings:
    """The routes' overlay for skeletons along a route (phases with via points), as
    :func:`_search_routes` planned them."""
    if any(p.via is not None for sk in candidates for p in sk.phases):
        return program_settings("routes", base=settings)
    return settings


def _pose_fits(request: SearchRequest, budgets: tuple[ProgramSettings, ...],
               space: SkeletonSpace) -> tuple[SearchResult, dict[int, SkeletonSpace]]:
    """The pushes fitted to the goal's pose (a given skeleton fixes their faces)."""
    task, given = request.task, request.skeleton
    if isinstance(given, str):
        given = parse_skeleton(given, task.actors[0], task.obj)
    return search_pose_budgets(request, budgets, space, given)


def _plain(request: SearchRequest, budgets: tuple[ProgramSettings, ...],
           space: SkeletonSpace) -> tuple[SearchResult, dict[int, SkeletonSpace]]:
    """The space's candidates sub-tier by sub-tier (:func:`candidate_tiers`), until one
    solves or the time budget is spent with a plan in hand."""
    result, spaces = SearchResult(None), {}
    for candidates, tier_space in candidate_tiers(request):
        tier_space = _space_of_guesses(tier_space, candidates, request.guesses)
        more = search_push(request.but(time_budget=request.left(result.seconds)), candidates,
                           _settings_of(candidates, budgets[0]), tier_space)
        spaces.update({id(s): tier_space for s in more.candidates})
        result = merge_results(result, more)
        if result.solved or budget_spent(result, request.time_budget):
            break
    return result, spaces


def _routes(request: SearchRequest, budgets: tuple[ProgramSettings, ...],
            space: SkeletonSpace) -> tuple[SearchResult, dict[int, SkeletonSpace]]:
    routed, result = _search_routes(request, budgets[0], space)
    return result, {id(s): routed for s in result.candidates}


TIER_SEARCHES = {"pose_fits": _pose_fits, "region_fits": search_region_fits_budgets,
                 "plain": _plain, "routes": _routes}
"""The search of each kind of tier candidates (``skeletons/tiers.yaml``)."""


def _runs(tier: Tier, charged: SearchResult, request: SearchRequest) -> bool:
    """Whether ``tier`` is tried after the charged tiers' result ``charged``."""
    if not tier.when.holds(request):
        return False
    if tier.runs == "always":
        return True
    in_budget = not budget_spent(charged, request.time_budget)
    return not charged.solved and (tier.runs == "unsolved" or in_budget)


def _ends(tier: Tier, result: SearchResult, last_resort: float | None) -> bool:
    """Whether the search ends after ``tier`` gave ``result``."""
    return {"never": False, "candidates": bool(result.candidates),
            "settled": result.settled(last_resort), "solved": result.solved}[tier.ends]


def search_scene(request: SearchRequest) -> tuple[SearchResult, dict[int, SkeletonSpace]]:
    """Search the task's tiers in the order of the tier table (``skeletons/tiers.yaml``,
    :mod:`robotplan.pushing.search.tiers`): each tier the task and the request qualify for, while
    the result so far lets it run, until one ends the search; the result and each
    candidate's skeleton space (by ``id`` of its solution). A warm start
    (``request.guesses``) solves with the smaller budget of a start close to a plan
    (``quick`` of the table's budgets) as its own.
    The time budget counts the seconds of the charged tiers; past ``request.deadline`` no
    further tier starts."""
    task = request.task
    own = with_overrides(task_settings(task, request.solver, dynamics_kind(request.model_dir)),
                         request.program)
    named = {name: budget_settings(name, own) for name in load_budgets()}
    named["own"] = named["quick"] if request.guesses else own  # a warm start: a re-plan
    space = space_for(task)
    apart, charged, spaces = SearchResult(None), SearchResult(None), {}
    tiers = load_tiers()
    kinds = request.candidate_kinds
    if kinds is not None:
        unknown = set(kinds) - {t.candidates for t in tiers}
        if unknown:
            raise ValueError(f"candidate kinds {sorted(unknown)}: not in the tier table; one "
                             f"of {sorted({t.candidates for t in tiers})}")
        tiers = tuple(t for t in tiers if t.candidates in kinds)
    for tier in tiers:
        if request.past_deadline():
            request.say(f"past the deadline: tier {tier.name!r} and those after it do not start")
            break
        if not _runs(tier, charged, request):
            continue
        budgets = tuple(named[b] for b in tier.budgets)
        timed = request.but(time_budget=request.left(charged.seconds))
        t0 = time.perf_counter()
        result, more = TIER_SEARCHES[tier.candidates](timed, budgets, space)
        # the tier's wall clock: its programs and what made their candidates (the fits)
        result = replace(result, seconds=max(result.seconds, time.perf_counter() - t0))
        spaces.update(more)
        if tier.charged:
            charged = merge_results(charged, result)
        else:
            apart = merge_results(apart, result)
        if _ends(tier, result if tier.ends != "solved" else charged, request.last_resort):
            break
    return merge_results(apart, charged), spaces
