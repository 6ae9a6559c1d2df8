"""H_F (eq. 5) as a row of a push program: the learned dynamics of an object pushed by an
actor (a disc or another object), a cost on its mean squared residual.

The model decides the functional: F_flow or F give H_F, the SDF residual over the table
(:class:`~robotplan.pushing.functionals.dynamics.LearnedDynamics`, or
:class:`~robotplan.pushing.functionals.framed_dynamics.FramedDynamics` for a model that reads its
grid in the object's frame); F_q gives H_q, the footprint's displacement from the
predicted rigid step (:class:`~robotplan.pushing.functionals.rigid_dynamics.RigidDynamics`). Both
enter the program as mean squares in mm² per step."""

from __future__ import annotations

import numpy as np
import torch

from robotplan.pushing.functionals.dynamics import (
    QUADRATURE_COARSE,
    LearnedDynamics,
    phase_quadrature,
)
from robotplan.pushing.functionals.framed_dynamics import FramedDynamics, field_dynamics
from robotplan.pushing.functionals.rigid_dynamics import RigidDynamics
from robotplan.pushing.models.dynamics import PushDynamics
from robotplan.pushing.models.rigid import RigidMotion

__all__ = ["Dynamics", "add_dynamics", "mm2_per_unit", "residual_mm2"]

Dynamics = LearnedDynamics | FramedDynamics | RigidDynamics


def mm2_per_unit(dynamics: Dynamics, scene) -> float:
    """What turns the functional's value per step into a mean square in mm²: H_F (m⁴, an
    integral over the table) is divided by the scene's table area; H_q is in m²."""
    if not dynamics.integral:
        return 1e6
    return 1e6 / float(scene.workspace.size[0] * scene.workspace.size[1])


def residual_mm2(dynamics: Dynamics, scene, q_obj: np.ndarray, q_actor: np.ndarray
                 ) -> np.ndarray:
    """``dynamics``' value per step as the mean squared residual (mm²)."""
    H, _, _ = dynamics.evaluate(torch.from_numpy(q_obj), torch.from_numpy(q_actor),
                                jacobian=False)
    return H.double().numpy() * mm2_per_unit(dynamics, scene)


def add_dynamics(ctx, model: PushDynamics | RigidMotion, pushed: tuple, pushing: tuple,
                 path: np.ndarray) -> Dynamics:
    """The row ``weight`` · Σ_t H_F,t (mm²; H_q for F_q) of the body ``pushed = (obj,
    Q_obj)`` (poses ``(N+1, 3)``) pushed by ``pushing = (actor, Q_actor)`` (``(N+1, 2)``
    positions of a disc, or ``(N+1, 3)`` poses of an object) over the row's steps t (with
    t − 1), integrated around ``path (N+1, ≥2)``, the object's guessed centres."""
    (obj, Q_obj), (actor, Q_actor) = pushed, pushing
    scene = ctx.program.scene
    if isinstance(model, RigidMotion):
        dynamics: Dynamics = RigidDynamics(model, obj, actor)
    else:
        quad = phase_quadrature(torch.as_tensor(path[:, :2], dtype=torch.float32),
                                obj.shape.bound_radius, scene.workspace,
                                coarse=QUADRATURE_COARSE)
        dynamics = field_dynamics(model, obj, actor, quad)
    N, d = len(Q_obj) - 1, Q_actor.shape[1]
    scale = mm2_per_unit(dynamics, scene)
    w = ctx.settings.row("H_F").weight

    def total(x: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
        X1 = torch.from_numpy(x[:3 * (N + 1)].reshape(N + 1, 3))
        X2 = torch.from_numpy(x[3 * (N + 1):].reshape(N + 1, d))
        H, J1, J2 = dynamics.evaluate(X1, X2, jacobian=jac)
        values = H.double().numpy() * scale
        if not jac:
            return np.array([w * values.sum()]), None
        J = np.zeros((N, (3 + d) * (N + 1)))
        rows = np.arange(N)
        J1n, J2n = J1.double().numpy() * scale, J2.double().numpy() * scale
        for which in (0, 1):
            states = rows + which
            for k in range(3):
                J[rows, 3 * states + k] = J1n[:, which, k]
            for k in range(d):
                J[rows, 3 * (N + 1) + d * states + k] = J2n[:, which, k]
        return np.array([w * values.sum()]), w * J.sum(axis=0, keepdims=True)

    # the row (and its time in the profile) is named after its functional
    name = ctx.name.replace("H_F", "H_q", 1) if isinstance(model, RigidMotion) else None
    ctx.cost(total, np.concatenate((Q_obj.ravel(), Q_actor.ravel())), name)
    return dynamics
