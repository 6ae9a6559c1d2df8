"""The facade for hang tasks (:class:`~robotplan.scene.task.HangTask`): ``plan`` finds a mug
pose on the hook (H_hang and H_coll, with restarts), ``execute`` drops the mug from it in
a simulator (pybullet by default, or MuJoCo: :mod:`robotplan.hanging.execution.worlds`),
``write_playback`` shows both; :class:`HangPlanner` offers them as its methods.

Closed loop (the default of ``execute``): when the mug falls from the found pose, the search
goes on from where it stopped (same random starts, the same budget of restarts and
evaluations), dropping each further pose it finds, until one hangs. Open loop drops the
first found pose only, the paper's protocol (Tab. 3).

Poses: the hook stands at its table pose X_WH; the search works in the hook frame H (as the
data and H_hang do); results are reported in the world frame W, ``(x, y, z, qw, qx, qy, qz)``
(:mod:`robotplan.hanging.api.poses`).
"""

from __future__ import annotations

import copy
import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robotplan.base.files import write_atomically
from robotplan.base.resources import learned_dir
from robotplan.hanging.api.poses import compose, inverse_pose, table_pose
from robotplan.hanging.execution.drop import DropResult
from robotplan.hanging.execution.worlds import hang_world
from robotplan.hanging.models.hang_model import load_hang_model
from robotplan.hanging.program.problem import HANG_DEFAULTS, HangProblem, HangSettings, HangSolution
from robotplan.hanging.scene.parts import hang_parts
from robotplan.hanging.search.optimise import optimise_hang
from robotplan.hanging.viz.picture import write_hang_picture
from robotplan.hanging.viz.viewer import write_hang_playback
from robotplan.scene.schema import Scene
from robotplan.scene.task import HangTask, TaskPlan

__all__ = [
    "HangExecution",
    "HangPlan",
    "HangPlanner",
    "execute_hang",
    "inverse_pose",
    "plan_hang",
    "solve_hang",
    "write_hang_playback_page",
    "write_hang_still",
]


@dataclass
class HangPlan(TaskPlan):
    """The pose found for the mug, in the hook frame (``solution.pose``) and in the world."""

    task: HangTask
    solution: HangSolution
    model: str
    X_WH: np.ndarray
    X_WM_start: np.ndarray
    settings: HangSettings = HANG_DEFAULTS
    # where a re-plan goes on: the scene's functionals, the random starts' generator and the
    # search's number of restarts
    search: tuple[HangProblem, np.random.Generator, int | None] | None = field(
        default=None, repr=False)

    @property
    def solved(self) -> bool:
        return self.solution.feasible

    @property
    def X_WM(self) -> np.ndarray:
        return compose(self.X_WH, self.solution.pose)


@dataclass
class HangExecution:
    hung: bool
    collision_at_start: bool
    on_ground: bool
    X_WM_end: np.ndarray
    in_place: bool = False  # hung without first falling onto the hook
    fall_m: float = 0.0  # how far the mug's centre came down before it rested
    drop: list = field(default_factory=list)  # [(t, X_WM)] every 1/30 s
    seconds: float = 0.0
    mode: str = "closed_loop"
    simulator: str = "pybullet"  # the world the mug was dropped in
    # closed loop: one entry per found pose the mug fell from, after which the search went on
    # while its budget lasted: step (the drop's number), reason, violation (of the program's
    # rows at that pose, within tolerance), h_hang, h_coll_cm3, seconds of the drop
    replans: list[dict] = field(default_factory=list)
    solution: HangSolution | None = None  # the pose dropped last (the plan's, or a re-plan's)


CHECK = learned_dir("hang_check")  # the check network beside learned/hang


def plan_hang(task: HangTask, model: str | Path | None = None, *, seed: int = 0,
              settings: HangSettings | None = None, restarts: int | None = None,
              check: str | Path | None = CHECK) -> HangPlan:
    """Optimisation from random poses (``restarts``, default the settings' 20) within the
    evaluation budget; ``seed`` draws the starts; ``settings`` default ``HANG_DEFAULTS``;
    ``check``: the folder of a second H_hang a found pose must satisfy too
    (``HangSettings.check_kappa``; None: none, the paper's one network)."""
    settings = settings or HANG_DEFAULTS
    mug, hook, mug_pose, hook_pose = hang_parts(task.scene)
    folder = str(model or learned_dir("hang"))
    problem = HangProblem(load_hang_model(folder), mug, hook, settings.collision,
                          None if check is None else load_hang_model(check))
    rng = np.random.default_rng(seed)
    sol = optimise_hang(problem, rng, settings, restarts)
    return HangPlan(task, sol, folder, table_pose(*hook_pose), table_pose(*mug_pose),
                    settings, (problem, rng, restarts))


def _fell(result: DropResult) -> str | None:
    """Why a drop did not solve the scene (None: it hangs; a pose that starts inside the hook
    does not)."""
    if result.collision_at_start:
        return "the mug started inside the hook"
    if not result.hangs:
        return "the mug fell" + (" to the ground" if result.on_ground else " off the hook")
    return None


def execute_hang(planned: HangPlan, mode: str = "closed_loop",
                 sim: str = "pybullet") -> HangExecution:
    """Drop the mug from the found pose in simulator ``sim`` (in the hook's world, then
    reported in W); in closed loop, while it falls, go on with the search and drop the next
    pose found (module docstring). ``replans`` lists the poses dropped before the one
    reported, each with why the mug did not hang there."""
    if mode not in ("closed_loop", "open_loop"):
        raise ValueError(f"mode {mode!r}: expected closed_loop or open_loop")
    mug, hook, _, _ = hang_parts(planned.scene)
    t0 = time.perf_counter()
    trials: list[tuple[HangSolution, DropResult, list, float]] = []
    with hang_world(hook, mug, sim) as world:

        def dropped(sol: HangSolution) -> DropResult:
            t, record = time.perf_counter(), []
            result = world.drop(sol.pose, record=record)
            trials.append((sol, result, record, time.perf_counter() - t))
            return result

        sol = planned.solution
        first = dropped(sol)
        if (mode == "closed_loop" and sol.feasible and not first.hangs
                and planned.search is not None):
            problem, rng, restarts = planned.search  # a copy: executions repeat
            sol = optimise_hang(problem, copy.deepcopy(rng), planned.settings, restarts,
                                accept=lambda found: dropped(found).hangs,
                                resume=sol)
    reported = next(k for k, (s, *_) in enumerate(trials) if np.array_equal(s.pose, sol.pose))
    result, record = trials[reported][1:3]
    replans = [{"step": k + 1, "reason": _fell(r),
                "violation": round(HangProblem.violation(s, planned.settings), 6),
                "h_hang": round(s.h_hang, 5), "h_coll_cm3": round(s.h_coll_cm3, 6),
                "seconds": round(dt, 3)}
               for k, (s, r, _, dt) in enumerate(trials) if k != reported]
    drop = [(t, compose(planned.X_WH, np.asarray(X))) for t, X in record]
    return HangExecution(result.hangs, result.collision_at_start, result.on_ground,
                         compose(planned.X_WH, np.asarray(result.X_WM_end)),
                         result.in_place(world.physics), result.fall_m, drop,
                         time.perf_counter() - t0, mode, sim, replans, sol)


def _dropped_pose(planned: HangPlan, executed: HangExecution) -> HangSolution:
    """The pose the execution reports (the plan's, or a closed loop's later one)."""
    return executed.solution if executed.solution is not None else planned.solution


def write_hang_playback_page(planned: HangPlan, executed: HangExecution, path: Path) -> None:
    mug, hook, _, _ = hang_parts(planned.scene)
    X_WM = compose(planned.X_WH, _dropped_pose(planned, executed).pose)
    write_hang_playback(mug, hook, planned.X_WH, planned.X_WM_start, X_WM, executed.drop,
                        Path(path))


def write_hang_still(planned: HangPlan, executed: HangExecution, path: Path) -> None:
    """The found pose and the pose after the drop, in the hook frame, as a PNG."""
    mug, hook, _, _ = hang_parts(planned.scene)
    X_HW = inverse_pose(planned.X_WH)
    outcome = ("hangs" if executed.hung else "falls") + (" in place" if executed.in_place
                                                         else "")
    write_hang_picture(mug, hook, _dropped_pose(planned, executed).pose,
                       compose(X_HW, executed.X_WM_end),
                       Path(path), title=f"{planned.scene.name}: found pose (light), after "
                       f"the drop in {executed.simulator} (solid): the mug {outcome}")


def write_hang_scene_picture(scene: Scene, path: Path) -> None:
    """The scene as it starts, the mug where it stands and the hook, as a PNG."""
    mug, hook, mug_pose, hook_pose = hang_parts(scene)
    X_HM = compose(inverse_pose(table_pose(*hook_pose)), table_pose(*mug_pose))
    write_hang_picture(mug, hook, None, X_HM, Path(path),
                       title=f"{scene.name}: the mug where it stands and the hook")


def _r(v: np.ndarray) -> list[float]:
    return [round(float(x), 6) for x in v]


def solve_hang(task: HangTask, out: Path, model: str | Path | None = None, *, seed: int = 0,
               restarts: int | None = None, settings: HangSettings | None = None,
               mode: str = "closed_loop", check: str | Path | None = CHECK,
               sim: str = "pybullet") -> dict:
    """Plan, drop in simulator ``sim`` (``mode``: closed loop goes on searching while the
    mug falls), write ``out/result.json``, ``out/playback.html`` and ``out/hang.png``;
    returns the result.
    Its pose, H_hang, restarts and evaluations are those of the pose dropped last;
    ``check`` as :func:`plan_hang`'s, in open loop only: the closed loop's drops are its
    check, and the network's refusals would spend the restarts it drops from
    (docs/experiments.md#hang-check)."""
    t0 = time.perf_counter()
    check = check if mode == "open_loop" else None
    planned = plan_hang(task, model, seed=seed, restarts=restarts, settings=settings,
                        check=check)
    executed = execute_hang(planned, mode, sim)
    sol = _dropped_pose(planned, executed)
    doc = {"scene": task.scene.name, "status": "solved" if sol.feasible else "no_solution",
           "goal": "hang", "model": planned.model,
           "check": None if check is None else str(check),
           "check_h": None if sol.check_h is None else round(sol.check_h, 5),
           "thread_mm": None if sol.thread_mm is None else round(sol.thread_mm, 3),
           "plan_seconds": round(sol.seconds, 2), "restarts": sol.restarts,
           "evaluations": sol.evaluations, "h_hang": round(sol.h_hang, 5),
           "h_coll_cm3": round(sol.h_coll_cm3, 6), "pose": _r(compose(planned.X_WH, sol.pose)),
           "pose_in_hook_frame": _r(sol.pose),
           "execution": {"simulator": executed.simulator, "mode": executed.mode,
                         "replans": executed.replans, "hung": executed.hung,
                         "collision_at_start": executed.collision_at_start,
                         "on_ground": executed.on_ground, "in_place": executed.in_place,
                         "fall_m": round(executed.fall_m, 4),
                         "final_pose": _r(executed.X_WM_end)},
           "seconds": round(time.perf_counter() - t0, 2), "playback": "playback.html",
           "picture": "hang.png"}
    out.mkdir(parents=True, exist_ok=True)
    write_hang_playback_page(planned, executed, out / "playback.html")
    write_hang_still(planned, executed, out / "hang.png")
    write_atomically(out / "result.json", lambda p: p.write_text(json.dumps(doc, indent=1)))
    return doc


class HangPlanner:
    """The planner of a :class:`~robotplan.scene.task.HangTask`, as the facade
    (:mod:`robotplan.api`) calls it: each method is one of this module's functions."""

    def plan(self, task: HangTask, model: str | Path | None = None, **options) -> HangPlan:
        """:func:`plan_hang` (``options``: ``seed``, ``settings``, ``restarts``, ``check``)."""
        return plan_hang(task, model, **options)

    def execute(self, planned: HangPlan, mode: str = "closed_loop", sim: str = "pybullet",
                **_ignored) -> HangExecution:
        """:func:`execute_hang` in simulator ``sim``; the facade's options of a push execution
        (a perturbed world, closed-loop settings, ``quiet``) do not apply to a drop and are
        ignored."""
        return execute_hang(planned, mode, sim)

    def playback(self, planned: HangPlan, executed: HangExecution, path: str | Path) -> None:
        """:func:`write_hang_playback_page`: the carry to the found pose and the drop."""
        write_hang_playback_page(planned, executed, Path(path))

    def solve(self, task: HangTask, out: str | Path, model: str | Path | None = None, *,
              mode: str = "closed_loop", quiet: bool = False, **options) -> dict:
        """:func:`solve_hang` into ``out`` (``options``: ``seed``, ``restarts``, ``settings``,
        ``check``, ``sim``); a hang solve prints nothing, whatever ``quiet``."""
        return solve_hang(task, Path(out), model, mode=mode, **options)
