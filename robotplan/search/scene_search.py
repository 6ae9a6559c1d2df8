"""The skeleton search over a whole scene: candidate tiers (a given skeleton, a chain, the
free pusher, or each arm init frame pruned by reach), then routes around obstacles, or for a
free pusher's region goal pushes fitted to a pose inside the region; one Drake program per
candidate (:func:`robotplan.search.planner.search_push`)."""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import replace
from pathlib import Path

from robotplan.functionals.clearance import OBSTACLE_MARGIN
from robotplan.models.loading import dynamics_kind
from robotplan.program.arm_program import reach_check
from robotplan.program.chain_program import objects_touch
from robotplan.program.settings import ProgramSettings, with_overrides
from robotplan.program.settings import settings_for as program_settings
from robotplan.program.skeleton import (
    Skeleton,
    SkeletonSpace,
    actor_candidates,
    chain_candidates,
    parse_skeleton,
    space_for,
)
from robotplan.program.solution import Solution
from robotplan.scene import Scene
from robotplan.search.planner import FEASIBLE, SearchResult, merge_results, search_push
from robotplan.search.pose_search import (
    search_pose_budgets,
    search_region_fits,
    search_region_fits_budgets,
)
from robotplan.search.route import routed_candidates
from robotplan.search.scene_classes import chain_target, scene_classes

__all__ = ["UnsupportedScene", "budget_spent", "candidate_table", "candidate_tiers",
           "check_supported", "metres", "search_scene", "settings_for"]


class UnsupportedScene(ValueError):
    """The scene is valid but needs a planner feature that is not built yet."""


def check_supported(scene: Scene) -> tuple[str, list[str]]:
    """The object the actors touch and the actors (pushers or arms) of a scene the
    planner handles."""
    chain = chain_target(scene)
    if chain is not None and scene.goal.type != "touch":
        return chain[0], [scene.pushers[0].name]
    if len(scene.objects) != 1:
        raise UnsupportedScene("objects: more than one movable object is planned only when "
                               "the pusher touches one of two and it pushes the goal's object "
                               "(pushers[0].touches)")
    if scene.robots and scene.pushers:
        raise UnsupportedScene("pushers: free pushers beside robot arms are not planned yet")
    if not scene.robots and len(scene.pushers) != 1:
        raise UnsupportedScene("pushers: only one free pusher is planned yet")
    if scene.goal.type == "touch" and not scene.robots:
        raise UnsupportedScene("goal: touch goals are planned for robot arms only")
    actors = [r.name for r in scene.robots] or [scene.pushers[0].name]
    return scene.objects[0].name, actors


def budget_spent(result: SearchResult, time_budget: float | None) -> bool:
    """Whether the search is past ``time_budget`` seconds with some plan in hand: then it
    starts no further tier or route search (each would solve at least one program per
    worker before looking at the clock). Without any plan it goes on."""
    return (time_budget is not None and result.best is not None
            and result.seconds >= time_budget)


def candidate_tiers(scene: Scene, obj: str, actors: list[str], skeleton: str | Skeleton | None,
                     max_pushes: int, quiet: bool) -> Iterator[tuple[list, SkeletonSpace]]:
    """The candidates tier by tier, each with its space; the search moves on to the next tier
    only when no candidate of a tier plans. One tier for a given skeleton, a chain or the
    free pusher; for arms one per init frame (the object's faces, then around the object as
    seen from the goal), every choice of arm pruned by reach before any program is solved,
    and a frame with nothing in reach skipped. Lazy: a frame is pruned when it is reached."""
    space = space_for(scene)
    chain = chain_target(scene)
    if skeleton:
        given = (skeleton if isinstance(skeleton, Skeleton)
                 else parse_skeleton(skeleton, actors[0], obj))
        if given.chained is not None and (chain is None or given.chained != chain[1]):
            raise ValueError(f"{skeleton!r}: {obj} may push {given.chained!r} only in a scene "
                             f"where the pusher touches {obj} and not the goal's object")
        if chain is not None and given.chained is None:
            raise ValueError(f"{skeleton!r}: the pusher may not touch {chain[1]}: end with a "
                             f"push in which {obj} pushes it, e.g. 'push@0,push@0>{chain[1]}'")
        yield [given], space
    elif chain is not None:
        # one push more than max_pushes: the first push alone brings obj to the target
        apart = not objects_touch(scene.bodies[chain[0]], scene.bodies[chain[1]])
        yield chain_candidates(space, actors[0], *chain, max_pushes + apart,
                               min_alone=int(apart)), space
    elif not scene.robots:
        yield space.candidates(actors[0], obj, max_pushes), space
    else:
        for frame in dict.fromkeys((space.init_frame, "goal")):
            framed = replace(space, init_frame=frame)
            kept = _arm_candidates(scene, framed, obj, actors, max_pushes, quiet)
            if kept:
                yield kept, framed


def _arm_candidates(scene: Scene, space: SkeletonSpace, obj: str, actors: list[str],
                    max_pushes: int, quiet: bool) -> list:
    """Every choice of arm per phase and init point in ``space``, pruned by reach."""
    touch = scene.goal.actor if scene.goal.type == "touch" else None
    every = actor_candidates(space, actors, obj, max_pushes, touch)
    kept = [sk for sk in every if reach_check(scene, sk, space) is None]
    if not quiet:
        print(f"skeletons: {len(kept)} of {len(every)} within the arms' reach "
              f"(init points in the {space.init_frame} frame)")
    return kept


def _search_routes(scene: Scene, obj: str, actor: str, model_dir: Path,
                   settings: ProgramSettings, space: SkeletonSpace, max_pushes: int,
                   workers: int, progress: bool, exhaustive: bool, quiet: bool,
                   time_budget: float | None) -> tuple[SkeletonSpace, SearchResult]:
    """Around obstacles, when the pushes of the plain search fail: straight face pushes
    along routes that keep the object clear of every obstacle to the goal region's centre
    (robotplan.search.route; none for a touch goal)."""
    region = scene.goal_region
    routed, skeletons = space, []
    if region is not None:
        routed, skeletons = routed_candidates(scene, actor, obj, space, region,
                                              settings.guess_speed)
    if not quiet:
        print(f"no plan with up to {max_pushes} pushes; trying {len(skeletons)} routes around "
              f"the obstacles ({routed.steps_per_phase} steps per phase)")
    if not skeletons:
        return routed, SearchResult(None)
    routes = program_settings("routes", base=settings)
    return routed, search_push(scene, model_dir, skeletons, routes, workers,
                               progress, exhaustive, time_budget, routed)


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


def settings_for(scene: Scene, solver: str = "snopt", dynamics: str = "flow"
                 ) -> ProgramSettings:
    """The program settings of a scene's actors (the arms' overlay, or the free pusher's),
    goal (the pose goals' overlay) and learned dynamics (F_q's overlay, ``rigid``)."""
    classes = tuple(c for c in scene_classes(scene) if c in ("arms", "pose")) + (
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


def search_scene(scene: Scene, model_dir: Path, solver: str = "snopt", workers: int = 2,
                 skeleton: str | Skeleton | None = None, max_pushes: int = 2,
                 progress: bool = True, exhaustive: bool = False, quiet: bool = False,
                 time_budget: float | None = None, guesses: dict[Skeleton, dict] | None = None,
                 program: Mapping[str, object] | None = None, replan: bool = False,
                 last_resort: float | None = None
                 ) -> tuple[SearchResult, dict[int, SkeletonSpace]]:
    """Search the scene's candidates tier by tier, then routes around obstacles when nothing
    plans; the result and each candidate's skeleton space (by ``id`` of its solution).
    ``guesses``: initial guesses of the learned program by skeleton (warm starts). A free
    pusher's region goal without obstacles that the plain tier does not plan gets the
    fitted pushes' tier, even past ``time_budget`` (at most four programs). ``program``:
    a user's program settings (:func:`~robotplan.program.settings.with_overrides`).
    ``replan``: a fresh search during execution; a pose goal's then runs with the
    ``replan`` overlay's budget first and its own where that does not solve, and a region
    goal's starts with the fitted pushes' tier at that budget, then at its own (the object
    has mostly come near the region by then), the plain tier following, with a
    ``time_budget`` of its own, where neither solves. ``last_resort``: the violation within
    which the caller adopts an unsolved plan that meets the constraints (the closed loop's
    last resort); such a plan from those fitted pushes ends the search there too
    (docs/experiments.md#replan-last-resort)."""
    obj, actors = check_supported(scene)
    settings = with_overrides(settings_for(scene, solver, dynamics_kind(model_dir)), program)
    replan_budget = program_settings("replan", base=settings)  # the re-plans' solver budget
    if guesses:  # a re-plan from an earlier plan
        settings = replan_budget
    result, spaces = SearchResult(None), {}  # spaces: a skeleton may recur in two tiers
    space = space_for(scene)
    if (scene.goal.type == "pose" and not guesses and not scene.robots
            and chain_target(scene) is None):
        given = parse_skeleton(skeleton, actors[0], obj) if isinstance(skeleton, str) else skeleton
        # executing: the re-plans' budget first, faster (docs/experiments.md#close-fits)
        budgets = (replan_budget, settings) if replan else (settings,)
        result, spaces = search_pose_budgets(scene, obj, actors[0], model_dir, budgets, space,
                                             max_pushes, workers, progress, exhaustive, quiet,
                                             time_budget, given)
        if result.candidates:  # the plain tier's pushes do not turn: it plans no pose goal
            return result, spaces
    fits = (scene.goal.type == "region" and skeleton is None and not guesses
            and not scene.robots and not scene.obstacles and chain_target(scene) is None)
    first = SearchResult(None)  # executing, a region goal's fitted pushes
    if fits and replan:  # (docs/experiments.md#replan-fits)
        first, spaces = search_region_fits_budgets(scene, obj, actors[0], model_dir,
                                                   (replan_budget, settings), space,
                                                   max_pushes, workers, progress, exhaustive,
                                                   quiet, last_resort)
        if first.settled(last_resort):
            return first, spaces
    for candidates, space in candidate_tiers(scene, obj, actors, skeleton, max_pushes, quiet):
        left = None if time_budget is None else max(0.0, time_budget - result.seconds)
        space = _space_of_guesses(space, candidates, guesses)
        more = search_push(scene, model_dir, candidates, _settings_of(candidates, settings),
                           workers, progress, exhaustive, left, space, guesses=guesses)
        spaces.update({id(s): space for s in more.candidates})
        result = merge_results(result, more)
        if result.solved or budget_spent(result, time_budget):
            break
    if (not result.solved and not budget_spent(result, time_budget) and scene.obstacles
            and skeleton is None and not scene.robots):
        left = None if time_budget is None else max(0.0, time_budget - result.seconds)
        routed, extra = _search_routes(scene, obj, actors[0], model_dir, settings, space,
                                       max_pushes, workers, progress, exhaustive, quiet, left)
        spaces.update({id(s): routed for s in extra.candidates})
        result = merge_results(result, extra)
    if not result.solved and fits and not replan:  # executing, they came first
        fitted, extra = search_region_fits(scene, obj, actors[0], model_dir, settings, space,
                                            max_pushes, workers, progress, exhaustive, quiet)
        spaces.update({id(s): fitted for s in extra.candidates})
        result = merge_results(result, extra)
    return merge_results(first, result), spaces
