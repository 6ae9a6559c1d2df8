"""Pushing through another object (paper Fig. 9, appendix C) as rows of the table
(``CHAIN_ROWS``): the actor may touch only the pushed object, which pushes the chained one
in the skeleton's chained phases. Both pairs get the functionals of a single push, the
second pair with the object in the actor's role: the chained object holds still outside its
push steps; H_coll(object, chained) at most a pressed-in face contact, H_coll(actor,
chained) and the swept clearance at the free-space level, H_coll with the obstacles as for
the object; H_PoC at the chain's contact points; kinematic stage: the contact point sticks
to both objects and the chained object moves as a quasi-static push
(QuasiStaticObjectPush); learned stage: H_F(chained | object), the learned model with the
object's SDF as φ2, with the cone the single push keeps."""

from __future__ import annotations

from functools import partial

import numpy as np

from robotplan.functionals import Collision, ContactPoint
from robotplan.functionals.collision import FixedCollision, SweptClearance
from robotplan.functionals.sticking import QuasiStaticObjectPush, StickingContact, turning_radius
from robotplan.pushing.program.rows_dynamics import add_dynamics
from robotplan.pushing.program.rows_push import (
    clear_overlap,
    hold,
    motion_cost,
    quasi_static_rows,
    workspace,
)

__all__ = ["CHAIN_ROWS"]


def _start(ctx) -> None:
    """State 0 of the chained object is the scene's (quantity ``start``)."""
    ctx.box(ctx.body("chained")[ctx.steps], start=np.array(ctx.program.target.pose, dtype=float))


def _objects_collide(ctx) -> None:
    """H_coll(object, chained); ``touch``: a face contact pressed in by
    ``H_coll.contact_depth``."""
    program, coll = ctx.program, ctx.settings.row("H_coll")
    obj, target = program.obj, program.target
    face = min(np.ptp(b.shape.outline(), axis=0).min() for b in (obj, target))
    touch = face * (1.0 / coll.a + coll.contact_depth)
    ctx.constrain(Collision(obj, target, a=coll.a),
                  [ctx.body("object")[1:], ctx.body("chained")[1:]], 1, touch=touch)


def _actor_keeps_off(ctx) -> None:
    """H_coll(chained, actor) at the free-space level ``clear``."""
    program, a = ctx.program, ctx.settings.row("H_coll").a
    ctx.constrain(Collision(program.target, program.pusher, a=a),
                  [ctx.body("chained")[1:], ctx.body("actor")[1:]], 1, clear=clear_overlap(ctx))


def _swept(ctx) -> None:
    """The actor's free moves clear of the chained object (the swept row's samples)."""
    program, free = ctx.program, ctx.steps
    samples = ctx.settings.row("swept").samples
    if samples <= 0:
        return
    Q3, Q2 = ctx.body("chained"), ctx.body("actor")
    ctx.constrain(SweptClearance(program.target, program.pusher, samples),
                  [Q3[free], Q2[free - 1], Q2[free]], samples)


def _obstacles(ctx) -> None:
    program, a = ctx.program, ctx.settings.row("H_coll").a
    for obstacle in program.scene.obstacles:
        wall = program.scene.bodies[obstacle.name]
        ctx.constrain(FixedCollision(program.target, wall, a), [ctx.body("chained")[1:]], 1,
                      name=f"H_coll_{obstacle.name}_chain")


def _contact(ctx) -> None:
    """H_PoC(object, chained) at the chain's contact points."""
    program, k = ctx.program, ctx.steps
    ctx.constrain(ContactPoint(program.obj, program.target),
                  [ctx.body("object")[k], ctx.body("chained")[k], ctx.body("chain_contact")], 2)


def _sticking(ctx) -> None:
    """The chain's contact point sticks to both objects between consecutive steps."""
    chain, i, P3 = ctx.program.steps.named("chain_push"), ctx.steps, ctx.body("chain_contact")
    a, b = chain[i - 1], chain[i]
    for Q in (ctx.body("object"), ctx.body("chained")):
        ctx.constrain(StickingContact(), [Q[a], P3[i - 1], Q[b], P3[i]], 2)


def _object_push(ctx, turn: bool) -> None:
    """QuasiStaticObjectPush rows of the chained object at its contact points (the
    learned stage's cone only with a friction > 0, as the single push's)."""
    program, k = ctx.program, ctx.steps
    push = ctx.settings.row("quasi_static")
    if push.friction <= 0 and ctx.spec.stage == "chain_learned":
        return
    radius = turning_radius(program.target.shape, push.turn_gain)
    H = QuasiStaticObjectPush(program.target, radius, push.friction, turn=turn)
    Q3 = ctx.body("chained")
    quasi_static_rows(ctx, H, [Q3[k - 1], Q3[k], ctx.body("chain_contact")])


def _dynamics(ctx) -> None:
    """H_F (eq. 5) of the chained object pushed by the object."""
    program = ctx.program
    program.chain_dynamics = add_dynamics(
        ctx, program.model, (program.target, ctx.body("chained")),
        (program.obj, ctx.body("object")), program.guess["q_chain"])


CHAIN_ROWS = {
    "start_chained": _start,
    "workspace_chain": partial(workspace, names=("chained", "chain_contact")),
    "hold_chained": lambda ctx: hold(ctx, ctx.body("chained")),
    "H_coll_chain": _objects_collide,
    "H_coll_pusher_chain": _actor_keeps_off,
    "swept_chain": _swept,
    "H_coll_obstacles_chain": _obstacles,
    "H_PoC_chain": _contact,
    "sticking_chain": _sticking,
    "quasi_static_chain": lambda ctx: _object_push(ctx, True),
    "object_motion_chain": lambda ctx: motion_cost(ctx, ctx.body("chained")),
    "H_F_chain": _dynamics,
    "friction_cone_chain": lambda ctx: _object_push(ctx, ctx.settings.row("friction_cone").turn),
}
