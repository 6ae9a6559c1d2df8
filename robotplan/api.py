"""``robotplan solve``: plan, execute in pybullet, write result.json and the playback."""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import numpy as np

from robotplan.base.files import write_atomically
from robotplan.execution.execute import execute_arms, execute_push, reach_substeps
from robotplan.execution.sim import PHYSICS
from robotplan.functionals.clearance import OBSTACLE_MARGIN
from robotplan.program.chain_program import objects_touch
from robotplan.program.settings import ProgramSettings
from robotplan.program.skeleton import (
    SkeletonSpace,
    actor_candidates,
    chain_candidates,
    parse_skeleton,
    space_for,
)
from robotplan.program.solution import Solution
from robotplan.scene import Scene
from robotplan.search.planner import (
    FEASIBLE,
    PLAUSIBLE_RMS_MM,
    SearchResult,
    merge_results,
    search_push,
)
from robotplan.search.route import route_settings, routed_candidates

__all__ = ["UnsupportedScene", "budget_spent", "candidate_table", "solve_scene"]


class UnsupportedScene(ValueError):
    """The scene is valid but needs a planner feature that is not built yet."""


def _chain_target(scene: Scene) -> tuple[str, str] | None:
    """``(obj, target)`` when the only free pusher may not touch the goal's object but may
    touch the one other object: it pushes ``obj``, which pushes ``target`` (paper Fig. 9)."""
    if scene.robots or len(scene.pushers) != 1 or len(scene.objects) != 2:
        return None
    goal_obj = getattr(scene.goal, "object", None)
    allowed = scene.pushers[0].touches
    others = [o.name for o in scene.objects if o.name != goal_obj]
    if allowed is None or goal_obj in allowed or others[0] not in allowed:
        return None
    return others[0], goal_obj


def _check_supported(scene: Scene) -> tuple[str, list[str]]:
    """The object the actors touch and the actors (pushers or arms) of a scene the
    planner handles."""
    chain = _chain_target(scene)
    if chain is not None and scene.goal.type == "region":
        return chain[0], [scene.pushers[0].name]
    if len(scene.objects) != 1:
        raise UnsupportedScene("objects: more than one movable object is planned only when "
                               "the pusher touches one of two and it pushes the goal's object "
                               "(pushers[0].touches)")
    if scene.robots and scene.pushers:
        raise UnsupportedScene("pushers: free pushers beside robot arms are not planned yet")
    if not scene.robots and len(scene.pushers) != 1:
        raise UnsupportedScene("pushers: only one free pusher is planned yet")
    if scene.goal.type != "region" and not scene.robots:
        raise UnsupportedScene("goal: touch goals are planned for robot arms only")
    actors = [r.name for r in scene.robots] or [scene.pushers[0].name]
    return scene.objects[0].name, actors


def budget_spent(result: SearchResult, time_budget: float | None) -> bool:
    """Whether the search is past ``time_budget`` seconds with some plan in hand: then it
    starts no further tier or route search (each would solve at least one program per
    worker before looking at the clock). Without any plan it goes on."""
    return (time_budget is not None and result.best is not None
            and result.seconds >= time_budget)


def _candidate_tiers(scene: Scene, obj: str, actors: list[str], skeleton: str | None,
                     max_pushes: int, quiet: bool) -> Iterator[tuple[list, SkeletonSpace]]:
    """The candidates tier by tier, each with its space; the search moves on to the next tier
    only when no candidate of a tier plans. One tier for a given skeleton, a chain or the
    free pusher; for arms one per init frame (the object's faces, then around the object as
    seen from the goal), every choice of arm pruned by reach before any program is solved,
    and a frame with nothing in reach skipped. Lazy: a frame is pruned when it is reached."""
    space = space_for(scene)
    chain = _chain_target(scene)
    if skeleton:
        given = parse_skeleton(skeleton, actors[0], obj)
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
    from robotplan.program.arm_program import reach_check

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
        routed, skeletons = routed_candidates(scene, actor, obj, space,
                                              np.array(region.pose[:2], dtype=float),
                                              settings.guess_speed)
    if not quiet:
        print(f"no plan with up to {max_pushes} pushes; trying {len(skeletons)} routes around "
              f"the obstacles ({routed.steps_per_phase} steps per phase)")
    if not skeletons:
        return routed, SearchResult(None)
    return routed, search_push(scene, model_dir, skeletons, route_settings(settings), workers,
                               progress, exhaustive, time_budget, routed)


def _margin_note(s: Solution) -> str:
    """Why a feasible plan around obstacles was not taken, if that is the reason."""
    if s.clearance >= OBSTACLE_MARGIN or s.violation > FEASIBLE:
        return ""
    return f", {100 * s.clearance:.1f} cm from an obstacle (margin {100 * OBSTACLE_MARGIN:g})"


def _metres(value: float) -> float | None:
    return round(value, 4) if math.isfinite(value) else None


def candidate_table(result: SearchResult) -> str:
    lines = [f"{'#':>2}  {'skeleton':<40} {'violation':>10} {'cost':>9} {'H_F rms mm':>10} "
             f"{'seconds':>8}  status"]
    for i, s in enumerate(result.candidates):
        mark = " <- best" if s is result.best else ""
        lines.append(f"{i:>2}  {s.skeleton.describe():<40} {s.violation:>10.3g} "
                     f"{s.cost:>9.3g} {s.dynamics_rms_mm:>10.2f} {s.seconds:>8.1f}  "
                     f"{s.status}{_margin_note(s)}{mark}")
    return "\n".join(lines)


def solve_scene(scene: Scene, out: Path, model_dir: Path, solver: str = "snopt",
                workers: int = 2, skeleton: str | None = None, max_pushes: int = 2,
                progress: bool = True, exhaustive: bool = False, quiet: bool = False,
                time_budget: float | None = None) -> dict:
    obj, actors = _check_supported(scene)
    settings = ProgramSettings(solver=solver)
    if scene.robots:
        from robotplan.program.arm_program import ARM_PROGRAM_SETTINGS

        settings = replace(ARM_PROGRAM_SETTINGS, solver=solver)
    result, spaces = SearchResult(None), {}  # spaces: a skeleton may recur in two tiers
    space = space_for(scene)
    for candidates, space in _candidate_tiers(scene, obj, actors, skeleton, max_pushes, quiet):
        left = None if time_budget is None else max(0.0, time_budget - result.seconds)
        more = search_push(scene, model_dir, candidates, settings, workers, progress,
                           exhaustive, left, space)
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
    if not quiet:
        print(candidate_table(result))
    best = result.best
    doc: dict = {"scene": scene.name, "status": "solved" if result.solved else "no_solution",
                 "skeleton": best.skeleton.as_rows() if best else [],
                 "skeleton_space": ({"steps_per_phase": spaces[id(best)].steps_per_phase,
                                     "init_frame": spaces[id(best)].init_frame}
                                    if best else None),
                 "plan_seconds": round(result.seconds, 2),
                 "programs_solved": len(result.candidates),
                 "violation": float(best.violation) if best else None,
                 "cost": float(best.cost) if best else None,
                 "dynamics_rms_mm": round(best.dynamics_rms_mm, 3) if best else None,
                 "obstacle_clearance": _metres(best.clearance) if best else None}
    if best is not None:
        if not quiet and best.q_others:
            print(f"plan: {' and '.join([obj, *best.q_others])} pushed by "
                  f"{actors[0]}; executing in pybullet")
        doc.update(_execute_and_show(scene, obj, best, out))
        doc["candidates"] = [{"skeleton": s.skeleton.describe(), "violation": s.violation,
                              "cost": s.cost, "seconds": round(s.seconds, 2),
                              "dynamics_rms_mm": round(s.dynamics_rms_mm, 3),
                              "obstacle_clearance": _metres(s.clearance),
                              "timings": s.timings,
                              "status": s.status} for s in result.candidates]
    doc["feasibility_threshold"] = FEASIBLE
    doc["plausible_dynamics_rms_mm"] = PLAUSIBLE_RMS_MM
    doc["obstacle_margin"] = OBSTACLE_MARGIN
    write_atomically(out / "result.json",
                     lambda tmp: tmp.write_text(json.dumps(doc, indent=1, default=_json)))
    return doc


def _execute_and_show(scene: Scene, obj: str, best, out: Path) -> dict:
    """Execute the plan in pybullet, write the playback; the result.json entries."""
    from robotplan.viz.viewer import write_playback

    dt = 1.0 / 12.0  # a kept step of the push data: 20 × 1/240 s
    steps = len(best.q_pusher) - 1
    T = steps // len(best.skeleton.phases)
    push = np.array([best.skeleton.phases[t // T].mode == "push" for t in range(steps)])
    # simulation steps per planned step: reaches run slower than the data's pushes
    if scene.robots:
        from robotplan.program.arm_program import ARM_SETTINGS

        slow = round(ARM_SETTINGS.reach_slowdown)
        substeps = [PHYSICS.keep_every * (1 if p else slow) for p in push]
        ex = execute_arms(scene, obj, best.q_joints, substeps)
    else:
        substeps = reach_substeps(best.q_pusher, push)
        ex = execute_push(scene, obj, scene.pushers[0].name, best.q_pusher, substeps=substeps)
    t = np.concatenate(([0.0], np.cumsum(substeps) / PHYSICS.keep_every * dt))
    planned = {obj: best.q_obj, **best.q_others}
    simulated = {obj: ex.object_poses, **{k: v for k, v in ex.others.items() if k in planned}}
    final = {obj: ex.final_pose, **{k: v[-1] for k, v in ex.others.items()}}
    doc = {"execution": {"simulator": "pybullet", "coverage": ex.coverage,
                         "final_poses": {k: [float(x) for x in v] for k, v in final.items()},
                         "touch_distance": ex.touch_distance,
                         "obstacle_contact": ex.obstacle_contact,
                         "forbidden_contacts": ex.forbidden_contacts},
           "trajectory": {"t": [round(float(v), 6) for v in t],
                          "pusher": best.q_pusher.tolist(),
                          "objects": {k: v.tolist() for k, v in planned.items()},
                          "contact_points": best.contact.tolist(),
                          "joints": {k: v.tolist() for k, v in best.q_joints.items()}},
           "executed": {"pusher": ex.pusher_positions.tolist(),
                        "objects": {k: v.tolist() for k, v in simulated.items()},
                        "joints": {k: v.tolist() for k, v in ex.joints.items()},
                        "tips": {k: v.tolist() for k, v in ex.tips.items()}}}
    if best.contact_others:
        doc["trajectory"]["object_contact_points"] = {
            k: v.tolist() for k, v in best.contact_others.items()}
    actor = scene.pushers[0].name if scene.pushers else None
    plan = {**planned, **({actor: best.q_pusher} if actor else {})}
    executed = {**simulated, **({actor: ex.pusher_positions} if actor else {})}
    write_playback(scene, out / "playback.html", plan, executed,
                   joints=(best.q_joints, ex.joints), times=t)
    doc["playback"] = "playback.html"
    return doc


def _json(x: object) -> object:
    if isinstance(x, np.generic):
        return x.item()
    raise TypeError(type(x))
