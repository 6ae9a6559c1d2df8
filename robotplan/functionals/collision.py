"""H_coll, the pair-collision functional (paper §6.1, eq. 7)."""

from __future__ import annotations

import torch
from torch import Tensor

from robotplan.functionals.base import Functional, Quadrature
from robotplan.scene.bodies import Body

__all__ = ["Collision"]


class Collision(Functional):
    """H_coll(φ1, φ2) = ∫_X σ(−a φ1(x)) σ(−a φ2(x)) dx (eq. 7): the overlap area of two bodies,
    smoothed by a sigmoid of sharpness ``a`` (1/m; paper a = 500, so the edge is ~2 mm wide).

    ``residual(X_W1 (T, 3|2), X_W2 (T, 3|2)) → (T, 1)`` in m². It is ≈ 0 when the bodies are
    apart by more than the smoothing band and grows with the overlap.
    """

    def __init__(self, body1: Body, body2: Body, quadrature: Quadrature, a: float = 500.0):
        self.body1, self.body2, self.quadrature, self.a = body1, body2, quadrature, a

    def residual(self, X_W1: Tensor, X_W2: Tensor) -> Tensor:
        x = self.quadrature.points.to(X_W1)
        inside1 = torch.sigmoid(-self.a * self.body1.sdf(x, X_W1))  # (T, N)
        inside2 = torch.sigmoid(-self.a * self.body2.sdf(x, X_W2))
        return self.quadrature.integrate(inside1 * inside2)[:, None]
