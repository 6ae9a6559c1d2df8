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
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robotplan.base.files import write_atomically
from robotplan.base.resources import learned_dir
from robotplan.execution.execute import Execution, execute_arms, execute_push, reach_substeps
from robotplan.execution.sim import PHYSICS
from robotplan.functionals.clearance import OBSTACLE_MARGIN
from robotplan.program.settings import ARM_PROGRAM_SETTINGS
from robotplan.program.skeleton import Skeleton, SkeletonSpace
from robotplan.program.solution import Solution
from robotplan.program.solve import warm_guess
from robotplan.scene import Scene
from robotplan.search.planner import FEASIBLE, PLAUSIBLE_RMS_MM, merge_results
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

STEP_SECONDS = 1.0 / 12.0  # a kept step of the push data: 20 × 1/240 s


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

    def summary(self) -> dict:
        """The plan's entries of ``result.json``."""
        best = self.best
        return {"status": "solved" if self.solved else "no_solution",
                "skeleton": best.skeleton.as_rows() if best else [],
                "skeleton_space": ({"steps_per_phase": self.space.steps_per_phase,
                                    "init_frame": self.space.init_frame}
                                   if best and self.space else None),
                "plan_seconds": round(self.seconds, 2),
                "programs_solved": len(self.candidates),
                "violation": float(best.violation) if best else None,
                "cost": float(best.cost) if best else None,
                "dynamics_rms_mm": round(best.dynamics_rms_mm, 3) if best else None,
                "obstacle_clearance": metres(best.clearance) if best else None}


def plan(scene: Scene, model: str | Path | None = None, *, solver: str = "snopt",
         workers: int = 2, skeleton: str | Skeleton | None = None, max_pushes: int = 2,
         progress: bool = True, exhaustive: bool = False, quiet: bool = False,
         time_budget: float | None = None, warm_start: Plan | None = None) -> Plan:
    """Search the scene's skeletons and solve their programs; no simulator runs.

    ``model``: the learned dynamics' folder (default: the shipped F_flow). ``skeleton``: one
    skeleton (in the CLI's notation, or a ``Skeleton``) instead of the search.
    ``warm_start``: an earlier plan of this scene (at other poses): its skeleton is tried
    first, from its trajectories; a fresh search follows when that does not solve.
    """
    model_dir = Path(model) if model is not None else learned_dir("push_flow")
    guesses = None
    if warm_start is not None and warm_start.best is not None and skeleton is None:
        skeleton = warm_start.best.skeleton
        guesses = {warm_start.best.skeleton: warm_guess(scene, warm_start.best)}
    obj, _actors = check_supported(scene)
    result, spaces = search_scene(scene, model_dir, solver, workers, skeleton, max_pushes,
                                  progress, exhaustive, quiet, time_budget, guesses)
    if not result.solved and guesses is not None:  # the old skeleton is lost: search afresh
        again, more = search_scene(scene, model_dir, solver, workers, None, max_pushes,
                                   progress, exhaustive, quiet, time_budget)
        result, spaces = merge_results(result, again), {**spaces, **more}
    if not quiet:
        print(candidate_table(result))
    best = result.best
    return Plan(scene, obj, best, result.solved, result.candidates, result.seconds,
                spaces.get(id(best)) if best is not None else None)


def execute(planned: Plan, scene: Scene | None = None) -> Execution:
    """Run the best plan open loop in pybullet (paper §7.2.3) in ``scene`` (default: the
    plan's); reaches run slower than the data's pushes (see ``reach_substeps``)."""
    if planned.best is None:
        raise ValueError("nothing to execute: the plan has no solution")
    scene = scene or planned.scene
    best, obj = planned.best, planned.obj
    steps = len(best.q_pusher) - 1
    T = steps // len(best.skeleton.phases)
    push = np.array([best.skeleton.phases[t // T].mode == "push" for t in range(steps)])
    if scene.robots:
        slow = round(ARM_PROGRAM_SETTINGS.reach_slowdown)
        substeps = [PHYSICS.keep_every * (1 if p else slow) for p in push]
        ex = execute_arms(scene, obj, best.q_joints, substeps)
    else:
        substeps = reach_substeps(best.q_pusher, push)
        ex = execute_push(scene, obj, scene.pushers[0].name, best.q_pusher, substeps=substeps)
    times = np.concatenate(([0.0], np.cumsum(substeps) / PHYSICS.keep_every * STEP_SECONDS))
    ex.times = times
    return ex


def _object_tracks(planned: Plan, executed: Execution) -> tuple[dict, dict]:
    """The moved objects' planned and simulated poses by name, each ``(N+1, 3)``."""
    best, obj = planned.best, planned.obj
    planned_poses = {obj: best.q_obj, **best.q_others}
    simulated = {obj: executed.object_poses,
                 **{k: v for k, v in executed.others.items() if k in planned_poses}}
    return planned_poses, simulated


def write_playback(planned: Plan, executed: Execution, path: Path) -> None:
    """The self-contained MeshCat page replaying the plan (ghosted) and its execution."""
    best, ex, scene = planned.best, executed, planned.scene
    planned_poses, simulated = _object_tracks(planned, executed)
    actor = scene.pushers[0].name if scene.pushers else None
    plan_tracks = {**planned_poses, **({actor: best.q_pusher} if actor else {})}
    executed_tracks = {**simulated, **({actor: ex.pusher_positions} if actor else {})}
    write_playback_html(scene, Path(path), plan_tracks, executed_tracks,
                        joints=(best.q_joints, ex.joints), times=executed.times)


def execution_summary(planned: Plan, executed: Execution) -> dict:
    """The execution's entries of ``result.json``: outcome, planned and executed tracks."""
    best, ex, obj = planned.best, executed, planned.obj
    planned_poses, simulated = _object_tracks(planned, executed)
    final = {obj: ex.final_pose, **{k: v[-1] for k, v in ex.others.items()}}
    doc = {"execution": {"simulator": "pybullet", "mode": "open_loop",
                         "coverage": ex.coverage,
                         "final_poses": {k: [float(x) for x in v] for k, v in final.items()},
                         "touch_distance": ex.touch_distance,
                         "obstacle_contact": ex.obstacle_contact,
                         "forbidden_contacts": ex.forbidden_contacts},
           "trajectory": {"t": [round(float(v), 6) for v in executed.times],
                          "pusher": best.q_pusher.tolist(),
                          "objects": {k: v.tolist() for k, v in planned_poses.items()},
                          "contact_points": best.contact.tolist(),
                          "joints": {k: v.tolist() for k, v in best.q_joints.items()}},
           "executed": {"pusher": ex.pusher_positions.tolist(),
                        "objects": {k: v.tolist() for k, v in simulated.items()},
                        "joints": {k: v.tolist() for k, v in ex.joints.items()},
                        "tips": {k: v.tolist() for k, v in ex.tips.items()}}}
    if best.contact_others:
        doc["trajectory"]["object_contact_points"] = {
            k: v.tolist() for k, v in best.contact_others.items()}
    return doc


def solve(scene: Scene, out: Path, model: str | Path | None = None, *, quiet: bool = False,
          **options: object) -> dict:
    """Plan, execute the best plan, write ``out/playback.html`` and ``out/result.json``
    (whole or not at all); the result document. ``options``: those of :func:`plan`."""
    out = Path(out)
    planned = plan(scene, model, quiet=quiet, **options)
    doc: dict = {"scene": scene.name, **planned.summary()}
    if planned.best is not None:
        best = planned.best
        if not quiet and best.q_others:
            print(f"plan: {' and '.join([planned.obj, *best.q_others])} pushed by "
                  f"{best.skeleton.phases[0].actor}; executing in pybullet")
        executed = execute(planned)
        doc.update(execution_summary(planned, executed))
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
