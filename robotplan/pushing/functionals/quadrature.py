"""The quadrature of H_F over the table: a multi-level midpoint rule refined along the
object's path."""

from __future__ import annotations

import torch
from torch import Tensor

from robotplan.functionals.base import Quadrature
from robotplan.sdf import Workspace

__all__ = ["QUADRATURE_COARSE", "QUADRATURE_LEVELS", "phase_quadrature"]


QUADRATURE_COARSE = 0.10
QUADRATURE_LEVELS = ((0.05, 0.05), (0.01, 0.025))
"""The default refinement of :func:`phase_quadrature`: ``(margin, spacing)`` pairs, coarse to
fine; a cell is refined to ``spacing`` when it comes within the object's bounding radius
plus ``margin`` of the object's path.

Fine enough that the worst per-step error of H_t against the 1 cm grid X_h stays below 5 %
on real pushes: the learned flow's error runs in thin ridges from the object's corners to the
table's border, which coarser cells miss (measured: docs/experiments.md#quadrature).
"""


def phase_quadrature(centers: Tensor, bound_radius: float, workspace: Workspace,
                     levels: tuple[tuple[float, float], ...] = QUADRATURE_LEVELS,
                     coarse: float = QUADRATURE_COARSE, dtype: torch.dtype = torch.float32
                     ) -> Quadrature:
    """A fixed multi-level midpoint rule for one phase.

    The workspace is tiled with ``coarse`` cells; level by level, a cell that comes within
    ``bound_radius + margin`` of any of the ``centers (C, 2)`` (e.g. the object's positions
    in the phase's initial guess) is split into square sub-cells of that level's spacing.
    Every point is a cell centre weighted by the cell's area, so the weights sum to the
    workspace area. The default, 10 / 5 / 2.5 cm, uses ~350–650 points for the objects of
    the data ranges and a 10-step push (19,600 for the 1 cm grid X_h).
    """
    cells = Workspace(workspace.center, workspace.size, coarse).points(torch.float64)
    cells, size = cells.reshape(-1, 2), coarse
    centers = centers.to(torch.float64)
    points, weights = [], []
    for margin, spacing in levels:
        # a cell is near when any part of it (half-diagonal ≈ 0.707·size) is within reach
        near = torch.cdist(cells, centers).amin(dim=1) <= bound_radius + margin + 0.7072 * size
        points.append(cells[~near])
        weights.append(torch.full((len(points[-1]),), size**2, dtype=torch.float64))
        ratio = max(1, round(size / spacing))
        offs = (torch.arange(ratio, dtype=torch.float64) + 0.5) * (size / ratio) - size / 2
        oy, ox = torch.meshgrid(offs, offs, indexing="ij")
        sub = torch.stack((ox, oy), dim=-1).reshape(-1, 2)
        cells, size = (cells[near][:, None, :] + sub[None]).reshape(-1, 2), size / ratio
    points.append(cells)
    weights.append(torch.full((len(cells),), size**2, dtype=torch.float64))
    return Quadrature(torch.cat(points).to(dtype), torch.cat(weights).to(dtype))
