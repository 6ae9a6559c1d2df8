"""The public facade: :func:`plan` (skeleton search and Drake programs, no simulator),
:func:`execute` (pybullet, or MuJoCo with ``sim="mujoco"``), :func:`write_playback`
(MeshCat page) and :func:`solve`, which composes them and writes ``result.json``, as
``robotplan solve`` does.

A scene is classified once into its task (:func:`~robotplan.scene.task.make_task`): a
:class:`~robotplan.scene.task.PushTask` or a :class:`~robotplan.scene.task.HangTask`. Each
call dispatches once, by the task's family, to that family's planner
(:class:`~robotplan.pushing.api.push.PushPlanner`,
:class:`~robotplan.hanging.api.planner.HangPlanner`), which returns the family's plan type.
"""

from __future__ import annotations

from pathlib import Path
from typing import overload

from robotplan.hanging.api.planner import HangExecution, HangPlan, HangPlanner
from robotplan.pushing.api.push import PushPlan, PushPlanner
from robotplan.pushing.execution.execute import Execution
from robotplan.scene import Scene
from robotplan.scene.task import HangTask, PushTask, Task, UnsupportedScene, load_task, make_task

__all__ = ["Execution", "HangPlan", "HangTask", "PushPlan", "PushTask", "Task",
           "UnsupportedScene", "execute", "load_task", "make_task", "plan", "planner_for",
           "solve", "write_playback"]

PLANNERS: dict[str, PushPlanner | HangPlanner] = {"push": PushPlanner(), "hang": HangPlanner()}
"""The planner of each task family (``Task.family``)."""


def as_task(scene: Scene | Task) -> Task:
    """The task of ``scene`` (classified here), or the task given."""
    return scene if isinstance(scene, PushTask | HangTask) else make_task(scene)


def planner_for(task: Task) -> PushPlanner | HangPlanner:
    """The planner of the task's family."""
    return PLANNERS[task.family]


@overload
def plan(task: PushTask, model: str | Path | None = None, **options: object) -> PushPlan: ...


@overload
def plan(task: HangTask, model: str | Path | None = None, **options: object) -> HangPlan: ...


@overload
def plan(task: Scene, model: str | Path | None = None,
         **options: object) -> PushPlan | HangPlan: ...


def plan(task, model=None, **options):
    """Plan a task (or a scene, classified first): the family planner's ``plan``, no
    simulator. Push tasks: :meth:`PushPlanner.plan` (the skeleton search; ``model``: the
    learned dynamics' folder); hang tasks: :meth:`HangPlanner.plan` (a mug pose on the hook;
    ``model``: H_hang's folder)."""
    task = as_task(task)
    return planner_for(task).plan(task, model, **options)


def execute(planned: PushPlan | HangPlan, scene: Scene | None = None, *,
            mode: str = "closed_loop", **options: object) -> Execution | HangExecution:
    """Run a plan in a simulator, closed loop (``mode="closed_loop"``, the default:
    re-planning from the observed state) or open loop (the paper's protocol), in ``scene``
    (default: the plan's). ``options``: the family planner's (:meth:`PushPlanner.execute`:
    ``sim`` (``"pybullet"``, the default, or ``"mujoco"``), ``perturb``, ``loop``,
    ``quiet``)."""
    return planner_for(planned.task).execute(planned, scene=scene, mode=mode, **options)


def write_playback(planned: PushPlan | HangPlan, executed: Execution | HangExecution,
                   path: Path) -> None:
    """The self-contained MeshCat page replaying the execution with its plans ghosted."""
    planner_for(planned.task).playback(planned, executed, Path(path))


def solve(task: Scene | Task, out: Path, model: str | Path | None = None,
          **options: object) -> dict:
    """Plan, execute, write ``out/playback.html`` and ``out/result.json`` (whole or not at
    all); the result document (:meth:`PushPlanner.solve`, :meth:`HangPlanner.solve`)."""
    task = as_task(task)
    return planner_for(task).solve(task, Path(out), model, **options)
