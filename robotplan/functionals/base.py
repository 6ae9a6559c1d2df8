"""Common parts of the functionals: the quadrature of X and the residual/Jacobian contract.

A functional H is a small class (one cost, one class) whose ``residual(*poses)`` maps the
decision variables of T steps, each input ``(T, d_i)``, to residuals ``(T, m)`` that vanish
when the scene is right. Steps are independent, so ``jacobians`` gets every per-step block
``∂r_t/∂x_t (T, m, d_i)`` from m backward passes (one per residual component), not T·m.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import Tensor

from robotplan.scene.bodies import Body
from robotplan.sdf import Circle, Workspace

__all__ = ["Functional", "Quadrature", "sdf_pose_gradients"]


@dataclass(frozen=True)
class Quadrature:
    """Points ``(N, 2)`` and weights ``(N,)`` approximating ∫_X f(x) dx ≈ Σ w_n f(x_n)."""

    points: Tensor
    weights: Tensor

    @classmethod
    def box(cls, center: tuple[float, float], size: tuple[float, float], resolution: float,
            dtype: torch.dtype = torch.float64) -> Quadrature:
        """Midpoint rule on a regular grid of ``resolution`` over ``center ± size / 2``."""
        ws = Workspace(center=center, size=size, resolution=resolution)
        pts = ws.points(dtype).reshape(-1, 2)
        return cls(pts, torch.full((pts.shape[0],), ws.cell_area, dtype=dtype))

    @classmethod
    def grid(cls, workspace: Workspace, dtype: torch.dtype = torch.float64) -> Quadrature:
        """The workspace grid X_h itself (paper: 140 × 140 at 1 cm)."""
        return cls.box(workspace.center, workspace.size, workspace.resolution, dtype)

    def integrate(self, values: Tensor) -> Tensor:
        """``(..., N)`` integrand values at the points → ``(...)`` integrals."""
        return values @ self.weights.to(values)


class Functional:
    """Base class: subclasses implement ``residual`` with batched ``(T, d)`` inputs."""

    def residual(self, *inputs: Tensor) -> Tensor:
        raise NotImplementedError

    def __call__(self, *inputs: Tensor) -> Tensor:
        return self.residual(*inputs)

    def jacobians(self, *inputs: Tensor) -> tuple[Tensor, list[Tensor]]:
        """Residuals ``(T, m)`` and per-step Jacobians ``[(T, m, d_i)]``, one per input."""
        xs = [x.detach().requires_grad_(True) for x in inputs]
        with torch.enable_grad():
            r = self.residual(*xs)
            m = r.shape[-1]
            rows = [torch.autograd.grad(r[:, k].sum(), xs, retain_graph=k + 1 < m,
                                        allow_unused=True) for k in range(m)]
        jac = [torch.stack([torch.zeros_like(x) if g[i] is None else g[i] for g in rows], dim=1)
               for i, x in enumerate(xs)]
        return r.detach(), jac


def sdf_pose_gradients(body: Body, points_W: Tensor, X_WB: Tensor, position_only: bool = False
                       ) -> tuple[Tensor, Tensor, Tensor]:
    """φ of ``body`` at table-frame points and its exact first derivatives, without autograd.

    Args:
        points_W: ``(..., N, 2)`` points; X_WB: ``(..., 3)`` poses or ``(..., 2)`` positions
            (leading dimensions broadcast as in :meth:`Body.sdf`).
        position_only: treat a ``(..., 3)`` pose as a position (no yaw derivative).
    Returns:
        φ ``(..., N)``; ∂φ/∂X_WB ``(..., N, k)`` with k = X_WB's width (the yaw column is 0
        for discs and position-only bodies); ∂φ/∂p_W ``(..., N, 2)``.
    From ∇φ in the body frame: ∂φ/∂p_W = R ∇φ_B, ∂φ/∂t = −R ∇φ_B and
    ∂φ/∂θ = ∇φ_B · (p_B,y, −p_B,x).
    """
    X = X_WB.detach()
    dx = points_W[..., 0].detach() - X[..., 0:1]  # (..., N) coordinate planes
    dy = points_W[..., 1].detach() - X[..., 1:2]
    if X.shape[-1] == 2:
        phi, gx, gy = body.shape.sdf_and_grad_planes(dx, dy)
        grad_W = torch.stack((gx, gy), dim=-1)
        return phi, -grad_W, grad_W
    c, s = torch.cos(X[..., 2:3]), torch.sin(X[..., 2:3])
    bx, by = c * dx + s * dy, c * dy - s * dx  # p_B = R(yaw)ᵀ (p_W − t)
    phi, gx, gy = body.shape.sdf_and_grad_planes(bx, by)
    wx, wy = c * gx - s * gy, s * gx + c * gy  # R ∇φ_B
    if position_only or isinstance(body.shape, Circle):
        d_theta = torch.zeros_like(phi)
    else:
        d_theta = gx * by - gy * bx
    return (phi, torch.stack((-wx, -wy, d_theta), dim=-1), torch.stack((wx, wy), dim=-1))
