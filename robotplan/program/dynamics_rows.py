"""H_F (eq. 5) as a row of a push program: the learned dynamics of an object pushed by an
actor (a disc or another object), a cost on its mean squared residual or a bound on it.

The model decides the functional: F_flow or F give H_F, the SDF residual over the table
(:class:`~robotplan.functionals.dynamics.LearnedDynamics`, or
:class:`~robotplan.functionals.framed_dynamics.FramedDynamics` for a model that reads its
grid in the object's frame); F_q gives H_q, the footprint's
displacement from the predicted rigid step
(:class:`~robotplan.functionals.rigid_dynamics.RigidDynamics`). Both enter the program as
mean squares in mm² per step."""

from __future__ import annotations

import numpy as np
import torch

from robotplan.functionals.dynamics import QUADRATURE_COARSE, LearnedDynamics, phase_quadrature
from robotplan.functionals.framed_dynamics import FramedDynamics, field_dynamics
from robotplan.functionals.rigid_dynamics import RigidDynamics
from robotplan.models.dynamics import PushDynamics
from robotplan.models.rigid import RigidMotion
from robotplan.program.bridge import bridge
from robotplan.program.row_table import RowSpec
from robotplan.program.rows import ProgramRows

__all__ = ["DynamicsRows", "mm2_per_unit"]

Dynamics = LearnedDynamics | FramedDynamics | RigidDynamics


def mm2_per_unit(dynamics: Dynamics, scene) -> float:
    """What turns the functional's value per step into a mean square in mm²: H_F (m⁴, an
    integral over the table) is divided by the scene's table area; H_q is in m²."""
    if not dynamics.integral:
        return 1e6
    return 1e6 / float(scene.workspace.size[0] * scene.workspace.size[1])


class DynamicsRows(ProgramRows):
    """H_F rows of a program with ``model``, ``obj``/``Q1``, ``pusher``/``Q2`` and a
    ``guess``."""

    def _row_dynamics(self, spec: RowSpec) -> None:
        """H_F (eq. 5) of the object pushed by the actor in every step."""
        self.dynamics = self._add_dynamics(self.model, (self.obj, self.Q1),
                                           (self.pusher, self.Q2), self.guess["q_obj"], spec.row)

    def _add_dynamics(self, model: PushDynamics | RigidMotion, pushed: tuple, pushing: tuple,
                      path: np.ndarray, name: str) -> Dynamics:
        """H_F (or H_q for F_q) of the body ``pushed = (obj, Q_obj)`` (poses ``(N+1, 3)``)
        pushed by ``pushing = (actor, Q_actor)`` (``(N+1, 2)`` positions of a disc, or
        ``(N+1, 3)`` poses of an object) in every step, integrated around ``path (N+1, ≥2)``,
        the object's guessed centres."""
        (obj, Q_obj), (actor, Q_actor), s = pushed, pushing, self.settings
        if isinstance(model, RigidMotion):
            dynamics: Dynamics = RigidDynamics(model, obj, actor)
            # the row (and its time in the profile) is named after its functional
            name = name.replace("H_F", "H_q", 1)
        else:
            quad = phase_quadrature(torch.as_tensor(path[:, :2], dtype=torch.float32),
                                    obj.shape.bound_radius, self.scene.workspace,
                                    coarse=QUADRATURE_COARSE)
            dynamics = field_dynamics(model, obj, actor, quad)
        N, d = self.N, Q_actor.shape[1]
        scale = mm2_per_unit(dynamics, self.scene)

        def fn(x: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
            X1 = torch.from_numpy(x[:3 * (N + 1)].reshape(N + 1, 3))
            X2 = torch.from_numpy(x[3 * (N + 1):].reshape(N + 1, d))
            H, J1, J2 = dynamics.evaluate(X1, X2, jacobian=jac)
            values = H.double().numpy() * scale
            if not jac:
                return values, None
            J = np.zeros((N, (3 + d) * (N + 1)))
            rows = np.arange(N)
            J1n, J2n = J1.double().numpy() * scale, J2.double().numpy() * scale
            for which in (0, 1):
                states = rows + which
                for k in range(3):
                    J[rows, 3 * states + k] = J1n[:, which, k]
                for k in range(d):
                    J[rows, 3 * (N + 1) + d * states + k] = J2n[:, which, k]
            return values, J

        variables = np.concatenate((Q_obj.ravel(), Q_actor.ravel()))
        if s.row("H_F").weight > 0:
            def total(x: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
                values, J = fn(x, jac)
                w = s.row("H_F").weight
                return (np.array([w * values.sum()]),
                        None if J is None else w * J.sum(axis=0, keepdims=True))

            self._add_cost(total, variables, name)
            return dynamics
        bound = (s.row("H_F").rmse * 1e3) ** 2
        self.prog.AddConstraint(bridge(fn, self.timings, name), np.zeros(N), np.full(N, bound),
                                variables, name)
        return dynamics
