"""Rehearsal: a plan run closed loop in the learned model F_q before it runs open loop.

A plan's object trajectory meets F_q only as well as its learned stage could make it (the
H_q row is a cost): the kinematic plans the search mostly keeps move an L-shape 10–40 mm
per step away from where F_q sends it, and open loop the object follows the pusher, not the
plan. Rehearsing it runs the plan in
:class:`~robotplan.pushing.execution.imagined_world.ImaginedWorld` with the closed loop's re-plans
(:func:`~robotplan.pushing.execution.closed_loop.execute_closed_loop`): where F_q's object leaves
the plan, the rest is planned again from where F_q put it. The pusher's states of that run are the
open-loop plan: they take F_q's object to the goal. Nothing of the simulator is used; the open loop
then runs them in pybullet unchanged (measured: docs/experiments.md#rehearsal).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robotplan.base.resources import REHEARSAL_FOLDERS, learned_dir
from robotplan.execution.physics import PHYSICS, Physics
from robotplan.pushing.execution.closed_loop import Replanner, execute_closed_loop
from robotplan.pushing.execution.imagined_world import ImaginedWorld
from robotplan.pushing.execution.loop_settings import LoopSettings
from robotplan.pushing.models.rigid import RigidMotion
from robotplan.pushing.program.solution import Solution
from robotplan.scene.task import PushTask

__all__ = ["REHEARSAL_BUDGET", "Rehearsal", "rehearsable", "rehearsal_world", "rehearse"]

# s after which a rehearsal asks for no more re-plans and runs its current plan to the end:
# the benchmark's longest rehearsals that helped took 88 and 118 s, an unseen U-shape's ran
# 276 s to end no closer (measured: docs/experiments.md#rehearsal)
REHEARSAL_BUDGET = 120.0


@dataclass
class Rehearsal:
    """The pusher's states ``pusher (M+1, 2)`` the open loop follows, step t over
    ``substeps[t−1]`` simulation steps, and the object's poses ``object_poses (M+1, 3)``
    (X_WB) F_q gives them; the goal coverage F_q's object ends at, the re-plans and the
    plans followed (``(step, Solution)``), the seconds it took and the F_q's folder."""

    pusher: np.ndarray
    object_poses: np.ndarray
    substeps: list[int]
    coverage: float
    replans: list = field(default_factory=list)
    plans: list = field(default_factory=list)
    seconds: float = 0.0
    model: str = ""

    def times(self, physics: Physics = PHYSICS) -> np.ndarray:
        """``(M+1,)`` s of the states."""
        return np.concatenate(([0.0], np.cumsum(self.substeps))) * physics.timestep

    def summary(self, physics: Physics = PHYSICS) -> dict:
        """The rehearsal's entry of ``result.json``."""
        return {"model": self.model, "model_coverage": self.coverage,
                "seconds": round(self.seconds, 2),
                "replans": len(self.replans),
                "adopted": sum(bool(r.adopted) for r in self.replans),
                "t": [round(float(v), 6) for v in self.times(physics)],
                "pusher": self.pusher.tolist(), "object": self.object_poses.tolist()}


def rehearsable(task: PushTask) -> bool:
    """Whether a plan of the task is rehearsed: F_q can stand in for the simulator (one free
    pusher, one object, no obstacles: F_q does not see them) and the goal is a region. A
    pose goal's rehearsal took 2–228 s for an open loop no better than the plan's own
    (measured: docs/experiments.md#rehearsal)."""
    return task.single and not task.obstacles and task.goal == "region"


def rehearsal_world(task: PushTask, model_dir: str | Path,
                    rehearsal_model: str | Path | None = None) -> Path:
    """The F_q folder a plan of the task's object made with ``model_dir`` is rehearsed in:
    the one given, else ``REHEARSAL_FOLDERS``' for the object's footprint type, else the
    plan's own."""
    if rehearsal_model is not None:
        return Path(rehearsal_model)
    footprint = task.scene.bodies[task.obj].shape.type
    if footprint in REHEARSAL_FOLDERS:
        return learned_dir(REHEARSAL_FOLDERS[footprint])
    return Path(model_dir)


def rehearse(task: PushTask, sol: Solution, replan: Replanner, model: RigidMotion,
             settings: LoopSettings | None = None, physics: Physics = PHYSICS,
             folder: str = "", budget: float = REHEARSAL_BUDGET) -> Rehearsal:
    """Run ``sol`` closed loop in F_q (``model``, read from ``folder``), re-planning through
    ``replan`` as the closed loop does (``settings``: the scene class's by default) for up
    to ``budget`` seconds, then on with the plan in hand; see the module docstring."""
    t0 = time.perf_counter()

    def within_budget(observed: PushTask, tail: Solution | None, fresh: bool,
                      last_resort: float | None = None, deadline: float | None = None):
        if time.perf_counter() - t0 > budget:
            return None  # nothing planned: the loop goes on with its plan
        return replan(observed, tail, fresh, last_resort, deadline)

    ex = execute_closed_loop(task, sol, within_budget, settings, physics,
                             world_of=lambda t, p: ImaginedWorld(t, model, p))
    substeps = [int(n) for n in np.rint(np.diff(ex.times) / physics.timestep)]
    return Rehearsal(ex.pusher_positions, ex.object_poses, substeps, float(ex.coverage),
                     ex.replans, ex.plans, time.perf_counter() - t0, folder)
