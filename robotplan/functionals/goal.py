"""H_g, the goal-region functional (paper §6.2, eq. 8)."""

from __future__ import annotations

import torch
from torch import Tensor

from robotplan.functionals.base import Functional, Quadrature
from robotplan.scene.bodies import Body

__all__ = ["GoalRegion"]


class GoalRegion(Functional):
    """H_g(φ1, φg) = ∫_X σ(−a φ1(x)) σ(a φg(x)) dx (eq. 8): the area of the body that lies
    outside the fixed goal region, smoothed with sharpness ``a`` (paper a = 100).

    ``residual(X_WB (T, 3|2)) → (T, 1)`` in m²; ≈ 0 when the body is well inside the region.
    """

    def __init__(self, body: Body, region: Body, quadrature: Quadrature, a: float = 100.0):
        self.body, self.region, self.quadrature, self.a = body, region, quadrature, a
        x = quadrature.points
        self._outside_region = torch.sigmoid(self.a * region.sdf(x))  # (N,), fixed region

    def residual(self, X_WB: Tensor) -> Tensor:
        x = self.quadrature.points.to(X_WB)
        inside = torch.sigmoid(-self.a * self.body.sdf(x, X_WB))  # (T, N)
        return self.quadrature.integrate(inside * self._outside_region.to(X_WB))[:, None]
