"""The push family's planner: :class:`PushPlanner` searches a :class:`PushTask`'s skeletons
and solves their programs (``plan``), runs the best plan in pybullet (``execute``), writes
its MeshCat page (``playback``) and composes the three into ``result.json`` (``solve``).

``plan`` takes the task in a scene read from a file, or in one whose bodies sit at observed
poses (``task.at(scene.with_state(...))``), and optionally the plan made before
(``warm_start``): its skeleton is tried first, its learned program started from the earlier
trajectories where they fit the skeleton's steps.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path

from robotplan.base.resources import DYNAMICS_FOLDERS, learned_dir
from robotplan.execution.physics import PHYSICS
from robotplan.execution.scene_world import actuation
from robotplan.pushing.api.playback import playback_layers
from robotplan.pushing.api.results import (
    candidate_summary,
    execution_summary,
    outcome_status,
    thresholds,
    write_json,
)
from robotplan.pushing.execution.closed_loop import (
    LoopSettings,
    execute_closed_loop,
    loop_settings_for,
)
from robotplan.pushing.execution.execute import Execution, plan_substeps, run_open_loop
from robotplan.pushing.execution.perturb import Perturbation
from robotplan.pushing.execution.rehearsal import Rehearsal, rehearsable, rehearsal_world, rehearse
from robotplan.pushing.models.loading import dynamics_kind, load_dynamics
from robotplan.pushing.program.skeleton import SkeletonSpace
from robotplan.pushing.program.solution import Solution
from robotplan.pushing.program.solve import warm_guess
from robotplan.pushing.search.default_dynamics import default_dynamics
from robotplan.pushing.search.fallback import side_by_side, tail_and_fresh
from robotplan.pushing.search.planner import merge_results
from robotplan.pushing.search.request import SearchRequest
from robotplan.pushing.search.scene_search import candidate_table, metres, search_scene
from robotplan.scene import Scene
from robotplan.scene.task import PushTask, TaskPlan
from robotplan.viz.viewer import write_playback as write_playback_html

__all__ = ["MODES", "REPLAN_BUDGET", "PushPlan", "PushPlanner"]

MODES = ("closed_loop", "open_loop")
# s of search per re-plan before it settles for the plans in hand (a fresh search goes on
# until it has one)
REPLAN_BUDGET = 20.0


@dataclass
class PushPlan(TaskPlan):
    """The outcome of :meth:`PushPlanner.plan`: the best solution (None: nothing planned),
    whether it meets every constraint, every candidate solved, and the best one's skeleton
    space."""

    task: PushTask
    best: Solution | None
    solved: bool
    candidates: list[Solution] = field(default_factory=list)
    seconds: float = 0.0
    space: SkeletonSpace | None = None
    # how it was planned (model folder, solver, workers, max_pushes): re-plans plan alike
    options: dict = field(default_factory=dict)
    # the best plan rehearsed in F_q (:mod:`robotplan.pushing.execution.rehearsal`): what the open
    # loop runs; None when not rehearsed
    rehearsal: Rehearsal | None = None

    @property
    def obj(self) -> str:
        """The object the actors touch."""
        return self.task.obj

    def summary(self) -> dict:
        """The plan's entries of ``result.json``."""
        best = self.best
        return {"plan_status": "solved" if self.solved else "no_solution",
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


class PushPlanner:
    """Plans, executes and plays back push tasks (free pushers, arms, chains)."""

    family = "push"

    def plan(self, task: PushTask, model: str | Path | None = None, *,
             warm_start: PushPlan | None = None, fallback: bool = True,
             rehearse_plan: bool = False, rehearsal_model: str | Path | None = None,
             **search: object) -> PushPlan:
        """Search the task's skeletons and solve their programs; no simulator runs.

        ``model``: the learned dynamics' folder (default: the shipped model of the task's
        class, :func:`~robotplan.pushing.search.default_dynamics.default_dynamics`). ``search``: the
        fields of :class:`~robotplan.pushing.search.request.SearchRequest` (``solver``, ``workers``,
        ``skeleton``, ``max_pushes``, ``time_budget``, ``program``, ``replan``,
        ``last_resort``, ``exhaustive``, ``progress``, ``quiet``, ``candidate_kinds``; the
        re-plans of its execution search with the same). ``warm_start``: an
        earlier plan of this task (at other poses): its skeleton is tried first, from its
        trajectories; a fresh search follows when that does not solve (unless ``fallback``
        is False; for a free pusher's pose goal the two run side by side,
        :mod:`robotplan.pushing.search.fallback`). ``rehearse_plan``: with F_q (and its learned
        stage), one free pusher, one object, no obstacles and a region goal, rehearse the best
        plan in F_q for the open loop (:mod:`robotplan.pushing.execution.rehearsal`; never in a
        re-plan); its seconds count as planning. ``rehearsal_model``: the F_q folder the
        rehearsal's object moves by (default: ``REHEARSAL_FOLDERS`` by the object's footprint type,
        else the plan's own F_q; the re-plans plan with ``model``)."""
        model_dir = (Path(model) if model is not None
                     else learned_dir(DYNAMICS_FOLDERS[default_dynamics(task)]))
        if (rehearse_plan and rehearsal_model is not None
                and dynamics_kind(rehearsal_model) != "rigid"):
            raise ValueError(f"rehearsal_model {rehearsal_model}: not an F_q (spec kind "
                             "'rigid')")
        request = SearchRequest(task, model_dir, **search)
        if warm_start is not None and warm_start.best is not None and request.skeleton is None:
            sk = warm_start.best.skeleton
            request = request.but(skeleton=sk, guesses={sk: warm_guess(task, warm_start.best)})
        if fallback and side_by_side(request):  # the tail and a fresh search
            result, spaces = tail_and_fresh(request)
        else:
            result, spaces = search_scene(request)
            if not result.solved and request.guesses is not None and fallback:
                # the old skeleton is lost: a fresh search
                again, more = search_scene(request.but(skeleton=None, guesses=None,
                                                       replan=True))
                result, spaces = merge_results(result, again), {**spaces, **more}
        if not request.quiet:
            kind = dynamics_kind(model_dir)
            named = ", the default for this task's class" if model is None else ""
            print(f"learned dynamics: {kind} from {model_dir}{named}")
            print(candidate_table(result, kind))
        best = result.best
        planned = PushPlan(task, best, result.solved, result.candidates, result.seconds,
                           spaces.get(id(best)) if best is not None else None,
                           {"model": model_dir, "solver": request.solver,
                            "workers": request.workers, "max_pushes": request.max_pushes,
                            "program": dict(request.program or {}),
                            "candidate_kinds": request.candidate_kinds})
        learned = (request.program or {}).get("learned_stage", True)  # F_q behind the plan
        if (rehearse_plan and learned and not request.replan and best is not None
                and dynamics_kind(model_dir) == "rigid" and rehearsable(task)):
            world = rehearsal_world(task, model_dir, rehearsal_model)
            planned.rehearsal = rehearse(task, best, self.replanner(planned),
                                         load_dynamics(world), folder=str(world))
            planned.seconds += planned.rehearsal.seconds
            if not request.quiet:
                r = planned.rehearsal
                print(f"rehearsed in F_q: coverage {r.coverage:.3f} after {len(r.replans)} "
                      f"re-plans ({r.seconds:.1f} s)")
        return planned

    def execute(self, planned: PushPlan, scene: Scene | None = None, *,
                mode: str = "closed_loop", perturb: Perturbation | None = None,
                loop: LoopSettings | None = None, quiet: bool = True,
                sim: str = "pybullet") -> Execution:
        """Run the best plan in the simulator ``sim`` (a key of
        :data:`~robotplan.execution.physics.SIMULATORS`) in ``scene`` (default: the
        plan's): closed loop
        (re-planning from the observed state, :mod:`robotplan.pushing.execution.closed_loop`) or
        open loop, the paper's protocol: a rehearsed plan's pusher states, else the best
        plan's. ``perturb``: friction, mass
        and observation noise of a perturbed world; ``loop``: the closed loop's settings
        (default: the task class's, ``skeletons/loop.yaml``); ``quiet=False`` prints a line
        per re-plan."""
        if planned.best is None:
            raise ValueError("nothing to execute: the plan has no solution")
        if mode not in MODES:
            raise ValueError(f"mode {mode!r}: expected one of {', '.join(MODES)}")
        task = planned.task if scene is None else planned.task.at(scene)
        best = planned.best
        physics = replace(perturb.physics() if perturb is not None else PHYSICS, simulator=sim)
        if mode == "open_loop" and planned.rehearsal is not None:
            r = planned.rehearsal
            return run_open_loop(task, {task.actors[0]: r.pusher}, r.substeps, physics)
        if mode == "open_loop":
            return run_open_loop(task, actuation(task, best.q_pusher, best.q_joints),
                                 plan_substeps(task, best, physics), physics)
        return execute_closed_loop(task, best, self.replanner(planned), loop, physics,
                                   perturb.observer() if perturb is not None else None,
                                   None if quiet else print)

    def replanner(self, planned: PushPlan):
        """:meth:`plan` of the task in an observed scene, as ``planned`` was made, warm
        started from the current plan's ``tail`` (None: a fresh search), a fresh search
        following when the tail does not solve only if ``fresh``; ``last_resort``: the
        violation within which the loop adopts an unsolved plan; ``deadline``: the
        ``time.monotonic()`` instant after which it starts nothing more."""
        options = dict(planned.options)
        model = options.pop("model", None)

        def replan(observed: PushTask, tail: Solution | None, fresh: bool,
                   last_resort: float | None = None, deadline: float | None = None
                   ) -> PushPlan:
            warm = PushPlan(observed, tail, True) if tail is not None else None
            return self.plan(observed, model, **options, progress=False, quiet=True,
                             time_budget=REPLAN_BUDGET, warm_start=warm, fallback=fresh,
                             replan=True, last_resort=last_resort, deadline=deadline)

        return replan

    def playback(self, planned: PushPlan, executed: Execution, path: Path) -> None:
        """The self-contained MeshCat page replaying the execution with its plans ghosted."""
        write_playback_html(planned.scene, Path(path), playback_layers(planned, executed))

    def solve(self, task: PushTask, out: Path, model: str | Path | None = None, *,
              quiet: bool = False, mode: str = "closed_loop",
              perturb: Perturbation | None = None, compare_open_loop: bool = False,
              loop: Mapping[str, object] | None = None, rehearse_plan: bool = True,
              sim: str = "pybullet", **options: object) -> dict:
        """Plan, execute the best plan (``mode``, in a world perturbed by ``perturb``),
        write ``out/playback.html`` and ``out/result.json`` (whole or not at all); the
        result document. ``compare_open_loop`` also runs the same plan open loop and records
        its outcome under ``open_loop``. ``loop``: closed-loop settings that replace those
        of the task's class (:class:`~robotplan.pushing.execution.closed_loop.LoopSettings` fields,
        recorded in the result). ``rehearse_plan``: rehearse the plan in F_q (:meth:`plan`)
        when an open loop runs. ``sim``: the simulator that executes it. ``options``: those
        of :meth:`plan`."""
        rehearse_plan = rehearse_plan and (mode == "open_loop" or compare_open_loop)
        planned = self.plan(task, model, quiet=quiet, rehearse_plan=rehearse_plan, **options)
        return self.report(planned, Path(out), quiet=quiet, mode=mode, perturb=perturb,
                           compare_open_loop=compare_open_loop, loop=loop, sim=sim)

    def report(self, planned: PushPlan, out: Path, *, quiet: bool = False,
               mode: str = "closed_loop", perturb: Perturbation | None = None,
               compare_open_loop: bool = False, loop: Mapping[str, object] | None = None,
               sim: str = "pybullet") -> dict:
        """Execute a plan made by :meth:`plan` and write ``out/playback.html`` and
        ``out/result.json`` (whole or not at all): the second half of :meth:`solve`, which
        a benchmark runs once per simulator on the same plan."""
        task = planned.task
        doc: dict = {"scene": task.scene.name, **planned.summary()}
        best = planned.best
        if best is not None:
            if not quiet and best.q_others:
                print(f"plan: {' and '.join([planned.obj, *best.q_others])} pushed by "
                      f"{best.skeleton.phases[0].actor}; executing in {sim}")
            t0 = time.perf_counter()
            settings = loop_settings_for(task, overrides=loop)
            executed = self.execute(planned, mode=mode, perturb=perturb, loop=settings,
                                    quiet=quiet, sim=sim)
            doc.update(execution_summary(planned, executed, perturb))
            doc["execution"]["goal_reached"] = settings.goal_met(
                task, executed.coverage, executed.touch_distance)
            if loop:
                doc["execution"]["loop_settings"] = dict(loop)
            doc["execution"]["seconds"] = round(time.perf_counter() - t0, 2)
            if compare_open_loop:
                t0 = time.perf_counter()
                baseline = self.execute(planned, mode="open_loop", perturb=perturb, sim=sim)
                doc["open_loop"] = {"coverage": baseline.coverage,
                                    "touch_distance": baseline.touch_distance,
                                    "seconds": round(time.perf_counter() - t0, 2)}
            self.playback(planned, executed, out / "playback.html")
            doc["playback"] = "playback.html"
            doc["candidates"] = [candidate_summary(s) for s in planned.candidates]
        status = outcome_status(doc)
        doc = {"scene": task.scene.name, "status": status, **doc, **thresholds()}
        write_json(out / "result.json", doc)
        return doc
