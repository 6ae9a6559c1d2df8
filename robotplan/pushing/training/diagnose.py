"""Where a free-pusher plan and physics part ways: ``robotplan diagnose DIR SCENE``.

For every push step t of ``DIR/result.json`` the object's planned step q1_{t−1} → q1_t is
compared with two one-step predictions from the planned state (q1_{t−1}, q2_{t−1}) and the
planned pusher move q2_{t−1} → q2_t:

* **physics**: pybullet (the execution's world), the object at rest at q1_{t−1}, the pusher
  driven along the move with ``keep_every`` interpolation steps;
* **model**: the learned model read as the planner reads it, argmin_{q1_t} H_t
  (:func:`~robotplan.pushing.training.pose_fit.fit_step`).

A plan whose steps agree with physics but which executes badly drifts (open-loop
instability); one that disagrees step by step rests on a wrong dynamics prediction. Physics
from rest ignores the object's momentum, so it lags a little behind a moving push.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch

from robotplan.execution.physics import PHYSICS, push_world
from robotplan.geometry.transforms import wrap_angle
from robotplan.pushing.execution.execute import obstacle_bodies
from robotplan.pushing.models.dynamics import load_model
from robotplan.pushing.training.pose_fit import fit_step
from robotplan.scene.task import PushTask

__all__ = ["StepCheck", "check_steps", "summarize", "table", "to_json"]


@dataclass
class StepCheck:
    """One push step: object steps ``(3,)`` (dx, dy m; dyaw rad) and the pusher's move."""

    t: int
    plan: list[float]
    physics: list[float]
    model: list[float]
    pusher: list[float]


def _delta(a: np.ndarray, b: np.ndarray) -> list[float]:
    d = np.asarray(b, dtype=float) - np.asarray(a, dtype=float)
    return [float(d[0]), float(d[1]), float(wrap_angle(d[2]))]


def check_steps(task: PushTask, result: dict, model_dir: str | Path) -> list[StepCheck]:
    """One :class:`StepCheck` per push step of a free-pusher plan (``result.json``)."""
    traj, scene = result.get("trajectory") or {}, task.scene
    if "pusher" not in traj or task.arms:
        raise ValueError("result.json has no free-pusher trajectory (arm plans are not "
                         "diagnosed yet)")
    if len(traj.get("objects", {})) > 1:
        raise ValueError("plans that push one object with another are not diagnosed yet")
    obj_name, poses = next(iter(traj["objects"].items()))
    Q1, Q2 = np.asarray(poses, dtype=float), np.asarray(traj["pusher"], dtype=float)
    body, spec = scene.bodies[obj_name], next(o for o in scene.objects if o.name == obj_name)
    tool = scene.bodies[task.actors[0]]
    model = load_model(model_dir)  # LearnedDynamics freezes its parameters
    checks = []
    with push_world(PHYSICS) as world:
        for t in range(1, len(Q1)):
            # push steps: the pusher within 2 mm of the object at either end of the step
            gap = min(float(body.sdf(torch.tensor(Q2[k][None]), torch.tensor(Q1[k]))[0])
                      for k in (t - 1, t))
            if gap > tool.shape.radius + 0.002:
                continue
            world.reset(body.shape, spec.height, tuple(Q1[t - 1]), tool.shape.radius,
                        tuple(Q2[t - 1]), obstacle_bodies(scene))
            for s in range(1, PHYSICS.keep_every + 1):
                world.step(tuple(Q2[t - 1] + (Q2[t] - Q2[t - 1]) * s / PHYSICS.keep_every))
            fit = fit_step(model, body, tool, Q1[t - 1], Q2[t - 1], Q2[t])
            checks.append(StepCheck(t, _delta(Q1[t - 1], Q1[t]),
                                    _delta(Q1[t - 1], world.object_pose()[0]),
                                    _delta(Q1[t - 1], fit),
                                    [float(v) for v in Q2[t] - Q2[t - 1]]))
    return checks


def summarize(checks: list[StepCheck]) -> dict:
    """Median disagreements over the push steps: translation (mm) and turn (degrees) of
    plan vs physics, model vs physics and plan vs model; and the turns' sums."""
    out: dict = {"push_steps": len(checks)}
    if not checks:
        return out
    A = {k: np.array([getattr(c, k) for c in checks]) for k in ("plan", "physics", "model")}
    for a, b in (("plan", "physics"), ("model", "physics"), ("plan", "model")):
        d = A[a] - A[b]
        out[f"{a}_vs_{b}"] = {
            "translation_mm": round(1e3 * float(np.median(np.linalg.norm(d[:, :2], axis=1))), 2),
            "turn_deg": round(float(np.degrees(np.median(np.abs(d[:, 2])))), 2)}
    out["total_turn_deg"] = {k: round(float(np.degrees(v[:, 2].sum())), 1) for k, v in A.items()}
    return out


def table(checks: list[StepCheck]) -> str:
    """A line per push step: the object's step in mm and degrees for plan, physics, model."""

    def f(v: list[float]) -> str:
        return f"{1e3 * v[0]:6.1f} {1e3 * v[1]:6.1f} {np.degrees(v[2]):6.1f}"

    head = (f"{'t':>3}  {'plan dx dy dθ':>20}  {'physics':>20}  {'model':>20}  "
            f"{'pusher dx dy':>13}")
    rows = [f"{c.t:>3}  {f(c.plan):>20}  {f(c.physics):>20}  {f(c.model):>20}  "
            f"{1e3 * c.pusher[0]:6.1f} {1e3 * c.pusher[1]:6.1f}" for c in checks]
    return "\n".join([head, *rows])


def to_json(checks: list[StepCheck]) -> str:
    return json.dumps({"summary": summarize(checks), "steps": [asdict(c) for c in checks]})
