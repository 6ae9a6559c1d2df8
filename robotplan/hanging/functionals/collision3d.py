"""H_coll in 3D between a moved body and a fixed one (paper §6.1, eq. 7; a = 1000 for the
mug and the hook, app. H): H_coll = ∫_X σ(−a φ_1(x)) σ(−a φ_2(x)) dx, the overlap volume
smoothed by a sigmoid of sharpness ``a`` (1/m). With ``read`` (an occupancy measure ψ of
φ, the paper's baseline of app. A.5) the integrand is σ(−a ψ_1(x)) σ(−a ψ_2(x)).

The fixed body's factor is computed once: the integral runs over the cells of a lattice of
``resolution`` around the fixed body where σ(−a φ_2) exceeds ``eps``, each weighted by its
volume and by σ(−a φ_2); only the moved body's SDF is evaluated per pose."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import torch
from torch import Tensor

from robotplan.functionals.base import Functional
from robotplan.sdf.mug_hook import sdf_at
from robotplan.sdf.shapes3d import Shape3D

__all__ = ["FixedCollision3D"]


class FixedCollision3D(Functional):
    """``residual(X_FM (T, 7)) → (T, 1)``: the smoothed overlap volume (m³) of ``moved`` at
    poses X_FM (in the fixed body's frame F) with ``fixed``.

    ``bounds`` ``(lo, hi)`` (each ``(3,)``, frame F) limits the lattice to where the moved
    body can be (the parts of the fixed body outside never touch it); a fixed body with an
    ``aabb()`` limits it further to that box grown by the sigmoid's reach."""

    def __init__(self, moved: Shape3D, fixed: Shape3D, bounds: tuple[np.ndarray, np.ndarray],
                 a: float = 1000.0, resolution: float = 0.002, eps: float = 1e-3,
                 dtype: torch.dtype = torch.float64,
                 read: Callable[[Tensor], Tensor] | None = None) -> None:
        self.moved, self.a = moved, a
        self.read = read or (lambda phi: phi)
        lo, hi = (np.asarray(b, dtype=float) for b in bounds)
        # σ(−a φ) > eps ⇔ φ < reach; an occupancy measure ψ(φ) ≤ φ for φ ≥ 0 (ψ = sign φ,
        # tanh(b φ) with b ≥ 1), so the same box holds every cell where σ(−a ψ) > eps
        reach = math.log(1 / eps - 1) / a
        if hasattr(fixed, "aabb"):
            box_lo, box_hi = fixed.aabb()
            lo, hi = np.maximum(lo, box_lo - reach), np.minimum(hi, box_hi + reach)
        axes = [torch.arange(lo[i] + resolution / 2, hi[i], resolution, dtype=dtype)
                for i in range(3)]
        points, weights = [], []
        cell = resolution**3
        # slabs along x keep the lattice's memory bounded
        for x in axes[0]:
            grid = torch.stack(torch.meshgrid(x[None], axes[1], axes[2], indexing="ij"),
                               dim=-1).reshape(-1, 3)
            psi = self.read(fixed.sdf(grid))
            near = psi < reach
            points.append(grid[near])
            weights.append(cell * torch.sigmoid(-a * psi[near]))
        self.points = torch.cat(points)
        self.weights = torch.cat(weights)

    def residual(self, X_FM: Tensor) -> Tensor:
        pts = self.points.to(X_FM)
        w = self.weights.to(X_FM)
        inside = torch.sigmoid(-self.a * self.read(sdf_at(self.moved, pts, X_FM)))  # (T, N)
        return (inside * w).sum(-1, keepdim=True)
