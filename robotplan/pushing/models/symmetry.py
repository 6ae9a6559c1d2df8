"""Exact symmetries of a pushing scene on a square grid, and models averaged over them.

Planar pushing on a uniform table does not change when the whole scene is turned by a
quarter turn or mirrored: the pushed object's step turns or mirrors with it. On a square
X_h whose cell centres lie symmetric about its centre, these eight maps (the dihedral group
of the square) take grid points to grid points, so they act on the rendered grids exactly,
as index permutations. A model's prediction averaged over the views of a scene,

    F̄(φ) = (1/|G|) Σ_g g⁻¹ · F(g · φ),

is exactly equivariant to them, whatever the network learnt (test-time symmetrisation).
The mirrored views are valid inputs where the training scenes are closed under mirroring:
a mirrored box is a box and a mirrored L-shape with half sizes (w, h) is the L-shape
(h, w) turned, which the data draws as well.

Grids are ``(…, H, W)`` with rows along y and columns along x (as rendered from
``Workspace.points``); a counter-clockwise quarter turn is ``rot90`` over ``(W, H)``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import torch
from torch import Tensor

__all__ = ["VIEW_COUNTS", "GridView", "grid_views", "symmetric_delta_q", "symmetric_field"]

VIEW_COUNTS = (1, 4, 8)  # the identity; the quarter turns; the quarter turns and mirrors


@dataclass(frozen=True)
class GridView:
    """The map g: mirror x → −x about the grid's centre (if ``mirror``), then ``turns``
    quarter turns counter-clockwise about it."""

    turns: int
    mirror: bool = False

    def images(self, grids: Tensor) -> Tensor:
        """The grids ``(…, H, W)`` of the scene g · s, from those of s."""
        _check_square(grids)
        x = grids.flip(-1) if self.mirror else grids
        return torch.rot90(x, self.turns, dims=(-1, -2))

    def images_back(self, grids: Tensor) -> Tensor:
        """The inverse of :meth:`images`: fields ``(…, H, W)`` seen in g · s, back in s."""
        _check_square(grids)
        x = torch.rot90(grids, -self.turns, dims=(-1, -2))
        return x.flip(-1) if self.mirror else x

    def matrix(self, like: Tensor) -> Tensor:
        """The linear part of g, ``(2, 2)``, for vectors in the table's (or window's) axes."""
        c = [1, 0, -1, 0][self.turns % 4]
        s = [0, 1, 0, -1][self.turns % 4]
        turn = like.new_tensor([[c, -s], [s, c]])
        return turn @ like.new_tensor([[-1, 0], [0, 1]]) if self.mirror else turn

    def delta_q_back(self, delta: Tensor) -> Tensor:
        """Δq ``(B, 3)`` = (Δx, Δy, Δα) predicted in g · s, back in s: the shift through
        g⁻¹, the turn's sign flipped by a mirror (the pivot is g's image of s's pivot)."""
        shift = delta[:, :2] @ self.matrix(delta)  # v = M⁻¹ v' = Mᵀ v' (M orthogonal)
        turn = -delta[:, 2:] if self.mirror else delta[:, 2:]
        return torch.cat((shift, turn), 1)


def grid_views(count: int) -> list[GridView]:
    """The first ``count`` views: 1 (the identity), 4 (the quarter turns) or 8 (with the
    mirrored ones)."""
    if count not in VIEW_COUNTS:
        raise ValueError(f"views {count}: expected one of {', '.join(map(str, VIEW_COUNTS))}")
    return [GridView(k % 4, k >= 4) for k in range(count)]


def _check_square(grids: Tensor) -> None:
    if grids.shape[-1] != grids.shape[-2]:
        raise ValueError(f"symmetry views need a square grid, got {tuple(grids.shape[-2:])}")


def symmetric_delta_q(model: Callable[[Tensor], Tensor], inputs: Tensor, count: int
                      ) -> Tensor:
    """F_q averaged over ``count`` views: ``inputs (B, C, H, W)`` → Δq ``(B, 3)``, about the
    pivot the grid defines (a point every view maps along with the scene)."""
    views = grid_views(count)
    if count == 1:  # the network alone
        return model(inputs)
    return torch.stack([v.delta_q_back(model(v.images(inputs))) for v in views]).mean(0)


def symmetric_field(model: Callable[[Tensor], Tensor], inputs: Tensor, count: int) -> Tensor:
    """A field model (F_flow, F) averaged over ``count`` views, on X_h's own points:
    ``inputs (B, C, H, W)`` → the field ``(B, H · W)`` in the grid's point order, where
    ``model`` maps inputs to the field at those points, ``(B, H · W)``."""
    views = grid_views(count)
    if count == 1:  # the network alone
        return model(inputs)
    B, _, H, W = inputs.shape
    fields = [v.images_back(model(v.images(inputs)).reshape(B, H, W)) for v in views]
    return torch.stack(fields).mean(0).reshape(B, H * W)
