"""``robotplan solve``: plan, execute in pybullet, write result.json and the playback."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from robotplan.execute import execute_push
from robotplan.planner import FEASIBLE, PLAUSIBLE_RMS_MM, SearchResult, search_push
from robotplan.program import ProgramSettings
from robotplan.render import write_atomically
from robotplan.scene import Scene
from robotplan.skeleton import load_skeleton_space, parse_skeleton

__all__ = ["UnsupportedScene", "candidate_table", "solve_scene"]


class UnsupportedScene(ValueError):
    """The scene is valid but needs a planner feature that is not built yet."""


def _check_supported(scene: Scene) -> tuple[str, str]:
    if scene.robots:
        raise UnsupportedScene("robots: scenes with robot arms are not planned yet")
    if len(scene.objects) != 1 or scene.obstacles or len(scene.pushers) != 1:
        raise UnsupportedScene("objects: only one object, one pusher and no obstacles are "
                               "planned yet")
    if scene.goal.type != "region":
        raise UnsupportedScene("goal: only region goals are planned yet")
    shape = scene.objects[0].shape.type
    if shape not in ("box", "lshape"):
        raise UnsupportedScene(f"objects[0].shape: {shape} footprints are not simulated yet")
    return scene.objects[0].name, scene.pushers[0].name


def candidate_table(result: SearchResult) -> str:
    lines = [f"{'#':>2}  {'skeleton':<40} {'violation':>10} {'cost':>9} {'H_F rms mm':>10} "
             f"{'seconds':>8}  status"]
    for i, s in enumerate(result.candidates):
        mark = " <- best" if s is result.best else ""
        lines.append(f"{i:>2}  {s.skeleton.describe():<40} {s.violation:>10.3g} "
                     f"{s.cost:>9.3g} {s.dynamics_rms_mm:>10.2f} {s.seconds:>8.1f}  "
                     f"{s.status}{mark}")
    return "\n".join(lines)


def solve_scene(scene: Scene, out: Path, model_dir: Path, solver: str = "snopt",
                workers: int = 2, skeleton: str | None = None, max_pushes: int = 2,
                progress: bool = True, exhaustive: bool = False, quiet: bool = False,
                time_budget: float | None = None) -> dict:
    from robotplan.viewer import write_playback

    obj, pusher = _check_supported(scene)
    space = load_skeleton_space()
    skeletons = ([parse_skeleton(skeleton, pusher, obj)] if skeleton
                 else space.candidates(pusher, obj, max_pushes))
    settings = ProgramSettings(solver=solver)
    result = search_push(scene, model_dir, skeletons, settings, workers, progress, exhaustive,
                         time_budget)
    if not quiet:
        print(candidate_table(result))
    best = result.best
    dt = 1.0 / 12.0  # a kept step of the push data: 20 × 1/240 s
    doc: dict = {"scene": scene.name, "status": "solved" if result.solved else "no_solution",
                 "skeleton": best.skeleton.as_rows() if best else [],
                 "plan_seconds": round(result.seconds, 2),
                 "programs_solved": len(result.candidates),
                 "violation": float(best.violation) if best else None,
                 "cost": float(best.cost) if best else None,
                 "dynamics_rms_mm": round(best.dynamics_rms_mm, 3) if best else None}
    if best is not None:
        ex = execute_push(scene, obj, pusher, best.q_pusher)
        doc["execution"] = {"simulator": "pybullet", "coverage": ex.coverage,
                            "final_poses": {obj: [float(v) for v in ex.final_pose]},
                            "touch_distance": ex.touch_distance}
        doc["trajectory"] = {"t": [round(k * dt, 6) for k in range(len(best.q_pusher))],
                             "pusher": best.q_pusher.tolist(),
                             "objects": {obj: best.q_obj.tolist()},
                             "contact_points": best.contact.tolist(), "joints": {}}
        doc["executed"] = {"pusher": ex.pusher_positions.tolist(),
                           "objects": {obj: ex.object_poses.tolist()}}
        doc["candidates"] = [{"skeleton": s.skeleton.describe(), "violation": s.violation,
                              "cost": s.cost, "seconds": round(s.seconds, 2),
                              "dynamics_rms_mm": round(s.dynamics_rms_mm, 3),
                              "timings": s.timings,
                              "status": s.status} for s in result.candidates]
        write_playback(scene, out / "playback.html",
                       {obj: best.q_obj, pusher: best.q_pusher},
                       {obj: ex.object_poses, pusher: ex.pusher_positions})
        doc["playback"] = "playback.html"
    doc["feasibility_threshold"] = FEASIBLE
    doc["plausible_dynamics_rms_mm"] = PLAUSIBLE_RMS_MM
    write_atomically(out / "result.json",
                     lambda tmp: tmp.write_text(json.dumps(doc, indent=1, default=_json)))
    return doc


def _json(x: object) -> object:
    if isinstance(x, np.generic):
        return x.item()
    raise TypeError(type(x))
