"""The initial guess of a chain (paper Fig. 9): the object pushed towards the chained one
until they touch, then both on towards the goal, and the geometry it needs."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import torch

from robotplan.functionals.base import sdf_pose_gradients
from robotplan.pushing.program.guess import guess_goal, initial_guess

if TYPE_CHECKING:
    from robotplan.pushing.program.push_program import PushProgram

__all__ = ["chain_guess", "objects_touch", "touching_distance"]


def _world_outline(body, X: np.ndarray) -> torch.Tensor:
    """``body``'s outline ``(V, 2)`` at the planar pose ``X (3,)``, as a float64 tensor."""
    return torch.as_tensor(body.outline_world(X), dtype=torch.float64)


def objects_touch(a, b, gap: float = 0.002) -> bool:
    """Whether bodies ``a`` and ``b`` at their scene poses come within ``gap`` (m): a vertex
    of one outline within ``gap`` of the other body."""
    Xa, Xb = (np.asarray(body.pose, dtype=float) for body in (a, b))
    return bool(min(float(b.sdf(_world_outline(a, Xa)[None], torch.as_tensor(Xb)[None]).min()),
                    float(a.sdf(_world_outline(b, Xb)[None], torch.as_tensor(Xa)[None]).min()))
                <= gap)


def touching_distance(a, b, X_b: np.ndarray, direction: np.ndarray, yaw_a: float) -> float:
    """How far (m) from ``b``'s origin (pose ``X_b``) along the unit ``direction`` body
    ``a`` (yaw ``yaw_a``) sits when it just touches ``b`` from outside: bisection on the
    outlines' vertices (neither has a vertex inside the other)."""
    Xb = torch.as_tensor(X_b, dtype=torch.float64)[None]
    verts_b = _world_outline(b, X_b)[None]

    def apart(d: float) -> bool:
        X_a = np.array([*(X_b[:2] + d * direction), yaw_a])
        va = _world_outline(a, X_a)[None]
        return bool(b.sdf(va, Xb).min() >= 0
                    and a.sdf(verts_b, torch.as_tensor(X_a)[None]).min() >= 0)

    lo, hi = 0.0, a.shape.bound_radius + b.shape.bound_radius
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if apart(mid) else (mid, hi)
    return hi


def chain_guess(prog: PushProgram) -> dict[str, np.ndarray]:
    """The circle-and-push guess (app. I.2) for a chain: the pushes alone carry ``obj``
    straight towards the target's centre until they touch (a sideways push would turn
    it), the chained pushes carry both on along that line to its point nearest the goal
    (the optimiser bends it where needed); the target moves with ``obj``
    in chained phases; ``p_chain`` is ``obj``'s centre projected onto the target's
    surface."""
    obj, target = prog.obj, prog.target
    s_obj = np.array(obj.pose[:2], dtype=float)
    X_t = np.array(target.pose, dtype=float)
    goal = guess_goal(prog, X_t[:2]) if prog.region is not None else X_t[:2]
    u = X_t[:2] - s_obj
    u = u / max(float(np.linalg.norm(u)), 1e-9)
    # on along the same line, as near the goal as it comes: a push through both objects'
    # centres moves the target within the friction cone without turning it
    travel = max(0.0, float((goal - X_t[:2]) @ u)) * u
    touch = X_t[:2] - touching_distance(obj, target, X_t, -u, obj.pose[2]) * u
    pushes = [ph for ph in prog.skeleton.phases if ph.mode == "push"]
    alone = sum(ph.chain is None for ph in pushes)
    ends, i_alone, i_chain = [], 0, 0
    for ph in pushes:
        if ph.chain is None:
            i_alone += 1
            ends.append(s_obj + (touch - s_obj) * i_alone / alone)
        else:
            i_chain += 1
            ends.append(touch + travel * i_chain / (len(pushes) - alone))
    guess = initial_guess(prog, np.array(ends))
    q1 = guess["q_obj"]
    q3 = np.tile(X_t, (prog.N + 1, 1))
    T = prog.T
    for k, ph in enumerate(prog.skeleton.phases):
        a = k * T
        q3[a + 1:a + T + 1] = q3[a]
        if ph.mode == "push" and ph.chain:
            q3[a + 1:a + T + 1, :2] += q1[a + 1:a + T + 1, :2] - q1[a, :2]
    steps = prog.chain_steps
    p = np.zeros((len(steps), 2))
    if len(steps):
        X = torch.as_tensor(q3[steps], dtype=torch.float64)
        centres = torch.as_tensor(q1[steps, :2], dtype=torch.float64)[:, None, :]
        phi, _, grad = sdf_pose_gradients(target, centres, X)
        n = grad[:, 0] / grad[:, 0].norm(dim=-1, keepdim=True).clamp_min(1e-9)
        p = (centres[:, 0] - phi[:, :1] * n).numpy()
    return {**guess, "q_chain": q3, "p_chain": p}
