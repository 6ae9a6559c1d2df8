"""A mesh's exact signed distance, sampled once on a lattice and read back smoothly.

A watertight mesh's SDF is exact at the lattice points: the distance to the nearest point
of its triangles (trimesh), the sign from containment. Containment comes from a flood
fill: a lattice point more than half a step from the surface has the sign of a neighbour
more than half a step from it too (the segment between them cannot cross the surface), so
the points reached from the lattice's boundary that way are outside; only the points
within half a step of the surface are tested by rays. Overlapping closed shells (a handle
sunk into a cup's wall) count as their union.

The lattice is cached on disk by the mesh file's content, its scale and the step, so a mesh
is sampled once per machine (10–20 s for a mug at 3 mm). Between lattice points
the SDF is trilinear (differentiable in the points); beyond the lattice's box, the value
at the nearest box point plus the distance to the box (a lower bound of the true one).
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import torch
from torch import Tensor

from robotplan.sdf.shapes3d import Shape3D

__all__ = ["GRID_STEP", "GridSDF", "mesh_sdf_lattice"]

# a mug's handle (a 7 mm tube) spans several steps; H_hang reads 1 cm; H_coll φ below 7 mm
# (measured: docs/experiments.md#mesh-lattice)
GRID_STEP = 0.003  # m
FORMAT = 2  # changes when the sampling does: older cached lattices are not read
MARGIN = 0.015  # m of lattice around the mesh's bounding box: H_coll reads φ < 7 mm


class GridSDF(Shape3D):
    """φ sampled at ``lo + step · (i, j, k)``, ``values (I, J, K)`` (frame of the shape)."""

    def __init__(self, lo: np.ndarray, step: float, values: np.ndarray) -> None:
        self.lo = np.asarray(lo, dtype=np.float64)
        self.step = float(step)
        self.values = torch.from_numpy(np.ascontiguousarray(values, dtype=np.float64))
        self.hi = self.lo + self.step * (np.array(values.shape) - 1)
        self._cast: dict[torch.dtype, Tensor] = {torch.float64: self.values}

    def sdf(self, p_B: Tensor) -> Tensor:
        lo = torch.as_tensor(self.lo, dtype=p_B.dtype, device=p_B.device)
        hi = torch.as_tensor(self.hi, dtype=p_B.dtype, device=p_B.device)
        inside = torch.minimum(torch.maximum(p_B, lo), hi)
        outside = (p_B - inside).norm(dim=-1)
        u = (inside - lo) / self.step  # lattice coordinates
        top = torch.as_tensor(self.values.shape, dtype=p_B.dtype, device=p_B.device) - 1
        i0 = torch.minimum(u.floor(), top - 1).clamp_min(0)
        f = u - i0  # (..., 3) in [0, 1]
        i0 = i0.long()
        v = self._cast.get(p_B.dtype)
        if v is None:  # once per dtype: H_hang reads the lattice in its model's float32
            v = self._cast[p_B.dtype] = self.values.to(p_B.dtype)
        out = torch.zeros_like(outside)
        for corner in range(8):
            bits = [(corner >> axis) & 1 for axis in range(3)]
            w = torch.ones_like(outside)
            for axis, b in enumerate(bits):
                w = w * (f[..., axis] if b else 1.0 - f[..., axis])
            out = out + w * v[i0[..., 0] + bits[0], i0[..., 1] + bits[1], i0[..., 2] + bits[2]]
        return out + outside


def _cache_key(mesh_file: Path, scale: float, offset: np.ndarray, step: float) -> str:
    h = hashlib.sha256(Path(mesh_file).read_bytes())
    h.update(np.asarray([scale, *offset, step, MARGIN, FORMAT], dtype=np.float64).tobytes())
    return h.hexdigest()[:32]


def mesh_sdf_lattice(mesh, mesh_file: Path, scale: float, offset: np.ndarray,
                     step: float = GRID_STEP) -> GridSDF:
    """The SDF lattice of ``mesh`` (already scaled and moved by ``-offset`` into the shape's
    frame), cached under the key of ``mesh_file``, ``scale``, ``offset`` and ``step``."""
    from robotplan.base.files import write_atomically
    from robotplan.base.resources import cache_dir

    path = cache_dir("sdf_lattices") / f"{_cache_key(mesh_file, scale, offset, step)}.npz"
    if path.is_file():
        with np.load(path) as data:
            return GridSDF(data["lo"], float(data["step"]), data["values"])
    lo = mesh.bounds[0] - MARGIN
    counts = np.ceil((mesh.bounds[1] + MARGIN - lo) / step).astype(int) + 1
    values = _sample(mesh, lo, step, counts)

    def write(tmp: Path) -> None:
        with tmp.open("wb") as f:
            np.savez_compressed(f, lo=lo, step=step, values=values)

    write_atomically(path, write)
    return GridSDF(lo, step, values)


def _sample(mesh, lo: np.ndarray, step: float, counts: np.ndarray) -> np.ndarray:
    """Signed distances ``counts`` shaped at the lattice points (module docstring)."""
    import trimesh
    from scipy import ndimage

    axes = [lo[i] + step * np.arange(counts[i]) for i in range(3)]
    points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    distance = np.empty(len(points))
    for start in range(0, len(points), 50_000):
        chunk = points[start:start + 50_000]
        _, distance[start:start + len(chunk)], _ = trimesh.proximity.closest_point(mesh, chunk)
    distance = distance.reshape(*counts)
    free = distance > 0.55 * step  # half a step, and room for rounding at exactly half
    labels, _ = ndimage.label(free)  # 6-connected: neighbours one step apart
    border = np.unique(np.concatenate([labels[0].ravel(), labels[-1].ravel(),
                                       labels[:, 0].ravel(), labels[:, -1].ravel(),
                                       labels[:, :, 0].ravel(), labels[:, :, -1].ravel()]))
    outside = np.isin(labels, border[border > 0])
    near = ~free
    inside = ~outside & free
    if near.any():
        shells = mesh.split(only_watertight=False) or [mesh]
        flat = points.reshape(*counts, 3)[near]
        hit = np.zeros(len(flat), dtype=bool)
        for shell in shells:
            hit |= trimesh.Trimesh(shell.vertices, shell.faces).contains(flat)
        inside[near] = hit
    return np.where(inside, -distance, distance)
