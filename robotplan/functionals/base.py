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

from robotplan.sdf import Workspace

__all__ = ["Functional", "Quadrature"]


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
