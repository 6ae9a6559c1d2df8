"""H_g, the goal-region functional (paper §6.2, eq. 8)."""

from __future__ import annotations

import torch
from torch import Tensor

from robotplan.functionals.base import Functional, Quadrature, sdf_pose_gradients
from robotplan.functionals.windows import body_aabb, margin, window_bound_gradients, window_points
from robotplan.scene.bodies import Body

__all__ = ["GoalRegion"]


class GoalRegion(Functional):
    """H_g(φ1, φg) = ∫_X σ(−a φ1(x)) σ(a φg(x)) dx (eq. 8): the area of the body that lies
    outside the fixed goal region, smoothed with sharpness ``a`` (paper a = 100). ``inset``
    (m) shrinks the region: a plan that ends deeper inside tolerates execution error.

    ``residual(X_WB (T, 3|2)) → (T, 1)`` in m²; ≈ 0 when the body is well inside the region.

    With a ``quadrature`` the integral runs over its points; without one (the fast path)
    over the body's bounding box grown by the sigmoid's ``eps`` margin, at ``resolution``
    (default 2/a: 2 cm for a = 100; within 0.2 % of a 1 mm full grid).
    """

    def __init__(self, body: Body, region: Body, quadrature: Quadrature | None = None,
                 a: float = 100.0, resolution: float | None = None, eps: float = 1e-4,
                 inset: float = 0.0):
        self.body, self.region, self.quadrature, self.a = body, region, quadrature, a
        self.inset = inset  # m: measure against the region shrunk by this much
        self.resolution = resolution or 2.0 / a
        self.margin = margin(a, eps)
        if quadrature is not None:
            x = quadrature.points
            self._outside_region = torch.sigmoid(self.a * (region.sdf(x) + inset))  # fixed

    def residual(self, X_WB: Tensor) -> Tensor:
        if self.quadrature is not None:
            x = self.quadrature.points.to(X_WB)
            inside = torch.sigmoid(-self.a * self.body.sdf(x, X_WB))  # (T, N)
            return self.quadrature.integrate(inside * self._outside_region.to(X_WB))[:, None]
        lo, hi = body_aabb(self.body, X_WB)
        lo, hi = lo - self.margin, hi + self.margin
        x, w = window_points(lo, hi, self.resolution, self.margin / 3)
        inside = torch.sigmoid(-self.a * self.body.sdf(x, X_WB))  # (T, P)
        outside_region = torch.sigmoid(self.a * (self.region.sdf(x) + self.inset))
        return (inside * outside_region * w).sum(1, keepdim=True)

    def jacobians(self, X_WB: Tensor) -> tuple[Tensor, list[Tensor]]:
        """The fast path's value and exact Jacobian ``(T, 1, k)`` without autograd (the
        sigmoid's slope along ∂φ/∂X plus the taper's, as in :class:`Collision`)."""
        if self.quadrature is not None:
            return super().jacobians(X_WB)
        X = X_WB.detach()
        lo, hi, J_lo, J_hi = body_aabb(self.body, X, jacobians=True)
        x, w, factors = window_points(lo - self.margin, hi + self.margin, self.resolution,
                                      self.margin / 3, factors=True)
        phi, d_pose, _ = sdf_pose_gradients(self.body, x, X)
        inside = torch.sigmoid(-self.a * phi)
        outside_region = torch.sigmoid(self.a * (self.region.sdf(x) + self.inset))
        f = inside * outside_region
        fw = f * w
        slope = (-self.a) * (1.0 - inside) * fw  # ∂(f w)/∂φ
        g_lo, g_hi = window_bound_gradients(f, factors)
        J = (torch.bmm(slope[:, None, :], d_pose)[:, 0]
             + (g_lo[..., None] * J_lo + g_hi[..., None] * J_hi).sum(1))
        return fw.sum(1, keepdim=True), [J[:, None, :]]
