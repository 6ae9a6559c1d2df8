"""The public facade: :func:`plan` (skeleton search and Drake programs, no simulator),
:func:`execute` (pybullet), :func:`write_playback` (MeshCat page) and :func:`solve`, which
composes them and writes ``result.json``, as ``robotplan solve`` does.

``plan`` takes any :class:`~robotplan.scene.Scene`: one read from a file, or one whose
bodies sit at observed poses (:meth:`Scene.with_state`), and optionally the plan made
before (``warm_start``): its skeleton is tried first, its learned program started from the
earlier trajectories where they fit the skeleton's steps.
"""

from __future__ import annotations

import json
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robotplan.api.hang import (
    HangPlan,
    execute_hang,
    plan_hang,
    solve_hang,
    write_hang_playback_page,
)
from robotplan.api.playback import playback_layers
from robotplan.api.results import execution_summary
from robotplan.base.files import write_atomically
from robotplan.base.resources import DYNAMICS_FOLDERS, learned_dir
from robotplan.execution.closed_loop import LoopSettings, execute_closed_loop, loop_settings_for
from robotplan.execution.execute import Execution, plan_substeps, run_open_loop
from robotplan.execution.perturb import Perturbation
from robotplan.execution.rehearsal import Rehearsal, rehearsable, rehearsal_world, rehearse
from robotplan.execution.scene_world import actuation
from robotplan.execution.sim import PHYSICS
from robotplan.functionals.clearance import OBSTACLE_MARGIN
from robotplan.models.loading import dynamics_kind, load_dynamics
from robotplan.program.skeleton import Skeleton, SkeletonSpace
from robotplan.program.solution import Solution
from robotplan.program.solve import warm_guess
from robotplan.scene import Scene
from robotplan.scene.schema import HangGoal
from robotplan.search.fallback import side_by_side, tail_and_fresh
from robotplan.search.planner import FEASIBLE, PLAUSIBLE_RMS_MM, merge_results
from robotplan.search.scene_classes import default_dynamics
from robotplan.search.scene_search import (
    UnsupportedScene,
    candidate_table,
    check_supported,
    metres,
    search_scene,
)
from robotplan.viz.viewer import write_playback as write_playback_html

__all__ = ["Execution", "Plan", "UnsupportedScene", "execute", "plan", "solve",
           "write_playback"]

MODES = ("closed_loop", "open_loop")
# s of search per re-plan before it settles for the plans in hand (a fresh search goes on
# until it has one)
REPLAN_BUDGET = 20.0


@dataclass
class Plan:
    """The outcome of :func:`plan`: the best solution (None: nothing planned), whether it
    meets every constraint, every candidate solved, and the best one's skeleton space."""

    scene: Scene
    obj: str
    best: Solution | None
    solved: bool
    candidates: list[Solution] = field(default_factory=list)
    seconds: float = 0.0
    space: SkeletonSpace | None = None
    # how it was planned (model folder, solver, workers, max_pushes): re-plans plan alike
    options: dict = field(default_factory=dict)
    # the best plan rehearsed in F_q (:mod:`robotplan.execution.rehearsal`): what the open
    # loop runs; None when not rehearsed
    rehearsal: Rehearsal | None = None

    def summary(self) -> dict:
        """The plan's entries of ``result.json``."""
        best = self.best
        return {"status": "solved" if self.solved else "no_solution",
                "skeleton": best.skeleton.as_rows() if best else [],
                "skeleton_space": ({"steps_per_phase": self.space.steps_per_phase,
                                    "init_frame": self.space.init_frame}
                                   if best and self.space else None),
                "model": str(self.options.get("model", "")),
                "plan_seconds": round(self.seconds, 2),
                "programs_solved": len(self.candidates),
                "violation": float(best.violation) if best else None,
                "cost": float(best.cost) if best else None,
                "dynamics_rms_mm": round(best.dynamics_rms_mm, 3) if best else None,
                "obstacle_clearance": metres(best.clearance) if best else None,
                "rehearsal": self.rehearsal.summary() if self.rehearsal else None,
                **({"program_settings": dict(self.options["program"])}
                   if self.options.get("program") else {})}


def plan(scene: Scene, model: str | Path | None = None, *, solver: str = "snopt",
         workers: int = 2, skeleton: str | Skeleton | None = None, max_pushes: int = 2,
         progress: bool = True, exhaustive: bool = False, quiet: bool = False,
         time_budget: float | None = None, warm_start: Plan | None = None,
         fallback: bool = True, program: Mapping[str, object] | None = None,
         replan: bool = False, last_resort: float | None = None,
         rehearse_plan: bool = False, rehearsal_model: str | Path | None = None) -> Plan:
    """Search the scene's skeletons and solve their programs; no simulator runs.

    ``model``: the learned dynamics' folder (default: the shipped model of the scene's class,
    :func:`~robotplan.search.scene_classes.default_dynamics`). ``skeleton``: one
    skeleton (in the CLI's notation, or a ``Skeleton``) instead of the search.
    ``warm_start``: an earlier plan of this scene (at other poses): its skeleton is tried
    first, from its trajectories; a fresh search follows when that does not solve (unless
    ``fallback`` is False; for a free pusher's pose goal the two run side by side,
    :mod:`robotplan.search.fallback`). ``program``: program settings that win over those of the
    scene's class (:class:`~robotplan.program.settings.ProgramSettings` fields, e.g.
    ``{"with_contact": False}``); its re-plans keep them.
    ``replan``: a re-plan during execution (the closed loop's): a pose goal's fresh search
    runs the ``replan`` overlay's smaller budget first. ``last_resort``: the violation within
    which the caller adopts an unsolved plan that meets the constraints; a region goal's
    fresh search that finds one in its first, fitted pushes stops there.
    ``rehearse_plan``: with F_q (and its learned stage), one free pusher, one object and no
    obstacles, rehearse the best plan in F_q for the open loop
    (:mod:`robotplan.execution.rehearsal`; never in a re-plan); its seconds count as
    planning. ``rehearsal_model``: the F_q folder the rehearsal's object moves by (default:
    ``REHEARSAL_FOLDERS`` by the object's footprint type, else the plan's own F_q; the
    re-plans plan with ``model``).
    """
    if isinstance(scene.goal, HangGoal):  # kinematic: a pose of the mug, no skeleton
        return plan_hang(scene, model)
    model_dir = (Path(model) if model is not None
                 else learned_dir(DYNAMICS_FOLDERS[default_dynamics(scene)]))
    if rehearse_plan and rehearsal_model is not None and dynamics_kind(rehearsal_model) != "rigid":
        raise ValueError(f"rehearsal_model {rehearsal_model}: not an F_q (spec kind 'rigid')")
    guesses = None
    if warm_start is not None and warm_start.best is not None and skeleton is None:
        skeleton = warm_start.best.skeleton
        guesses = {warm_start.best.skeleton: warm_guess(scene, warm_start.best)}
    obj, _actors = check_supported(scene)
    if fallback and side_by_side(scene, workers, guesses):  # the tail and a fresh search
        result, spaces = tail_and_fresh(scene, model_dir, solver, skeleton, guesses, max_pushes,
                                        progress, exhaustive, quiet, time_budget, program)
    else:
        result, spaces = search_scene(scene, model_dir, solver, workers, skeleton, max_pushes,
                                      progress, exhaustive, quiet, time_budget, guesses,
                                      program, replan=replan, last_resort=last_resort)
        if not result.solved and guesses is not None and fallback:  # the old skeleton is lost
            again, more = search_scene(scene, model_dir, solver, workers, None, max_pushes,
                                       progress, exhaustive, quiet, time_budget,
                                       program=program, replan=True, last_resort=last_resort)
            result, spaces = merge_results(result, again), {**spaces, **more}
    if not quiet:
        kind = dynamics_kind(model_dir)
        named = ", the default for this scene's class" if model is None else ""
        print(f"learned dynamics: {kind} from {model_dir}{named}")
        print(candidate_table(result, kind))
    best = result.best
    planned = Plan(scene, obj, best, result.solved, result.candidates, result.seconds,
                   spaces.get(id(best)) if best is not None else None,
                   {"model": model_dir, "solver": solver, "workers": workers,
                    "max_pushes": max_pushes, "program": dict(program or {})})
    learned = (program or {}).get("learned_stage", True)  # no F_q behind an analytic plan
    if (rehearse_plan and learned and not replan and best is not None
            and dynamics_kind(model_dir) == "rigid" and rehearsable(scene)):
        world = rehearsal_world(scene, obj, model_dir, rehearsal_model)
        planned.rehearsal = rehearse(scene, obj, best, _replanner(planned),
                                     load_dynamics(world), folder=str(world))
        planned.seconds += planned.rehearsal.seconds
        if not quiet:
            r = planned.rehearsal
            print(f"rehearsed in F_q: coverage {r.coverage:.3f} after {len(r.replans)} "
                  f"re-plans ({r.seconds:.1f} s)")
    return planned


def execute(planned: Plan, scene: Scene | None = None, *, mode: str = "closed_loop",
            perturb: Perturbation | None = None, loop: LoopSettings | None = None,
            quiet: bool = True) -> Execution:
    """Run the best plan in pybullet in ``scene`` (default: the plan's).

    ``mode="closed_loop"`` observes the scene after every planned step and calls
    :func:`plan` again from the observed state when it departs from the plan
    (:mod:`robotplan.execution.closed_loop`); ``"open_loop"`` runs the plan as it is, the
    paper's protocol (§7.2.3): a rehearsed plan's pusher states (``planned.rehearsal``),
    else the best plan's. Reaches run slower than the data's pushes (see
    ``plan_substeps``). ``perturb``: friction, mass and observation noise of a perturbed
    world. ``loop``: the closed loop's settings (default: those of the plan's scene class,
    ``skeletons/loop.yaml``). ``quiet=False`` prints a line per re-plan. A hang plan is
    dropped from its pose; in closed loop, while the mug falls, its search goes on and drops
    the next pose it finds (:func:`robotplan.api.hang.execute_hang`)."""
    if isinstance(planned, HangPlan):
        return execute_hang(planned, mode)
    if planned.best is None:
        raise ValueError("nothing to execute: the plan has no solution")
    if mode not in MODES:
        raise ValueError(f"mode {mode!r}: expected one of {', '.join(MODES)}")
    scene = scene or planned.scene
    best, obj = planned.best, planned.obj
    physics = perturb.physics() if perturb is not None else PHYSICS
    if mode == "open_loop" and planned.rehearsal is not None:
        r = planned.rehearsal
        return run_open_loop(scene, obj, {scene.pushers[0].name: r.pusher}, r.substeps,
                             physics)
    if mode == "open_loop":
        return run_open_loop(scene, obj, actuation(scene, best.q_pusher, best.q_joints),
                             plan_substeps(scene, best, physics), physics)
    return execute_closed_loop(scene, obj, best, _replanner(planned), loop, physics,
                               perturb.observer() if perturb is not None else None,
                               None if quiet else print)


def _replanner(planned: Plan):
    """:func:`plan` from an observed scene, as ``planned`` was made, warm started from the
    current plan's ``tail`` (None: a fresh search), a fresh search following when the tail
    does not solve only if ``fresh``; ``last_resort``: the violation within which the loop
    adopts an unsolved plan."""
    options = dict(planned.options)
    model = options.pop("model", None)

    def replan(observed: Scene, tail: Solution | None, fresh: bool,
               last_resort: float | None = None) -> Plan:
        warm = Plan(observed, planned.obj, tail, True) if tail is not None else None
        return plan(observed, model, **options, progress=False, quiet=True,
                    time_budget=REPLAN_BUDGET, warm_start=warm, fallback=fresh, replan=True,
                    last_resort=last_resort)

    return replan


def write_playback(planned: Plan, executed: Execution, path: Path) -> None:
    """The self-contained MeshCat page replaying the execution with its plans ghosted."""
    if isinstance(planned, HangPlan):
        return write_hang_playback_page(planned, executed, Path(path))
    write_playback_html(planned.scene, Path(path), playback_layers(planned, executed))


def solve(scene: Scene, out: Path, model: str | Path | None = None, *, quiet: bool = False,
          mode: str = "closed_loop", perturb: Perturbation | None = None,
          compare_open_loop: bool = False, loop: Mapping[str, object] | None = None,
          rehearse_plan: bool = True, **options: object) -> dict:
    """Plan, execute the best plan (``mode``, in a world perturbed by ``perturb``), write
    ``out/playback.html`` and ``out/result.json`` (whole or not at all); the result
    document. ``compare_open_loop`` also runs the same plan open loop and records its
    outcome under ``open_loop``. ``loop``: closed-loop settings that replace those of the
    scene's class (:class:`~robotplan.execution.closed_loop.LoopSettings` fields, recorded
    in the result). ``rehearse_plan``: rehearse the plan in F_q (:func:`plan`) when an
    open loop runs. ``options``: those of :func:`plan`."""
    out = Path(out)
    if isinstance(scene.goal, HangGoal):
        return solve_hang(scene, out, model, mode=mode)
    rehearse_plan = rehearse_plan and (mode == "open_loop" or compare_open_loop)
    planned = plan(scene, model, quiet=quiet, rehearse_plan=rehearse_plan, **options)
    doc: dict = {"scene": scene.name, **planned.summary()}
    if planned.best is not None:
        best = planned.best
        if not quiet and best.q_others:
            print(f"plan: {' and '.join([planned.obj, *best.q_others])} pushed by "
                  f"{best.skeleton.phases[0].actor}; executing in pybullet")
        t0 = time.perf_counter()
        settings = loop_settings_for(scene, overrides=loop) if loop else None
        executed = execute(planned, mode=mode, perturb=perturb, loop=settings, quiet=quiet)
        doc.update(execution_summary(planned, executed, perturb))
        if loop:
            doc["execution"]["loop_settings"] = dict(loop)
        doc["execution"]["seconds"] = round(time.perf_counter() - t0, 2)
        if compare_open_loop:
            t0 = time.perf_counter()
            baseline = execute(planned, mode="open_loop", perturb=perturb)
            doc["open_loop"] = {"coverage": baseline.coverage,
                                "touch_distance": baseline.touch_distance,
                                "seconds": round(time.perf_counter() - t0, 2)}
        write_playback(planned, executed, out / "playback.html")
        doc["playback"] = "playback.html"
        doc["candidates"] = [{"skeleton": s.skeleton.describe(), "violation": s.violation,
                              "cost": s.cost, "seconds": round(s.seconds, 2),
                              "dynamics_rms_mm": round(s.dynamics_rms_mm, 3),
                              "obstacle_clearance": metres(s.clearance),
                              "timings": s.timings,
                              "status": s.status} for s in planned.candidates]
    doc["feasibility_threshold"] = FEASIBLE
    doc["plausible_dynamics_rms_mm"] = PLAUSIBLE_RMS_MM
    doc["obstacle_margin"] = OBSTACLE_MARGIN
    write_atomically(out / "result.json",
                     lambda tmp: tmp.write_text(json.dumps(doc, indent=1, default=_json)))
    return doc


def _json(x: object) -> object:
    if isinstance(x, np.generic):
        return x.item()
    raise TypeError(type(x))
