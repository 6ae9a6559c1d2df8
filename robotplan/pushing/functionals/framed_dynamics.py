"""H_F (paper eq. 5) with an F_flow or F that reads X_h in the object's frame.

H_F,t = ∫_X (φ1_t(x) − F̂_t(x))² dx with F̂_t = φ1_{t−1} + F_flow(…) (eq. 4) or F(…) (eq. 3),
as :class:`~robotplan.pushing.functionals.dynamics.LearnedDynamics` integrates it, but the model's
grid X_h is attached to the object at t − 1 (``spec.frame == "object"``): the frame F_t has
its origin at the footprint's area centroid c_{t−1} and the body's axes, so

* φ1_{t−1} on X_h is the footprint's own SDF about its centroid, the same image every step;
* φ2_{t−1}, φ2_t on X_h are the actor's SDF at the window's points placed by F_t;
* the query points x of the quadrature (fixed on the table) are read as F_t⁻¹ x.

Every term is a smooth function of the states, so the Jacobians come from one reverse pass
of autograd through the rendering, the network and the quadrature: row t of ``J1``/``J2``
holds ∂H_t/∂(state t − 1) and ∂H_t/∂(state t), as for the table-frame functional.
"""

from __future__ import annotations

import torch
from torch import Tensor

from robotplan.functionals.base import Quadrature
from robotplan.geometry.transforms import planar_to_body, planar_to_world
from robotplan.pushing.functionals.dynamics import LearnedDynamics
from robotplan.pushing.models.dynamics import PushDynamics
from robotplan.pushing.models.rigid import object_frame
from robotplan.scene.bodies import Body
from robotplan.sdf.footprint import footprint_centroid

__all__ = ["FramedDynamics", "field_dynamics"]


class FramedDynamics:
    """H_F of an object (φ1, planar pose) pushed by an actor (a disc's position or an
    object's pose) for T steps, with an object-frame F_flow or F (see the module notes).

    ``evaluate(X1 (T+1, 3), X2 (T+1, d))`` → ``H (T,)`` (m²), ``J1 (T, 2, 3)``,
    ``J2 (T, 2, d)``.
    """

    integral = True  # H is an integral over the table (m⁴), as H_F's

    def __init__(self, model: PushDynamics, obj: Body, pusher: Body,
                 quadrature: Quadrature) -> None:
        spec = model.spec
        if spec.frame != "object" or spec.representation != "sdf":
            raise ValueError("FramedDynamics needs an object-frame F_flow or F on SDFs "
                             f"(spec frame {spec.frame!r}, representation "
                             f"{spec.representation!r})")
        self.model, self.obj, self.pusher = model.eval(), obj, pusher
        for p in model.parameters():
            p.requires_grad_(False)
        self.dtype = next(model.parameters()).dtype
        window = spec.workspace()
        self.shape = window.shape
        self.window_points = window.points(self.dtype).reshape(-1, 2)
        self.centroid = torch.as_tensor(footprint_centroid(obj.shape), dtype=self.dtype)
        at_origin = torch.cat((-self.centroid, self.centroid.new_zeros(1)))
        with torch.no_grad():
            self.phi1_window = obj.sdf(self.window_points, at_origin)  # (H·W,)
        self.quadrature = Quadrature(quadrature.points.to(self.dtype),
                                     quadrature.weights.to(self.dtype))

    def _values(self, q1p: Tensor, q1n: Tensor, q2p: Tensor, q2n: Tensor) -> Tensor:
        T = q1p.shape[0]
        frames = object_frame(q1p, self.centroid.expand(T, 2))
        placed = planar_to_world(self.window_points[None], frames)  # (T, H·W, 2)
        inputs = torch.stack((self.phi1_window.expand(T, -1), self.pusher.sdf(placed, q2p),
                              self.pusher.sdf(placed, q2n)), 1).reshape(T, 3, *self.shape)
        x, w = self.quadrature.points, self.quadrature.weights
        out = self.model(inputs, planar_to_body(x[None], frames))  # (T, N)
        predicted = self.obj.sdf(x[None], q1p) + out if self.model.spec.kind == "flow" else out
        residual = self.obj.sdf(x[None], q1n) - predicted
        return (residual * residual) @ w

    def evaluate(self, X1: Tensor, X2: Tensor, jacobian: bool = True
                 ) -> tuple[Tensor, Tensor | None, Tensor | None]:
        X1, X2 = X1.to(self.dtype), X2.to(self.dtype)
        parts = [v.detach().clone().requires_grad_(jacobian)
                 for v in (X1[:-1], X1[1:], X2[:-1], X2[1:])]
        with torch.set_grad_enabled(jacobian):
            H = self._values(*parts)
        if not jacobian:
            return H, None, None
        # H_t depends on row t of each part alone, so the gradient of Σ_t H_t holds each
        # step's own derivatives row by row
        g1p, g1n, g2p, g2n = torch.autograd.grad(H.sum(), parts)
        return H.detach(), torch.stack((g1p, g1n), 1), torch.stack((g2p, g2n), 1)


def field_dynamics(model: PushDynamics, obj: Body, pusher: Body, quadrature: Quadrature
                   ) -> LearnedDynamics | FramedDynamics:
    """H_F for an F_flow or F of either frame: the table-frame fast path
    (:class:`LearnedDynamics`), or :class:`FramedDynamics` for a model that reads its grid
    about the object."""
    functional = FramedDynamics if model.spec.frame == "object" else LearnedDynamics
    return functional(model, obj, pusher, quadrature)
