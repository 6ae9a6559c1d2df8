"""Feedback on the acting actor's motion between re-plans (:mod:`robotplan.pushing.execution.
closed_loop`): the acting free pusher or arm steered sideways against the object's turn
(``steer_gain``)."""

from __future__ import annotations

import numpy as np

from robotplan.execution.scene_world import SceneWorld
from robotplan.geometry.transforms import wrap_angle
from robotplan.pushing.execution.loop_settings import LoopSettings

__all__ = ["steer_actor", "steer_pusher"]


def steer_pusher(target: np.ndarray, start: np.ndarray, planned_pose: np.ndarray,
                 seen_pose: np.ndarray, gain: float, limit: float) -> np.ndarray:
    """A free pusher's step target ``(x, y)`` moved sideways to its planned step from
    ``start``: by how far the object's centre is off the plan sideways, so that the contact
    keeps its planned offset from the centre, plus ``gain`` × the object's yaw off the plan
    (at most ``limit`` m in all), so that the push turns the object back.

    A push along d at a contact left of the centre turns the object clockwise (the torque
    r × F = −r_⊥ |F|), so a yaw error e > 0 (turned counter-clockwise too far) moves the
    contact to the left, by ``gain · e``."""
    step = np.asarray(target, dtype=float) - np.asarray(start, dtype=float)
    length = float(np.hypot(*step))
    if length < 1e-6:
        return np.asarray(target, dtype=float)
    left = np.array([-step[1], step[0]]) / length
    yaw_off = wrap_angle(float(seen_pose[2] - planned_pose[2]))
    side = float((seen_pose[:2] - planned_pose[:2]) @ left) + gain * yaw_off
    return np.asarray(target, dtype=float) + float(np.clip(side, -limit, limit)) * left


def steer_actor(world: SceneWorld, loop, target: dict[str, np.ndarray],
                seen_pose: np.ndarray, settings: LoopSettings) -> None:
    """In push steps, steer the acting actor's step ``target`` (actor → state, in place) by
    :func:`steer_pusher`: a free pusher's position; an arm's joints, moved so that its tip
    shifts sideways to the object's planned step as a free pusher would (``Arm.steered``).
    ``loop``: the closed loop's state (its plan, the step ``t``, steps per phase ``T`` and
    the free pusher's planned positions ``drive``)."""
    phase = loop.plan.skeleton.phases[loop.t // loop.T]
    if phase.mode != "push":
        return
    planned = loop.plan.q_obj
    gain, limit = settings.steer_gain, settings.steer_limit
    if world.pusher is not None:
        name = world.pusher.name
        target[name] = steer_pusher(target[name], loop.drive[name][loop.t], planned[loop.t],
                                    seen_pose, gain, limit)
        return
    actor = phase.actor
    if actor in world.arms:
        ahead = planned[loop.t + 1, :2]
        shift = steer_pusher(ahead, planned[loop.t, :2], planned[loop.t], seen_pose, gain,
                             limit) - ahead
        target[actor] = world.arms[actor].steered(target[actor], np.append(shift, 0.0))
