"""The layers of a push plan's playback page: the executed motion and the plans it
followed, ghosted."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from robotplan.execution.physics import PHYSICS
from robotplan.pushing.execution.execute import Execution, plan_substeps
from robotplan.pushing.program.solution import Solution
from robotplan.scene.task import PushTask
from robotplan.viz.viewer import Layer

if TYPE_CHECKING:
    from robotplan.pushing.api.push import PushPlan

__all__ = ["playback_layers"]


def _plan_layer(task: PushTask, sol: Solution, start: float, name: str,
                shown: tuple[float, float | None] | None) -> Layer:
    """A plan as a ghosted playback layer from ``start`` s on."""
    times = start + np.concatenate(([0.0], np.cumsum(plan_substeps(task, sol)))) * (
        PHYSICS.timestep)
    tracks = {task.obj: sol.q_obj, **sol.q_others}
    if not task.arms:
        tracks[task.actors[0]] = sol.q_pusher
    return Layer(name, times, tracks, sol.q_joints, ghost=True, shown=shown)


def _plan_layers(planned: PushPlan, ex: Execution) -> list[Layer]:
    """Every plan ``ex`` followed (the first, then each re-plan), each shown from when it
    was made until the next one."""
    plans = ex.plans or [(0, planned.best)]
    starts = [float(ex.times[step]) for step, _ in plans]
    layers = []
    for k, (_step, sol) in enumerate(plans):
        until = starts[k + 1] if k + 1 < len(plans) else None
        shown = (starts[k], until) if len(plans) > 1 else None
        layers.append(_plan_layer(planned.task, sol, starts[k],
                                  "plan" if k == 0 else f"replan_{k}", shown))
    return layers


def playback_layers(planned: PushPlan, executed: Execution) -> list[Layer]:
    """The executed motion and every plan it followed (the first, then each re-plan), each
    plan shown from when it was made until the next one; an open loop of a rehearsed plan
    shows the rehearsal (F_q's object and the pusher) as its plan."""
    task, obj, ex = planned.task, planned.obj, executed
    r = planned.rehearsal
    if ex.mode == "open_loop" and r is not None:
        layers = [Layer("rehearsal", r.times(), {obj: r.object_poses,
                                                 task.actors[0]: r.pusher})]
    else:
        layers = _plan_layers(planned, ex)
    tracks = {obj: ex.object_poses, **{k: v for k, v in ex.others.items()}}
    if not task.arms:
        tracks[task.actors[0]] = ex.pusher_positions
    layers.append(Layer("executed", ex.times, tracks, ex.joints, ghost=False))
    return layers
