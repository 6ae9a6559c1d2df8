"""The closed loop's settings (:class:`LoopSettings`): when the executor re-plans and what it
does between re-plans, each with its reason (measurements: docs/experiments.md#closed-loop),
and their overlays per scene class in ``skeletons/loop.yaml``."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from functools import cache
from pathlib import Path

from robotplan.base.overlays import apply_overlays, parse_overrides, read_overlays
from robotplan.base.resources import skeletons_dir
from robotplan.scene.task import PushTask

__all__ = ["LOOP_CLASSES", "LoopSettings", "load_loop_overlays", "loop_settings_for",
           "parse_loop_overrides"]


@dataclass(frozen=True)
class LoopSettings:
    # m and rad of an object off the plan that trigger a re-plan mid-phase: only gross
    # departures, as the learned model's own error stays below them while a push goes on
    # (measured: docs/experiments.md#closed-loop)
    drift: float = 0.05
    drift_yaw: float = math.radians(20.0)
    phase_drift: float = 0.005  # the same at the end of a phase
    phase_drift_yaw: float = math.radians(2.0)
    goal_coverage: float = 0.995  # below this at the plan's end: plan afresh
    # the same for a pose goal: Push-T's success (0.95) and 1 % for what 1 mm of perception
    # error uncovers of a T; closing pushes above it left T-shapes lower as often as higher
    # (measured: docs/experiments.md#pose-closing)
    pose_coverage: float = 0.96
    touch_gap: float = 0.005  # m: a touch goal farther than this at the end: plan afresh
    # a free pusher's L-shape that departs again and again needs more than 8 re-plans to
    # reach its goal; arms and chains keep 8 (overlays) (measured: docs/experiments.md#replan-fits)
    max_replans: int = 16
    # off by default: searching afresh at once when a departure's re-anchored tail does not
    # plan finds slow plans that drift off again (measured: docs/experiments.md#closed-loop)
    fresh_after_miss: bool = False
    # at a phase's end, an object beyond drift / drift_yaw whose tail does not plan gets a
    # fresh search at once: the stale plan pushes where the object is not and drives it
    # further off (measured: docs/experiments.md#closed-loop)
    fresh_beyond_drift: bool = True
    # at the plan's end with the goal not met, the plan's last reach and push are tried
    # again from where the object is before a fresh search; off (pose goals): the fresh
    # search at once, where the redone push almost never solved
    # (measured: docs/experiments.md#side-by-side)
    redo_last_push: bool = True
    # at the plan's end with the goal not met, a re-plan that meets every constraint is taken
    # even when the learned dynamics call it implausible (residual beyond 10 mm): the loop
    # would otherwise stop short of the goal, and it re-plans again if pybullet departs
    # (measured: docs/experiments.md#last-resort)
    adopt_feasible_at_end: bool = True
    # the largest scaled constraint violation such a last-resort plan may have: three times
    # the bound of a solved plan, which the re-plans that left L-shapes short of the goal
    # missed only narrowly (measured: docs/experiments.md#last-resort)
    last_resort_violation: float = 0.03
    # a gross departure at a phase end whose re-plans do not solve also takes a last-resort
    # plan rather than the stale one, which pushes where the object is not
    # (measured: docs/experiments.md#last-resort)
    last_resort_beyond_drift: bool = True
    # off by default: with no re-plans left, an object beyond drift / drift_yaw of the plan
    # ends the execution where it is, rather than the stale plan pushing where the object
    # is not (measured: docs/experiments.md#close-fits)
    stop_when_lost: bool = False
    # m of sideways offset of the acting pusher or arm tip per rad of the object's yaw off
    # the plan in push steps and the largest offset (steer_pusher); 0, off: for free pushers
    # no gain helped beyond the scatter between scenes (measured:
    # docs/experiments.md#closed-loop); arms steer (the `arms` overlay)
    steer_gain: float = 0.0
    steer_limit: float = 0.03
    # s after which a re-plan starts no further tier or program, drops those running in the
    # search's processes and answers with the best it has (none: the loop goes on with its
    # plan), 0.5 s before the 5 s a re-plan may take at most: a free pusher's re-plans take a
    # fraction of a second, the few past 5 s ended unsolved (measured:
    # docs/experiments.md#replan-deadline); none for arms and chains (`.inf`), whose one
    # program takes longer
    replan_deadline: float = 4.5

    def goal_met(self, task: PushTask, coverage: float | None, gap: float | None) -> bool:
        """Whether an outcome meets the task's goal: a touch goal's ``gap`` (m) within
        ``touch_gap``, else the goal's ``coverage`` at least ``goal_coverage`` (a region)
        or ``pose_coverage`` (a pose)."""
        if task.touch_actor is not None:
            return gap is not None and gap <= self.touch_gap
        bound = self.pose_coverage if task.goal == "pose" else self.goal_coverage
        return coverage is not None and coverage >= bound


LOOP_CLASSES = ("arms", "chains", "pose")
"""Scene classes with their own closed-loop settings: ``arms``, scenes pushed by robot arms;
``chains``, scenes in which the pusher pushes one object into another; ``pose``, pose
goals."""


@cache
def load_loop_overlays(path: Path | None = None) -> dict[str, dict]:
    """The overlays of ``skeletons/loop.yaml``, checked against :class:`LoopSettings`."""
    return read_overlays(path or skeletons_dir() / "loop.yaml", LoopSettings(), LOOP_CLASSES,
                         "closed-loop setting")


def loop_settings_for(task: PushTask, base: LoopSettings | None = None,
                      overrides: Mapping[str, object] | None = None) -> LoopSettings:
    """``base`` (default :class:`LoopSettings`) with the overlays of the classes ``task``
    belongs to (:attr:`~robotplan.scene.task.PushTask.classes`), then ``overrides`` (a
    user's settings win over the task class's)."""
    classes = tuple(c for c in task.classes if c in LOOP_CLASSES)
    settings = apply_overlays(base or LoopSettings(), load_loop_overlays(), classes)
    return replace(settings, **overrides) if overrides else settings


def parse_loop_overrides(items: Sequence[str]) -> dict[str, object]:
    """``NAME=VALUE`` items (the CLI's ``--loop``) as :class:`LoopSettings` fields with
    values of their types: booleans as true/false (on/off, yes/no, 1/0), numbers as written.
    Raises ValueError naming the item that is not a setting or not of its type."""
    return parse_overrides(LoopSettings(), items, "closed-loop setting")
