"""The fitted pushes' tier of the skeleton search: the pushes fitted in closed form
(:mod:`robotplan.pushing.search.pose_pushes`) to a target pose as skeletons, each with a full
initial guess (the pusher backs off, circles the object to a standoff behind the contact
point, steps in and follows the arc), which the kinematic stage then only polishes: from the
circle-and-push guess, whose pushes translate without turning, SNOPT finds no plan of a turn
of 30–90° (measured: docs/experiments.md#pose-goals).

A pose goal's target is its pose. A region goal the plain tier does not plan gets one too
(:func:`region_target`): its footprint centred in the region, turned from its start by the
least angle at which it meets the program's goal row with room to spare
(measured: docs/experiments.md#fitted-region).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np
import torch

from robotplan.functionals.sticking import centroid
from robotplan.geometry.transforms import wrap_angle
from robotplan.pushing.program.rows_goal import region_goal
from robotplan.pushing.program.settings import ProgramSettings
from robotplan.pushing.program.settings import settings_for as program_settings
from robotplan.pushing.program.skeleton import Phase, Skeleton, SkeletonSpace
from robotplan.pushing.search.planner import SearchResult, merge_results, search_push
from robotplan.pushing.search.pose_pushes import (
    FIT_TOLERANCE,
    INIT_DIRECTIONS_DEG,
    STANDOFF,
    PosePushes,
    TurningBody,
    centroid_room,
    fit_pose_pushes,
    push_arc,
    rotation,
    sticking_share,
)
from robotplan.pushing.search.request import SearchRequest
from robotplan.scene import Scene
from robotplan.scene.task import PushTask

__all__ = ["pose_candidates", "pose_guess", "region_target", "search_pose", "search_pose_budgets",
           "search_region_fits", "search_region_fits_budgets"]

MAX_STEPS_PER_PHASE = 30
YAW_STEP_DEG = 5.0  # the turns tried for a region goal's target
REGION_SLACK = 0.5  # share of goal.tol that H_g may reach at a region goal's target


def region_target(task: PushTask, settings: ProgramSettings
                  ) -> tuple[float, float, float] | None:
    """A target pose ``(x, y, yaw)`` of the task's object for the region goal's fitted pushes: its
    footprint's centroid or bounding box's centre on the region's centroid (moved so that
    its centroid stays in the room the fits keep it in: :func:`centroid_room`), turned from
    its start yaw by the least multiple
    of YAW_STEP_DEG at which the program's goal row (H_g over the area, eq. 8) is at most
    REGION_SLACK of ``goal.tol`` (else within 10 % of its least); None when at every turn
    half the footprint or more lies outside."""
    region, body = task.region, task.scene.bodies[task.obj]
    c_B, c_R = centroid(body.shape.outline()), centroid(region.outline_world())
    yaw0 = float(body.pose[2])
    yaws = yaw0 + np.array(sorted(np.radians(np.arange(-180.0, 180.0, YAW_STEP_DEG)), key=abs))
    cos, sin = np.cos(yaws), np.sin(yaws)
    R = np.stack((np.stack((cos, -sin), -1), np.stack((sin, cos), -1)), -2)  # (Y, 2, 2)
    turned = np.einsum("yij,nj->yni", R, body.shape.outline())
    # per turn, the footprint's centroid or its bounding box's centre on the region's
    # centroid, whichever leaves less outside (an L's centroid is off its box's centre)
    # (Y, 2), moved where the centroid would leave the room the fits keep it in
    centroids = R @ c_B  # (Y, 2), from the origin
    middles = np.stack((centroids, 0.5 * (turned.min(axis=1) + turned.max(axis=1))))
    lo, hi = centroid_room(task)
    candidates = c_R - middles  # (2, Y, 2) origins
    candidates += np.clip(candidates + centroids, lo, hi) - (candidates + centroids)
    H = region_goal(body, region, settings)
    shares = [H(torch.from_numpy(np.column_stack((origins, yaws))))[:, 0].numpy()
              for origins in candidates]
    best = np.argmin(shares, axis=0)
    origins = candidates[best, np.arange(len(yaws))]
    outside = np.min(shares, axis=0) / body.area
    if outside.min() >= 0.5:
        return None
    # the least turn within the slack, or within 10 % of the least outside share (a box's
    # half turn and quarter turns leave it about the same)
    fits = outside <= max(REGION_SLACK * settings.row("goal").tol, 1.1 * float(outside.min()))
    i = int(np.argmax(fits))
    return float(origins[i, 0]), float(origins[i, 1]), float(wrap_angle(float(yaws[i])))


def _steps_for(body: TurningBody, fit: PosePushes, speed: float, max_turn: float) -> int:
    """Steps per phase: the longest push at ``speed`` m per step (the pusher, which sweeps
    faster than the centroid while the object turns) and ``max_turn`` rad per step, plus one
    step into contact and one spare."""
    need = 0
    for face, share, length in zip(fit.faces, fit.shares, fit.lengths, strict=True):
        r_B = face.point(share) - body.c_B
        kappa = abs(r_B[0] * face.n[1] - r_B[1] * face.n[0]) / body.radius**2
        sweep = 1.0 + kappa * float(np.linalg.norm(r_B))
        need = max(need, math.ceil(length * sweep / speed), math.ceil(kappa * length / max_turn))
    return min(MAX_STEPS_PER_PHASE, need + 2)


def pose_guess(scene: Scene, obj: str, actor: str, fit: PosePushes, T: int,
               turn_gain: float = 1.0) -> dict[str, np.ndarray]:
    """The push program's initial guess for ``fit`` at ``T`` steps per phase: per push a
    reach (the pusher circles the object clear of it to STANDOFF behind the contact point),
    then a step into contact and the arc of the quasi-static push over the other T − 1."""
    body = TurningBody(scene, obj, turn_gain)
    shape = scene.bodies[obj].shape
    rho = scene.bodies[actor].shape.radius
    pose = np.asarray(scene.bodies[obj].pose, dtype=float)
    c, yaw = pose[:2] + rotation(pose[2]) @ body.c_B, float(pose[2])
    q_obj, q_pusher, contacts = [pose.copy()], [np.asarray(scene.bodies[actor].pose[:2])], []
    circle = shape.bound_radius + float(np.linalg.norm(body.c_B)) + rho + STANDOFF
    last_n = None  # the inward normal of the face pushed last (table frame)
    for face, share, length in zip(fit.faces, fit.shares, fit.lengths, strict=True):
        stick = sticking_share(body, face, share, length / (T - 1))
        R = rotation(yaw)
        p_W = c + R @ (face.point(stick) - body.c_B)
        n_W = R @ face.n
        touching = p_W - rho * n_W
        standoff = touching - STANDOFF * n_W
        here = np.append(body.origin(c[None], np.array([yaw]))[0], yaw)
        # reach: back off the face just pushed (or out from the centroid), round the
        # centroid on a circle clear of the object, then in to the standoff
        start = q_pusher[-1]
        away = -last_n if last_n is not None else start - c
        away = away / max(float(np.linalg.norm(away)), 1e-9)
        out = start + circle * away
        a0 = math.atan2(*(out - c)[::-1])
        a1 = math.atan2(*(standoff - c)[::-1])
        da = wrap_angle(a1 - a0)
        ring = max(circle, float(np.linalg.norm(out - c)))
        entry = c + ring * np.array([math.cos(a1), math.sin(a1)])
        for s in range(1, T + 1):
            if s == 1:
                q_pusher.append(out)
            elif s <= T - 2:
                u = (s - 1) / (T - 3)
                a = a0 + u * da
                rad = float(np.linalg.norm(out - c)) * (1 - u) + ring * u
                q_pusher.append(c + rad * np.array([math.cos(a), math.sin(a)]))
            else:
                q_pusher.append(entry + (s - (T - 2)) / 2 * (standoff - entry))
            q_obj.append(here)
        # push: one step into contact, then the arc
        q_pusher.append(touching)
        q_obj.append(here)
        contacts.append(p_W)
        s_grid = length * np.arange(1, T) / (T - 1)
        cs, ys = push_arc(c, yaw, face.point(share) - body.c_B, face.n, body.radius, s_grid)
        origins = body.origin(cs, ys)
        for cj, yj, oj in zip(cs, ys, origins, strict=True):
            Rj = rotation(float(yj))
            pj = cj + Rj @ (face.point(stick) - body.c_B)
            q_obj.append(np.append(oj, yj))
            q_pusher.append(pj - rho * (Rj @ face.n))
            contacts.append(pj)
        c, yaw, last_n = cs[-1], float(ys[-1]), rotation(float(ys[-1])) @ face.n
    # on the table: a back-off or a circle round an object near its edge would leave it
    x0, x1, y0, y1 = scene.workspace.bounds
    q_pusher = np.clip(np.array(q_pusher), [x0, y0], [x1, y1])
    return {"q_obj": np.array(q_obj), "q_pusher": q_pusher,
            "p": np.array(contacts)}


def pose_candidates(task: PushTask, space: SkeletonSpace,
                    settings: ProgramSettings, max_pushes: int = 2,
                    given: Skeleton | None = None,
                    target: tuple[float, float, float] | None = None
                    ) -> tuple[SkeletonSpace, list[Skeleton], dict[Skeleton, dict]]:
    """Skeletons of the fitted pushes (:func:`fit_pose_pushes`) to ``target`` (default:
    the task's pose goal; those that count as reaching it, else those within
    FIT_TOLERANCE), their initial guesses, and the space they need (init points at
    the object frame's face normals, enough steps per phase for the longest push at the
    guess's speed and the kinematic stage's turn per step); the turning law of
    ``settings``. A ``given`` skeleton fixes the faces' classes (its pushes' init points,
    object frame) and is fitted as well as it can be."""
    gain, scene, actor = settings.row("quasi_static").turn_gain, task.scene, task.actors[0]
    obj = task.obj
    target = tuple(scene.goal.pose) if target is None else target
    fits: list[PosePushes] = []
    if given is not None:
        classes = tuple(p.init for p in given.phases if p.mode == "push")
        fits = fit_pose_pushes(task, target, len(classes), turn_gain=gain, classes=classes)
    loose: list[PosePushes] = []
    for pushes in () if given is not None else (max_pushes, max_pushes + 1):
        found = fit_pose_pushes(task, target, pushes, turn_gain=gain)
        fits = [f for f in found if f.within]
        if fits:  # one push more only when none fits
            break
        loose = loose or [f for f in found if f.error <= FIT_TOLERANCE]
    # near the target no close fit may exist: then those within FIT_TOLERANCE
    fits = fits or loose
    if not fits:
        return space, [], {}
    body = TurningBody(scene, obj, gain)
    T = max(space.steps_per_phase, max(_steps_for(body, f, settings.guess_speed,
                                                  settings.row("turn_limits").turn) for f in fits))
    posed = replace(space, steps_per_phase=T, init_frame="object",
                    init_directions_deg=INIT_DIRECTIONS_DEG)
    skeletons, guesses = [], {}
    for fit in fits:
        phases: list[Phase] = []
        for face in fit.faces:
            phases += [Phase("reach", actor, obj, face.init), Phase("push", actor, obj, face.init)]
        sk = Skeleton(tuple(phases))
        skeletons.append(sk)
        guesses[sk] = pose_guess(scene, obj, actor, fit, T, gain)
    return posed, skeletons, guesses


def search_pose(request: SearchRequest, settings: ProgramSettings, space: SkeletonSpace,
                given: Skeleton | None = None,
                target: tuple[float, float, float] | None = None, made: dict | None = None
                ) -> tuple[SkeletonSpace, SearchResult]:
    """Solve the skeletons fitted to ``target`` (default: the pose goal's pose;
    :func:`pose_candidates`; ``given``: that skeleton's faces only), each from its own
    guess; the space they were solved in and the result. ``made``: the candidates a tier
    already fitted, by what they depend on (filled here): the budgets a tier tries in turn
    change how its programs are solved, not its fits."""
    made = {} if made is None else made
    key = (settings.row("quasi_static").turn_gain, settings.guess_speed,
           settings.row("turn_limits").turn, target)
    if key not in made:
        made[key] = pose_candidates(request.task, space, settings, request.max_pushes, given,
                                    target)
    posed, skeletons, guesses = made[key]
    where = "pose goal" if target is None else (
        f"pushes fitted to ({target[0]:.3f}, {target[1]:.3f}, "
        f"{math.degrees(target[2]):.0f}°) in the goal region")
    request.say(f"{where}: {len(skeletons)} fitted push sequences "
                f"({posed.steps_per_phase} steps per phase)")
    if not skeletons:
        return posed, SearchResult(None)
    # the fits' own order: the least pushing first
    return posed, search_push(request.but(guesses=guesses), skeletons, settings, posed,
                              ordered=True)


def _in_turn(search: Callable[[ProgramSettings, float], tuple[SkeletonSpace, SearchResult]],
             budgets: tuple[ProgramSettings, ...], last_resort: float | None = None
             ) -> tuple[SearchResult, dict[int, SkeletonSpace]]:
    """``search(settings, seconds spent so far)`` with each of ``budgets`` (program settings)
    in turn until the merged result is settled (:meth:`SearchResult.settled`); that result
    and each candidate's space (by ``id`` of its solution)."""
    result, spaces = SearchResult(None), {}
    for budget in budgets:
        searched, more = search(budget, result.seconds)
        spaces.update({id(s): searched for s in more.candidates})
        result = merge_results(result, more)
        if result.settled(last_resort):
            break
    return result, spaces


def search_pose_budgets(request: SearchRequest, budgets: tuple[ProgramSettings, ...],
                        space: SkeletonSpace, given: Skeleton | None = None
                        ) -> tuple[SearchResult, dict[int, SkeletonSpace]]:
    """:func:`search_pose` with each of ``budgets`` (program settings) in turn until one
    solves, within ``request.time_budget`` s in all; the merged result and each
    candidate's space (by ``id`` of its solution)."""
    made: dict = {}
    return _in_turn(lambda budget, spent: search_pose(
        request.but(time_budget=request.left(spent)), budget, space, given, made=made),
        budgets)


def search_region_fits(request: SearchRequest, settings: ProgramSettings,
                       space: SkeletonSpace, made: dict | None = None
                       ) -> tuple[SkeletonSpace, SearchResult]:
    """A free pusher's region goal the plain tier did not plan: pushes fitted in closed form
    to a pose inside the region (:func:`region_target`), planned with the turning gain the
    pose goals measured in pybullet (the `pose` overlay's ``turn_gain``). No time budget:
    the tier has at most four programs, and without it nothing plans. ``made``: as
    :func:`search_pose`'s."""
    gain = program_settings("pose").row("quasi_static").turn_gain
    fitted = settings.with_values({"quasi_static.turn_gain": gain})
    target = region_target(request.task, fitted)
    if target is None:
        return space, SearchResult(None)
    return search_pose(request.but(time_budget=None), fitted, space, target=target, made=made)


def search_region_fits_budgets(request: SearchRequest, budgets: tuple[ProgramSettings, ...],
                               space: SkeletonSpace
                               ) -> tuple[SearchResult, dict[int, SkeletonSpace]]:
    """:func:`search_region_fits` with each of ``budgets`` (program settings) in turn until
    one solves or, given ``request.last_resort``, gives a plan that meets the constraints
    within that violation; the merged result and each candidate's space (by ``id`` of its
    solution)."""
    made: dict = {}
    return _in_turn(lambda budget, _spent: search_region_fits(request, budget, space, made),
                    budgets, request.last_resort)
