"""The functionals of a push program as rows of the table (paper eq. 2): the start and
the table, H_F, H_coll, H_PoC, the quasi-static push and the costs (``PUSH_ROWS``; the
goals' rows: :mod:`robotplan.pushing.program.rows_goal`).

Each is ``row(ctx)`` for a :class:`~robotplan.pushing.program.builder.RowContext`: it takes its
variables by the row's ``bodies`` at the row's ``steps`` and names the quantities its
bounds use."""

from __future__ import annotations

from functools import partial

import numpy as np
import torch

from robotplan.functionals import Collision, ContactPoint
from robotplan.functionals.collision import (
    FixedCollision,
    SweptClearance,
    crossing_depth,
    face_contact_overlap,
)
from robotplan.functionals.sticking import (
    PushingDirection,
    PushLever,
    QuasiStaticPush,
    StickingContact,
    centroid,
    turning_radius,
)
from robotplan.geometry.transforms import carry_with_body
from robotplan.program.bridge import stepwise
from robotplan.pushing.program.rows_dynamics import add_dynamics

__all__ = ["PUSH_ROWS", "clear_overlap", "cone_bounds", "hold", "motion_cost", "swept_shortfall"]


def clear_overlap(ctx) -> float:
    """H_coll of the actor ``H_coll.clearance`` off a face (m²): free space."""
    coll = ctx.settings.row("H_coll")
    return face_contact_overlap(ctx.program.pusher, coll.a, -coll.clearance)


def cone_bounds(turn: bool) -> np.ndarray:
    """The upper bounds ``(1, m)`` of QuasiStaticPush's rows: [turn = 0,] cone edges ≥ 0."""
    return np.array([[0.0, np.inf, np.inf]]) if turn else np.full((1, 2), np.inf)


def hold(ctx, Q: np.ndarray) -> None:
    """Pose row t of ``Q`` equals row t − 1 at each of the row's states t."""
    d = Q.shape[1]
    for t in ctx.steps:
        ctx.linear(np.hstack((np.eye(d), -np.eye(d))), np.concatenate((Q[t], Q[t - 1])))


def motion_cost(ctx, Q: np.ndarray) -> None:
    """``object_motion.weight`` · Σ_t |Δq_t|² of poses ``Q`` (yaw in
    ``object_motion.turn_length`` m)."""
    motion = ctx.settings.row("object_motion")
    scale = np.array([1.0, 1.0, motion.turn_length])
    D = np.hstack((np.diag(scale), -np.diag(scale)))
    for t in ctx.steps:
        ctx.quadratic(2 * motion.weight * D.T @ D, np.concatenate((Q[t], Q[t - 1])))


def quasi_static_rows(ctx, H: QuasiStaticPush, blocks: list[np.ndarray]) -> None:
    """``H``'s rows on ``blocks``; bounds' quantity ``cone`` (:func:`cone_bounds`)."""
    ctx.constrain(H, blocks, 3 if H.turn else 2, cone=cone_bounds(H.turn))


def _start(ctx) -> None:
    """State 0 of the object and the actor is the scene's (quantity ``start``)."""
    program = ctx.program
    for name, body in (("object", program.obj), ("actor", program.pusher)):
        Q = ctx.body(name)
        ctx.box(Q[ctx.steps], start=np.array(body.pose[:Q.shape[1]]))


def workspace(ctx, names: tuple[str, ...]) -> None:
    """Every point ``(x, y)`` of the bodies ``names`` on the table (``low``, ``high``)."""
    x0, x1, y0, y1 = ctx.program.scene.workspace.bounds
    for name in names:
        Q = ctx.body(name)
        if Q.size:
            ctx.box(Q[:, :2], low=np.array([x0, y0]), high=np.array([x1, y1]))


def _hold_object(ctx) -> None:
    """A reach phase moves the actor without touching (H_coll keeps it off), so the
    object stays where it is. Without this, the cost on H_F alone lets the optimiser
    drift the object a few mm per step."""
    hold(ctx, ctx.body("object"))


def _dynamics(ctx) -> None:
    """H_F (eq. 5) of the object pushed by the actor in every step."""
    program = ctx.program
    program.dynamics = add_dynamics(ctx, program.model, (program.obj, ctx.body("object")),
                                    (program.pusher, ctx.body("actor")),
                                    program.guess["q_obj"])


def _quasi_static(ctx, turn: bool) -> None:
    """QuasiStaticPush rows in every push step: the friction cone, and with ``turn`` the
    limit surface's turning rate."""
    program, k = ctx.program, ctx.steps
    push = ctx.settings.row("quasi_static")
    if push.friction <= 0:
        return
    radius = turning_radius(program.obj.shape, push.turn_gain)
    H = QuasiStaticPush(centroid(program.obj.shape.outline()), radius, push.friction,
                        turn=turn)
    Q1 = ctx.body("object")
    quasi_static_rows(ctx, H, [Q1[k - 1], Q1[k], ctx.body("actor")[k], ctx.body("contact")])


def _sticking(ctx) -> None:
    """The kinematic stand-in for H_F: the contact point sticks to the object between
    consecutive push steps of a phase."""
    push, P, Q1 = ctx.program.steps.named("push"), ctx.body("contact"), ctx.body("object")
    i = ctx.steps
    ctx.constrain(StickingContact(), [Q1[push[i - 1]], P[i - 1], Q1[push[i]], P[i]], 2)


def _pushing(ctx) -> None:
    """In push steps the actor moves into the contact point."""
    Q2, k = ctx.body("actor"), ctx.steps
    ctx.constrain(PushingDirection(), [Q2[k - 1], Q2[k], ctx.body("contact")], 1)


def _step_limits(ctx, body: str, columns: slice) -> None:
    """|Q[t] − Q[t − 1]| within the row's bounds per column, t in the row's states."""
    Q = ctx.body(body)[:, columns]
    d, n, N1 = Q.shape[1], len(ctx.steps), Q.shape[0]
    D = np.zeros((d * n, d * N1))
    for i, t in enumerate(ctx.steps):
        for j in range(d):
            D[d * i + j, d * t + j], D[d * i + j, d * (t - 1) + j] = 1.0, -1.0
    ctx.linear(D, Q.ravel())


def _collision(ctx) -> None:
    """H_coll in every step; ``limit``: a pressed-in face contact in push steps (and at a
    touch goal's end), :func:`clear_overlap` elsewhere (the pusher follows straight lines
    between the planned points; brushing the object on the way turns it)."""
    program, coll = ctx.program, ctx.constants
    touch = max(coll.contact_area,
                face_contact_overlap(program.pusher, coll.a, coll.contact_depth))
    limit = np.full(program.N, clear_overlap(ctx))
    limit[program.steps.named("push") - 1] = touch
    if program.task.goal == "touch":
        limit[-1] = touch  # the touch goal's last state is a contact, not a reach
    Q1, Q2 = ctx.body("object"), ctx.body("actor")
    ctx.constrain(Collision(program.obj, program.pusher, a=coll.a), [Q1[1:], Q2[1:]], 1,
                  limit=limit)


def _swept(ctx) -> None:
    """Along each free move of a free pusher, its gap to the object at ``samples`` points
    (and after the solve at points ``check_spacing`` apart: :func:`swept_shortfall`), at
    most ``depth`` (m) into it: ``tolerance``, or for the move from the scene's start as
    deep as the pusher starts in the object (a re-plan observes it pressed in; no plan
    changes where it starts)."""
    program, free, samples = ctx.program, ctx.steps, ctx.constants.samples
    if program.task.arms or samples <= 0:
        return
    depth = np.full(len(free), float(ctx.constants.tolerance))
    start_depth = 0.0
    if len(free) and free[0] == 1:
        start = torch.as_tensor(program.pusher.pose[:2], dtype=torch.float64)[None, None]
        pose = torch.as_tensor(program.obj.pose, dtype=torch.float64)[None]
        start_depth = program.pusher.shape.radius - float(program.obj.sdf(start, pose)[0, 0])
        depth[0] = max(depth[0], start_depth)
    program.swept_check = (free, ctx.spec.scale, start_depth)
    # the object holds still in these steps (hold_object.active): its pose at t
    Q1, Q2 = ctx.body("object"), ctx.body("actor")
    ctx.constrain(SweptClearance(program.obj, program.pusher, samples),
                  [Q1[free], Q2[free - 1], Q2[free]], samples, depth=depth)


def swept_shortfall(program, q_obj: np.ndarray, q_pusher: np.ndarray) -> float:
    """How far (in the swept row's scaled units) the plan's moves cross the object, at
    points ``swept.check_spacing`` apart: free moves beyond ``swept.check_depth`` (the
    row's samples miss it in long moves), push steps' moves seen from the object beyond
    ``swept.push_check_depth`` (rows hold at their end states only). 0 without the row."""
    swept = program.settings.row("swept")
    if program.swept_check is None or swept.check_spacing is None:
        return 0.0
    free, scale, start_depth = program.swept_check
    q1, q2 = torch.from_numpy(q_obj), torch.from_numpy(q_pusher[:, :2])
    depth = partial(crossing_depth, program.obj, program.pusher, spacing=swept.check_spacing,
                    samples=swept.samples)
    from_start = len(free) > 0 and free[0] == 1
    rest = free[1:] if from_start else free
    beyond = depth(q1[rest], q2[rest - 1], q2[rest]) - swept.check_depth
    if from_start:  # the move from the start, as deep as the pusher starts in the object
        first = depth(q1[1:2], q2[:1], q2[1:2])
        beyond = max(beyond, first - max(swept.check_depth, start_depth))
    push = program.steps.named("push")
    if len(push):
        start = carry_with_body(q2[push - 1, None], q1[push - 1], q1[push])[:, 0]
        beyond = max(beyond, depth(q1[push], start, q2[push]) - swept.push_check_depth)
    return scale * max(0.0, beyond)


def _obstacles(ctx) -> None:
    """H_coll of the object (≤ ``overlap``) and of the actor (≤ ``clear``, free space)
    with every obstacle, in every step."""
    program, a = ctx.program, ctx.settings.row("H_coll").a
    Q1, Q2 = ctx.body("object"), ctx.body("actor")
    for obstacle in program.scene.obstacles:
        wall = program.scene.bodies[obstacle.name]
        ctx.constrain(FixedCollision(program.obj, wall, a), [Q1[1:]], 1, key="object",
                      name=f"H_coll_{obstacle.name}")
        ctx.constrain(FixedCollision(program.pusher, wall, a), [Q2[1:]], 1, key="actor",
                      name=f"H_coll_{obstacle.name}_pusher", clear=clear_overlap(ctx))


def _contact(ctx) -> None:
    """H_PoC (eq. 9) at the contact points of push steps."""
    program, k = ctx.program, ctx.steps
    ctx.constrain(ContactPoint(program.obj, program.pusher),
                  [ctx.body("object")[k], ctx.body("actor")[k], ctx.body("contact")], 2)


def _acceleration(ctx) -> None:
    """``actor`` · Σ|a_actor|² + ``contact`` · Σ|a_p|², a_t = q_{t+1} − 2 q_t + q_{t−1};
    the actor's with the prefix q_{−1} = q_0."""
    def accel_cost(Q: np.ndarray, weight: float, prefix: bool) -> None:
        n = Q.shape[0]
        if n < 2:
            return
        rows = []
        for t in range(0 if prefix else 1, n - 1):
            r = np.zeros(n)
            r[t + 1] += 1
            r[t] -= 2
            r[max(t - 1, 0)] += 1
            rows.append(r)
        D = np.kron(np.array(rows), np.eye(2))
        ctx.quadratic(2 * weight * D.T @ D, Q.ravel())

    accel_cost(ctx.body("actor")[ctx.steps], ctx.constants.actor, prefix=True)
    accel_cost(ctx.body("contact"), ctx.constants.contact, prefix=False)


def _lever(ctx) -> None:
    """``weight`` · Σ (lever arm in the row's unit)² over push steps (see PushLever)."""
    w, program, k = ctx.constants.weight, ctx.program, ctx.steps
    if w <= 0:
        return
    H = PushLever(centroid(program.obj.shape.outline()))
    fn, variables = stepwise(H, [ctx.body("object")[k], ctx.body("actor")[k],
                                 ctx.body("contact")], ctx.spec.scale)

    def total(x: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
        r, J = fn(x, jac)
        return np.array([w * r @ r]), None if J is None else (2 * w * r @ J)[None]

    ctx.cost(total, variables)


PUSH_ROWS = {
    "start": _start,
    "workspace": partial(workspace, names=("object", "actor", "contact")),
    "hold_object": _hold_object,
    "H_F": _dynamics,
    "friction_cone": lambda ctx: _quasi_static(ctx, ctx.constants.turn),
    "sticking": _sticking,
    "pushing": _pushing,
    "quasi_static": lambda ctx: _quasi_static(ctx, True),
    "object_motion": lambda ctx: motion_cost(ctx, ctx.body("object")),
    "step_limits": partial(_step_limits, body="actor", columns=slice(None)),
    "turn_limits": partial(_step_limits, body="object", columns=slice(2, None)),
    "H_coll": _collision,
    "swept": _swept,
    "H_coll_obstacles": _obstacles,
    "H_PoC": _contact,
    "acceleration": _acceleration,
    "lever": _lever,
}
