"""H_PoC, establishing contact (paper §6.3, eq. 9, in the decision-variable form of app. G)."""

from __future__ import annotations

import torch
from torch import Tensor

from robotplan.functionals.base import Functional, sdf_pose_gradients
from robotplan.scene.bodies import Body

__all__ = ["ContactPoint"]


class ContactPoint(Functional):
    """H_PoC(φ1, φ2) = min_p |φ1(p)| + |φ2(p)| (eq. 9). With the contact point p as a decision
    variable (appendix G) it becomes the two equalities φ1(p) = 0 and φ2(p) = 0.

    ``residual(X_W1 (T, 3|2), X_W2 (T, 3|2), p_W (T, 2)) → (T, 2) = [φ1(p), φ2(p)]`` in m;
    both vanish exactly when p lies on both surfaces, i.e. the bodies touch at p.
    """

    def __init__(self, body1: Body, body2: Body):
        self.body1, self.body2 = body1, body2

    def residual(self, X_W1: Tensor, X_W2: Tensor, p_W: Tensor) -> Tensor:
        p = p_W[:, None, :]  # (T, 1, 2): one query point per step
        return torch.cat((self.body1.sdf(p, X_W1), self.body2.sdf(p, X_W2)), dim=-1)

    def jacobians(self, X_W1: Tensor, X_W2: Tensor, p_W: Tensor
                  ) -> tuple[Tensor, list[Tensor]]:
        """Residuals ``(T, 2)`` and exact Jacobians from ∇φ (no autograd)."""
        p = p_W.detach()[:, None, :]
        phi1, d1, g1 = sdf_pose_gradients(self.body1, p, X_W1)
        phi2, d2, g2 = sdf_pose_gradients(self.body2, p, X_W2)
        J1 = torch.zeros(p.shape[0], 2, X_W1.shape[1], dtype=phi1.dtype)
        J2 = torch.zeros(p.shape[0], 2, X_W2.shape[1], dtype=phi1.dtype)
        J1[:, 0], J2[:, 1] = d1[:, 0], d2[:, 0]
        return torch.cat((phi1, phi2), dim=-1), [J1, J2, torch.cat((g1, g2), dim=1)]
