"""H_hang, the learned kinematic success functional of mug hanging (paper §5.2, §7.1), as a
functional of the mug's pose X_HM in the hook frame: the mug's SDF rigidly moved by the pose
(T(q)[φ], paper §4) and the hook's SDF, both on the grid X_h, through the network."""

from __future__ import annotations

import torch
from torch import Tensor

from robotplan.functionals.base import Functional
from robotplan.geometry.transforms import spatial_to_body
from robotplan.hanging.models.hang_model import HangSpec, HangSuccess
from robotplan.hanging.scene.ranges import GridSpec
from robotplan.sdf.mug_hook import Hook, Mug, mug_sdf, sdf_at

__all__ = ["HangGrids", "HangSuccessFunctional", "mug_grids"]


class HangGrids:
    """X_h for one hook: its cell centres ``(C³, 3)`` in the hook frame (a lattice about the
    grid's centre), the hook's SDF on them ``(C, C, C)``, and the mug's SDF there for any
    poses."""

    def __init__(self, hook: Hook, spec: HangSpec, dtype: torch.dtype = torch.float32) -> None:
        grid = GridSpec(size=spec.size, cells=spec.cells, below_arm=spec.below_arm)
        self.cells = spec.cells
        self.centre = torch.from_numpy(grid.centre(hook)).to(dtype)
        self.points = torch.from_numpy(grid.points(hook).reshape(-1, 3)).to(dtype)
        self.hook = hook.sdf(self.points).reshape(spec.cells, spec.cells, spec.cells)

    def mug(self, mug: Mug, X_HM: Tensor) -> Tensor:
        """The mug's SDF ``(B, C, C, C)`` at poses ``X_HM (B, 7)`` (differentiable in them)."""
        c = self.cells
        return sdf_at(mug, self.points.to(X_HM), X_HM).reshape(-1, c, c, c)

    def stacked(self, mug: Mug, X_HM: Tensor) -> Tensor:
        """The network's input ``(B, 2, C, C, C)``: mug, then hook."""
        m = self.mug(mug, X_HM)
        return torch.stack((m, self.hook.to(m).expand_as(m)), dim=1)


def mug_grids(lattice: Tensor, centres: Tensor, mugs: Tensor, X_HM: Tensor) -> Tensor:
    """Many scenes at once: the SDFs ``(B, N)`` of mugs ``(B, 7)`` (parameters in
    ``MUG_FIELDS`` order) posed at ``X_HM (B, 7)``, at the cells ``lattice (N, 3)`` about each
    scene's grid centre ``centres (B, 3)``."""
    points = lattice[None] + centres[:, None]
    return mug_sdf(mugs, spatial_to_body(points, X_HM))


class HangSuccessFunctional(Functional):
    """H_hang(T(X_HM)[φ_mug], φ_hook): ``residual(X_HM (T, 7)) → (T, 1)``, ≈ 0 where the mug
    hangs (trained with eq. 21). The model's dtype sets the arithmetic; the Jacobian
    ``(T, 1, 7)`` comes from autograd through the grid rendering."""

    def __init__(self, model: HangSuccess, mug: Mug, hook: Hook) -> None:
        self.model = model
        self.mug = mug
        dtype = next(model.parameters()).dtype
        self.grids = HangGrids(hook, model.spec, dtype)

    def residual(self, X_HM: Tensor) -> Tensor:
        dtype = next(self.model.parameters()).dtype
        grids = self.grids.stacked(self.mug, X_HM.to(dtype))
        return self.model(grids)[:, None].to(X_HM.dtype)
