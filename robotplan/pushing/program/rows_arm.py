"""Programs over joints (paper app. E) as rows of the table (``ARM_ROWS``): the push
program with robot arms as the actors.

Each arm's joint angles ``q_<robot> (N+1, dof)`` are decision variables; the actor's
positions become the tip of the arm that acts in each step (``tip_coupling``:
FK_xy(q_t) = x_t, :class:`~robotplan.functionals.kinematics.TipCoupling`), so H_F, H_coll,
H_PoC and the goal see the tip as they see a free pusher. Per arm: joint limits, its home
pose at state 0, joint-velocity limits (reach steps run ``arm_joints.reach_slowdown``
times slower, so they may move that much more), the squared joint steps as a cost; its tip
at push height while it pushes (and at a touch goal), above the table while it reaches,
``idle_lift.lift`` above the objects while idle; the flange above the objects' tops and the
other check links above ``links.link_min``. With two arms, their check points
``arm_separation.gap`` apart (smooth minimum)."""

from __future__ import annotations

import numpy as np

from robotplan.functionals.kinematics import (
    ArmSeparation,
    CheckPointHeights,
    TipCoupling,
    TipHeight,
    track_tip_path,
)
from robotplan.scene import Scene

__all__ = ["ARM_ROWS", "joint_guess", "objects_top"]


def objects_top(scene: Scene) -> float:
    """The height (m) of the tallest object or obstacle."""
    return max((o.height for o in (*scene.objects, *scene.obstacles)), default=0.0)


def _kin(ctx):
    return ctx.program.kin[ctx.arm]


def _joint_limits(ctx) -> None:
    kin = _kin(ctx)
    ctx.box(ctx.body("joints"), lower=np.array(kin.model.joint_lower),
            upper=np.array(kin.model.joint_upper))


def _velocity(ctx) -> None:
    """|q_t − q_{t−1}| ≤ ``velocity``: the joints' limits over ``step_seconds``, times
    ``reach_slowdown`` in reach steps."""
    Q, kin = ctx.body("joints"), _kin(ctx)
    dof, steps = Q.shape[1], ctx.program.steps
    v = np.array(kin.model.velocity_limits) * ctx.constants.step_seconds
    for t in ctx.steps:
        slow = 1.0 if steps.mode(t) == "push" else ctx.constants.reach_slowdown
        ctx.linear(np.hstack((np.eye(dof), -np.eye(dof))), np.concatenate((Q[t], Q[t - 1])),
                   velocity=v * slow)


def _motion(ctx) -> None:
    """``weight`` · |q_t − q_{t−1}|² per step."""
    Q, w = ctx.body("joints"), ctx.constants.weight
    dof = Q.shape[1]
    for t in ctx.steps:
        ctx.quadratic(2 * w * np.block([[np.eye(dof), -np.eye(dof)], [-np.eye(dof), np.eye(dof)]]),
                      np.concatenate((Q[t], Q[t - 1])))


def _tip_coupling(ctx) -> None:
    k = ctx.steps
    ctx.constrain(TipCoupling(_kin(ctx)), [ctx.body("joints")[k], ctx.body("actor")[k]], 2)


def _tip_height(ctx, **quantities) -> None:
    ctx.constrain(TipHeight(_kin(ctx)), [ctx.body("joints")[ctx.steps]], 1, **quantities)


def _idle_lift(ctx) -> None:
    """The idle tip's centre ``height``: ``lift`` above the objects' tops, plus its radius."""
    top = objects_top(ctx.program.scene)
    _tip_height(ctx, height=top + ctx.constants.lift + ctx.program.tip_radius)


def _links(ctx) -> None:
    """Check points' ``heights``: the flange ``flange_clearance`` above the objects' tops,
    the links between it and the tip ``link_min``."""
    kin, c = _kin(ctx), ctx.constants
    heights = np.array([objects_top(ctx.program.scene) + c.flange_clearance]
                       + [c.link_min] * (len(kin._frames) - 2))
    ctx.constrain(CheckPointHeights(kin), [ctx.body("joints")[ctx.steps]], len(heights),
                  heights=heights[None])


def _tip_reach(ctx) -> None:
    """|Δx| per step and axis of the acting tip ≤ ``limit``: ``tip_reach.step`` while
    reaching, ``step_limits.step`` while pushing, in both stages: without it the learned
    stage can sweep the tip across the box's face between two planned states."""
    Q2, steps, s = ctx.body("actor"), ctx.program.steps, ctx.settings
    D = np.hstack((np.eye(2), -np.eye(2)))
    for t in ctx.steps:
        lim = (s.row("step_limits").step if steps.mode(t) == "push" else ctx.constants.step)
        ctx.linear(D, np.concatenate((Q2[t], Q2[t - 1])), limit=np.full(2, lim))


def _separation(ctx) -> None:
    """The two arms' check points (tips included) at least ``gap`` apart."""
    joints, kin = ctx.program.variables.joints, ctx.program.kin
    if len(joints) != 2:
        return
    a, b = joints
    ctx.constrain(ArmSeparation(kin[a], kin[b]), [joints[a][ctx.steps], joints[b][ctx.steps]], 1)


ARM_ROWS = {
    "joint_limits": _joint_limits,
    "start_joints": lambda ctx: ctx.box(ctx.body("joints")[ctx.steps], home=_kin(ctx).q0),
    "arm_joints": _velocity,
    "joint_motion": _motion,
    "tip_coupling": _tip_coupling,
    "push_height": lambda ctx: _tip_height(ctx, radius=ctx.program.tip_radius),
    "above_table": lambda ctx: _tip_height(ctx, radius=ctx.program.tip_radius),
    "idle_lift": _idle_lift,
    "links": _links,
    "tip_reach": _tip_reach,
    "arm_separation": _separation,
}


def joint_guess(program) -> dict[str, np.ndarray]:
    """Inverse kinematics along the guessed tip path of each arm: the planar guess at
    push height in its push states, descending while it reaches; idle, back home."""
    s, steps, T, N = program.settings, program.steps, program.T, program.N
    top, r = objects_top(program.scene), program.tip_radius
    high = top + s.row("idle_lift").lift + r + 0.03
    out = {}
    for name, kin in program.kin.items():
        low = set(steps.named("arm_push", name).tolist())
        targets = np.full((N + 1, 3), np.nan)
        for t in range(1, N + 1):
            if steps.actor(t) != name:
                targets[t] = kin.tip(kin.q0)  # idle: the home pose's tip
                continue
            xy = program.guess["q_pusher"][t]
            if t in low:
                targets[t] = (*xy, r)
            else:  # reaching: high first, down to push height at the phase's end
                u = ((t - 1) % T + 1) / T
                targets[t] = (*xy, r + (high - r) * (1.0 - u**3))
        links = s.row("links")
        out[name] = track_tip_path(kin, targets, kin.q0, top + links.flange_clearance,
                                   links.link_min)
    return out
