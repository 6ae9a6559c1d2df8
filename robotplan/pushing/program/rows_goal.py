"""The goals of a push program as rows of the table (``GOAL_ROWS``): H_g (eq. 8) of a
region, the pose error of a target pose, the touch of an arm (H_PoC at the end)."""

from __future__ import annotations

import numpy as np
import torch

from robotplan.functionals import ContactPoint, GoalRegion
from robotplan.functionals.goal import PoseError
from robotplan.pushing.program.settings import ProgramSettings
from robotplan.scene.bodies import Body

__all__ = ["GOAL_ROWS", "region_goal"]


def region_goal(body: Body, region: Body, settings: ProgramSettings) -> GoalRegion:
    """H_g of ``body`` in the goal ``region`` as the program's goal row has it: the region
    shrunk by ``goal.inset`` (at most a third of the room the body has at its centre), so
    that a plan ends deeper inside and tolerates execution error; the row bounds H_g over
    the body's area by ``goal.tol``."""
    origin = torch.zeros(1, 2, dtype=torch.float64)
    extent = np.ptp(body.shape.outline(), axis=0).max() / 2
    room = -float(region.shape.sdf(origin)[0]) - extent
    inset = min(settings.row("goal").inset, max(0.0, room / 3))
    return GoalRegion(body, region, a=settings.row("goal").a, inset=inset)


class AreaShare:
    """A functional ``H`` divided by ``area``: H_g as the share of the object's area."""

    def __init__(self, H, area: float) -> None:
        self.H, self.per_area = H, 1.0 / area

    def __call__(self, X: torch.Tensor) -> torch.Tensor:
        return self.H(X) * self.per_area

    def jacobians(self, X: torch.Tensor):
        r, (J,) = self.H.jacobians(X)
        return r * self.per_area, (J * self.per_area,)


def _region_goal(ctx) -> None:
    """H_g (eq. 8) of the goal's object at the last state as a share of its area."""
    program = ctx.program
    if program.region is None:
        return
    body = program.goal_body
    H = AreaShare(region_goal(body, program.region, ctx.settings), body.area)
    ctx.constrain(H, [ctx.body("goal")[ctx.steps]], 1)


def _pose_goal(ctx) -> None:
    """The object's own footprint at the target pose: each component of the pose error
    within ``tolerance`` (what moves ``tol`` of its area off target, over √3)."""
    program = ctx.program
    outline = program.goal_body.shape.outline()
    H = PoseError(outline, tuple(program.scene.goal.pose))
    tolerance = H.tolerance(outline, ctx.constants.tol) / np.sqrt(3)
    ctx.constrain(H, [ctx.body("goal")[ctx.steps]], 3, tolerance=tolerance)


def _touch_goal(ctx) -> None:
    """The touching tip is the last phase's actor; it ends on the object (H_PoC)."""
    program, t = ctx.program, ctx.steps
    H = ContactPoint(program.obj, program.scene.bodies[program.task.touch_actor])
    ctx.constrain(H, [ctx.body("object")[t], ctx.body("actor")[t], ctx.body("touch")], 2)


GOAL_ROWS = {"goal": _region_goal, "H_pose": _pose_goal, "H_touch": _touch_goal}
