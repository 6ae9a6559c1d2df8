"""The result documents of a push plan and its execution (``result.json``'s entries)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from robotplan.base.files import write_atomically
from robotplan.execution.physics import PHYSICS
from robotplan.functionals.clearance import OBSTACLE_MARGIN
from robotplan.pushing.execution.execute import Execution, plan_substeps
from robotplan.pushing.execution.perturb import Perturbation
from robotplan.pushing.program.solution import Solution
from robotplan.pushing.search.planner import FEASIBLE, PLAUSIBLE_RMS_MM
from robotplan.pushing.search.scene_search import metres
from robotplan.scene.task import PushTask

__all__ = ["candidate_summary", "execution_summary", "outcome_status", "thresholds",
           "write_json"]


def candidate_summary(s: Solution) -> dict:
    """One solved candidate's entry of ``result.json``."""
    return {"skeleton": s.skeleton.describe(), "violation": s.violation, "cost": s.cost,
            "seconds": round(s.seconds, 2), "dynamics_rms_mm": round(s.dynamics_rms_mm, 3),
            "obstacle_clearance": metres(s.clearance), "timings": s.timings,
            "status": s.status}


def outcome_status(doc: dict) -> str:
    """A push result's ``status``: ``solved`` (the plan meets every constraint and, where it
    was executed, the simulator reached the goal), ``reached`` (the plan does not meet every
    constraint, but its execution reached the goal), ``missed`` (executed, the goal not
    reached) or ``no_solution`` (no plan to execute)."""
    reached = (doc.get("execution") or {}).get("goal_reached")
    if doc["plan_status"] == "solved" and reached is not False:
        return "solved"
    if reached is None:
        return "no_solution"
    return "reached" if reached else "missed"


def thresholds() -> dict:
    """The thresholds a push plan is judged by, recorded beside it."""
    return {"feasibility_threshold": FEASIBLE, "plausible_dynamics_rms_mm": PLAUSIBLE_RMS_MM,
            "obstacle_margin": OBSTACLE_MARGIN}


def _json(x: object) -> object:
    if isinstance(x, np.generic):
        return x.item()
    raise TypeError(type(x))


def write_json(path: Path, doc: dict) -> None:
    """``doc`` as ``path``, whole or not at all (numpy scalars as numbers)."""
    write_atomically(path, lambda tmp: tmp.write_text(json.dumps(doc, indent=1, default=_json)))


def _track_doc(sol: Solution, task: PushTask) -> dict:
    obj = task.obj
    times = np.concatenate(([0.0], np.cumsum(plan_substeps(task, sol)))) * PHYSICS.timestep
    doc = {"t": [round(float(v), 6) for v in times], "skeleton": sol.skeleton.describe(),
           "pusher": sol.q_pusher.tolist(),
           "objects": {obj: sol.q_obj.tolist(), **{k: v.tolist() for k, v in sol.q_others.items()}},
           "contact_points": sol.contact.tolist(),
           "joints": {k: v.tolist() for k, v in sol.q_joints.items()}}
    if sol.contact_others:
        doc["object_contact_points"] = {k: v.tolist() for k, v in sol.contact_others.items()}
    return doc


def execution_summary(planned, executed: Execution,
                      perturb: Perturbation | None = None) -> dict:
    """The execution's entries of ``result.json``: mode and outcome, every re-plan, the
    planned trajectories (the first plan and each adopted re-plan) and the executed ones."""
    ex, obj = executed, planned.obj
    final = {obj: ex.final_pose, **{k: v[-1] for k, v in ex.others.items()}}
    plans = ex.plans or [(0, planned.best)]
    tracks = []
    for step, sol in plans:
        track = _track_doc(sol, planned.task)
        tracks.append({"step": step, "time": round(float(ex.times[step]), 4), **track})
    doc = {"execution": {"simulator": ex.simulator, "mode": ex.mode,
                         "coverage": ex.coverage,
                         "final_poses": {k: [float(x) for x in v] for k, v in final.items()},
                         "touch_distance": ex.touch_distance,
                         "obstacle_contact": ex.obstacle_contact,
                         "forbidden_contacts": ex.forbidden_contacts,
                         "replans": [r.as_dict() for r in ex.replans],
                         "stopped": ex.stopped,
                         "perturbation": perturb.describe() if perturb else None},
           "trajectory": {k: v for k, v in tracks[0].items() if k not in ("step", "time")},
           "replanned": tracks[1:],
           "executed": {"t": [round(float(v), 6) for v in ex.times],
                        "pusher": ex.pusher_positions.tolist(),
                        "objects": {obj: ex.object_poses.tolist(),
                                    **{k: v.tolist() for k, v in ex.others.items()}},
                        "joints": {k: v.tolist() for k, v in ex.joints.items()},
                        "tips": {k: v.tolist() for k, v in ex.tips.items()}}}
    return doc
