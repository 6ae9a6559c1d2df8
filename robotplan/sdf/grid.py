"""The workspace grid X_h on which SDFs are rendered and functionals integrated (paper §5.3)."""

from __future__ import annotations

from dataclasses import dataclass, field

import torch
from torch import Tensor

__all__ = ["Workspace"]


@dataclass(frozen=True)
class Workspace:
    """Square table region ``center ± size / 2`` sampled every ``resolution`` metres.

    Grid points are cell centres: with the defaults (1.4 m, 1 cm) X_h is 140 × 140.
    """

    center: tuple[float, float] = (0.0, 0.0)
    size: tuple[float, float] = field(default=(1.4, 1.4), metadata={"positive": True})
    resolution: float = field(default=0.01, metadata={"positive": True})

    def check(self) -> tuple[str, str] | None:
        if self.resolution > min(self.size):
            return "resolution", f"must not exceed the workspace size {list(self.size)}"
        return None

    @property
    def shape(self) -> tuple[int, int]:
        """``(H, W)``: rows along y, columns along x."""
        return (round(self.size[1] / self.resolution), round(self.size[0] / self.resolution))

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """``(x_min, x_max, y_min, y_max)``."""
        cx, cy = self.center
        w, h = self.size
        return (cx - w / 2, cx + w / 2, cy - h / 2, cy + h / 2)

    def points(self, dtype: torch.dtype = torch.float32) -> Tensor:
        """X_h as ``(H, W, 2)`` table-frame points, ``[i, j] = (x_j, y_i)``."""
        x0, _, y0, _ = self.bounds
        rows, cols = self.shape
        r = self.resolution
        xs = x0 + (torch.arange(cols, dtype=torch.float64) + 0.5) * r
        ys = y0 + (torch.arange(rows, dtype=torch.float64) + 0.5) * r
        gy, gx = torch.meshgrid(ys, xs, indexing="ij")
        return torch.stack((gx, gy), dim=-1).to(dtype)

    @property
    def cell_area(self) -> float:
        return self.resolution**2
