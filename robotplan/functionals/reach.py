"""How far an arm's tip reaches at push height, measured by inverse kinematics.

A robot folder's ``reach`` (``robot.yaml``) lets the skeleton search drop pushes an arm can
never make before solving anything. It is measured, not guessed: along a few directions
from the base, the tip is walked outwards and inwards from a reachable radius in 1 cm steps
(each inverse-kinematics program started from the last answer), with the flange and the
check links held above the objects. The reach is the band every direction reaches.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robotplan.functionals.kinematics import arm_kinematics, track_tip_path
from robotplan.scene.schema import RobotSpec

__all__ = ["ReachSettings", "measure_reach"]


@dataclass(frozen=True)
class ReachSettings:
    """Where the tip must get to: its centre at ``tip_height`` (m) above the table, the
    flange above ``flange_min`` and the other check links above ``link_min`` (the
    planner's defaults for 6 cm objects); ``tolerance`` (m) is a hit."""

    tip_height: float = 0.03
    flange_min: float = 0.07
    link_min: float = 0.12
    tolerance: float = 0.002
    directions: tuple[float, ...] = (-0.8, -0.4, 0.0, 0.4, 0.8)  # rad about the base's x
    step: float = 0.01
    farthest: float = 1.6


def _band(kin, direction: float, settings: ReachSettings) -> tuple[float, float] | None:
    """``(nearest, farthest)`` radius the tip reaches along ``direction``, or None."""
    u = np.array([np.cos(direction), np.sin(direction)])
    radii = np.arange(settings.step * 5, settings.farthest + 1e-9, settings.step)

    def reached(r: float, q: np.ndarray) -> tuple[bool, np.ndarray]:
        target = np.array([[*(r * u), settings.tip_height]])
        q = track_tip_path(kin, target, q, settings.flange_min, settings.link_min)[0]
        return bool(np.linalg.norm(kin.tip(q) - target[0]) < settings.tolerance), q

    start = None
    for r in radii[len(radii) // 4::3]:  # a reachable radius to walk from
        ok, q_start = reached(float(r), kin.q0)
        if ok:
            start = float(r)
            break
    if start is None:
        return None
    ends = []
    for sign in (1.0, -1.0):
        r, q, last = start, q_start, start
        while settings.step * 5 <= r + sign * settings.step <= settings.farthest:
            r += sign * settings.step
            ok, q_next = reached(r, q)
            if not ok:
                break
            q, last = q_next, r
        ends.append(last)
    return ends[1], ends[0]


def measure_reach(model: str, settings: ReachSettings = ReachSettings()
                  ) -> tuple[float, float]:
    """The horizontal band ``(lo, hi)`` (m from the base axis) in which the tip of robot
    folder ``model`` reaches push height in every direction of ``settings``, rounded
    inwards to centimetres; NaNs when some direction is never reached."""
    spec = RobotSpec(name="reach", model=model, base=(0.0, 0.0, 0.0, 0.0), tip_radius=0.03)
    kin = arm_kinematics(spec)
    bands = [_band(kin, d, settings) for d in settings.directions]
    if any(b is None for b in bands):
        return (float("nan"), float("nan"))
    lo, hi = max(b[0] for b in bands), min(b[1] for b in bands)
    return float(np.ceil(lo * 100 - 1e-6) / 100), float(np.floor(hi * 100 + 1e-6) / 100)
