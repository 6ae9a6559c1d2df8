"""H_g, the goal-region functional (paper §6.2, eq. 8), and the pose goal's error."""

from __future__ import annotations

import math

import numpy as np
import torch
from torch import Tensor

from robotplan.functionals.base import Functional, Quadrature, sdf_pose_gradients
from robotplan.functionals.sticking import centroid
from robotplan.functionals.windows import body_aabb, margin, window_bound_gradients, window_points
from robotplan.geometry.polygons import signed_area
from robotplan.geometry.transforms import planar_to_world
from robotplan.scene.bodies import Body

__all__ = ["GoalRegion", "PoseError", "gyration_radius"]


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


def gyration_radius(outline: np.ndarray) -> float:
    """Radius of gyration (m) of a simple polygon ``(V, 2)`` about its area centroid:
    √(J_c / A) with J_c the polar second moment of area (shoelace form)."""
    x, y = outline[:, 0], outline[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    area = cross.sum() / 2
    c = centroid(outline)
    polar = (cross * (x * x + x * xn + xn * xn + y * y + y * yn + yn * yn)).sum() / 12
    return float(math.sqrt(max(polar / area - c @ c, 0.0)))


class PoseError(Functional):
    """The pose goal's error: ``residual(X_WB (T, 3)) → (T, 3)`` in m,
    ``[Δc_x, Δc_y, 2 ρ sin(Δθ/2)]`` with Δc the footprint centroid's offset from its place at
    the target pose ``X_WG`` and ρ the footprint's radius of gyration, so that the squared
    norm is the mean squared displacement of the footprint's points from the target
    (|Δc|² + ρ² (2 − 2 cos Δθ)). Unlike H_g with the footprint as region, whose smoothing
    leaves a sixth of a box's area "outside" at the exact pose, it is zero there."""

    def __init__(self, outline_B: np.ndarray, X_WG: tuple[float, float, float]) -> None:
        self.c_B = torch.as_tensor(centroid(outline_B))
        self.rho = gyration_radius(outline_B)
        self.X_WG = torch.as_tensor(np.asarray(X_WG, dtype=float))

    def residual(self, X_WB: Tensor) -> Tensor:
        goal = self.X_WG.to(X_WB)
        c_B = self.c_B.to(X_WB)[None]
        d = (planar_to_world(c_B, X_WB) - planar_to_world(c_B, goal))[:, 0]
        turn = 2 * self.rho * torch.sin((X_WB[:, 2] - goal[2]) / 2)
        return torch.cat((d, turn[:, None]), -1)

    def tolerance(self, outline_B: np.ndarray, share: float) -> float:
        """The RMS displacement (m) that moves at most ``share`` of the footprint's area off
        its target by translation: share · 2A / P (a translation δ uncovers at most δ·P/2)."""
        edges = np.linalg.norm(np.roll(outline_B, -1, axis=0) - outline_B, axis=1)
        return float(share * 2 * abs(signed_area(outline_B)) / edges.sum())
