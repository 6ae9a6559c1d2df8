"""Mugs and hooks given as mesh files, with what the hanging task reads of a mug and a hook
found from their geometry (not from the parameters of a procedural one).

Frames as the procedural ones (:mod:`robotplan.sdf.mug_hook`): a mug mesh stands on its
bottom, its axis the file's z axis, its handle towards +x in the plane y = 0; a hook mesh's
post stands on the file's z axis, its arm leaving towards +x in the plane y = 0. The lowest
point goes to z = 0.

* the mug's handle opening: the hole of the mug's cross-section y = 0 outside the cup
  (the bounded region free of the mug in that plane, found on the SDF), as the largest
  ellipse about its most interior point that stays in it;
* the hook's arm: its centre line traced from the post outwards, each point the centre of
  the tube's cross-section normal to the line, then simplified to a few straight parts;
  its radius the cross-sections' mean radius.
"""

from __future__ import annotations

from functools import cached_property
from pathlib import Path

import numpy as np
import torch
from torch import Tensor

from robotplan.sdf.grid_sdf import GRID_STEP, GridSDF, mesh_sdf_lattice
from robotplan.sdf.shapes3d import Shape3D

__all__ = ["CLEARANCE", "MeshHook", "MeshMug", "MeshSolidProblem"]

OPENING_STEP = 0.001  # m: the cross-section's pixels when looking for the handle's opening
ARM_STEP = 0.005  # m between traced points of a hook's arm
ARM_TOLERANCE = 0.002  # m: the simplified arm stays this close to the traced line


class MeshSolidProblem(ValueError):
    """A mesh is not a usable mug or hook; ``str(err)`` says why in one line."""


class _MeshSolid(Shape3D):
    def __init__(self, mesh, mesh_file: str | Path, scale: float, step: float = GRID_STEP
                 ) -> None:
        self.mesh_file, self.scale = str(mesh_file), float(scale)
        self.offset = np.array([0.0, 0.0, float(mesh.vertices[:, 2].min())])
        self.mesh = mesh.copy()
        self.mesh.apply_translation(-self.offset)
        self.lattice: GridSDF = mesh_sdf_lattice(self.mesh, Path(mesh_file), scale,
                                                 self.offset, step)

    def sdf(self, p_B: Tensor) -> Tensor:
        return self.lattice.sdf(p_B)

    def aabb(self) -> tuple[np.ndarray, np.ndarray]:
        """Axis-aligned bounding box ``(lo, hi)`` in the shape's frame."""
        return self.mesh.bounds[0].copy(), self.mesh.bounds[1].copy()

    @property
    def height(self) -> float:
        return float(self.mesh.bounds[1, 2])


CLEARANCE = 0.001  # m a mesh mug is read fatter (measured: docs/experiments.md#mesh-clearance)


class MeshMug(_MeshSolid):
    """A mug from a mesh: its SDF (a cached lattice, read ``CLEARANCE`` fatter: the lattice
    and the simulator's pieces of a mesh each stray a millimetre or two from it, and a pose
    found touching the hook would start inside it in pybullet), its handle's opening, its
    reach."""

    def __init__(self, mesh, mesh_file: str | Path, scale: float = 1.0,
                 step: float = GRID_STEP) -> None:
        super().__init__(mesh, mesh_file, scale, step)
        self.x0, self.z0, self.a, self.b = self._find_opening()
        self.radius = self.x0 - self.a  # the opening's wall side: the threading row's bound

    def sdf(self, p_B: Tensor) -> Tensor:
        return self.lattice.sdf(p_B) - CLEARANCE

    def opening(self) -> tuple[float, float, float, float]:
        """``(x0, z0, a, b)``: an ellipse (centre, semi-axes along x and z) inside the
        handle's opening in the plane y = 0."""
        return self.x0, self.z0, self.a, self.b

    @property
    def reach(self) -> float:
        """The farthest point of the mug from its frame's origin (m)."""
        return float(np.linalg.norm(self.mesh.vertices, axis=1).max())

    def _find_opening(self) -> tuple[float, float, float, float]:
        from scipy import ndimage

        lo, hi = self.aabb()
        xs = np.arange(0.0, hi[0] + OPENING_STEP, OPENING_STEP)
        zs = np.arange(lo[2], hi[2] + OPENING_STEP, OPENING_STEP)
        X, Z = np.meshgrid(xs, zs, indexing="ij")
        points = torch.from_numpy(np.stack((X, np.zeros_like(X), Z), -1))
        free = (self.sdf(points) > 0).numpy()
        labels, count = ndimage.label(free)
        edge = set(np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0],
                                             labels[:, -1]])))
        holes = [k for k in range(1, count + 1) if k not in edge]
        if not holes:
            raise MeshSolidProblem("the mug's cross-section y = 0 shows no opening in a "
                                   "handle towards +x: a mug stands on its bottom, its handle "
                                   "towards +x")
        hole = labels == max(holes, key=lambda k: int((labels == k).sum()))
        depth = ndimage.distance_transform_edt(hole) * OPENING_STEP
        ridge = np.argwhere(depth >= depth.max() - OPENING_STEP)  # the most interior points
        i, k = ridge[np.argmin(np.linalg.norm(ridge - ridge.mean(0), axis=1))]
        rows, cols = np.nonzero(hole[:, k])[0], np.nonzero(hole[i, :])[0]
        a = min(i - rows.min(), rows.max() - i) * OPENING_STEP
        b = min(k - cols.min(), cols.max() - k) * OPENING_STEP
        x0, z0 = float(xs[i]), float(zs[k])
        angles = np.linspace(0.0, 2 * np.pi, 64, endpoint=False)
        for shrink in np.linspace(1.0, 0.3, 15):  # the largest such ellipse inside the hole
            ring = np.stack((x0 + shrink * a * np.cos(angles), z0 + shrink * b * np.sin(angles)))
            u = np.clip(np.round(ring[0] / OPENING_STEP).astype(int), 0, len(xs) - 1)
            v = np.clip(np.round((ring[1] - lo[2]) / OPENING_STEP).astype(int), 0, len(zs) - 1)
            if hole[u, v].all():
                return x0, z0, float(shrink * a), float(shrink * b)
        raise MeshSolidProblem("the mug's handle opening is too narrow to thread a hook's arm")


class MeshHook(_MeshSolid):
    """A hook from a mesh: its SDF (a cached lattice), its arm's centre line and radius."""

    def __init__(self, mesh, mesh_file: str | Path, scale: float = 1.0,
                 step: float = GRID_STEP) -> None:
        super().__init__(mesh, mesh_file, scale, step)
        self.post_radius = self._post_radius()
        self._arm, self.rod_radius = self._trace_arm()
        self.post_height = float(self._arm[0, 2])

    def arm_points(self) -> np.ndarray:
        """The arm's centre line ``(parts + 1, 3)``, starting on the post's axis."""
        return self._arm.copy()

    def _post_radius(self) -> float:
        """Half the post's width at a tenth of the hook's height."""
        import trimesh

        lines = trimesh.intersections.mesh_plane(self.mesh, [0, 0, 1],
                                                 [0, 0, 0.1 * self.height])
        points = lines.reshape(-1, 3)
        near = points[np.linalg.norm(points[:, :2], axis=1) < 0.1]
        if len(near) < 3:
            raise MeshSolidProblem("no post on the hook mesh's z axis")
        return float(np.linalg.norm(near[:, :2], axis=1).mean())

    def _section(self, origin: np.ndarray, normal: np.ndarray, near: float) -> np.ndarray:
        """Points ``(n, 3)`` of the mesh's cross-section by a plane, within ``near`` of its
        ``origin``."""
        import trimesh

        lines = trimesh.intersections.mesh_plane(self.mesh, normal, origin)
        points = lines.reshape(-1, 3)
        return points[np.linalg.norm(points - origin, axis=1) < near]

    @cached_property
    def _first(self) -> np.ndarray:
        x = self.post_radius + 0.01
        top = self.mesh.vertices[np.abs(self.mesh.vertices[:, 0] - x) < 0.02]
        if not len(top):
            raise MeshSolidProblem("no arm leaves the hook's post towards +x")
        return np.array([x, 0.0, float(top[:, 2].max())])

    def _trace_arm(self) -> tuple[np.ndarray, float]:
        guess, direction = self._first, np.array([1.0, 0.0, 0.0])
        found: list[np.ndarray] = []
        radii: list[float] = []
        for _ in range(400):
            section = self._section(guess, direction, 0.03)
            if len(section) < 3:
                break
            centre = section.mean(axis=0)
            if found and np.linalg.norm(centre - found[-1]) < ARM_STEP / 4:
                break
            radii.append(float(np.linalg.norm(section - centre, axis=1).mean()))
            if found:
                step = centre - found[-1]
                direction = step / np.linalg.norm(step)
            found.append(centre)
            guess = centre + ARM_STEP * direction
        if len(found) < 3:
            raise MeshSolidProblem("the hook's arm could not be traced from its post "
                                   "towards +x")
        line = np.array(found[:-1] if len(found) > 3 else found)
        root = line[0] - line[0, 0] / max(line[1, 0] - line[0, 0], 1e-9) * (line[1] - line[0])
        line = np.vstack([[0.0, 0.0, root[2]], line])
        return _simplify(line, ARM_TOLERANCE), float(np.median(radii))


def _simplify(line: np.ndarray, tolerance: float) -> np.ndarray:
    """Douglas–Peucker: the polyline's points that keep it within ``tolerance``."""
    a, b = line[0], line[-1]
    d = b - a
    t = np.clip((line - a) @ d / max(d @ d, 1e-18), 0.0, 1.0)
    far = np.linalg.norm(line - (a + t[:, None] * d), axis=1)
    k = int(np.argmax(far))
    if far[k] <= tolerance or len(line) <= 2:
        return np.stack((a, b))
    return np.vstack((_simplify(line[:k + 1], tolerance)[:-1], _simplify(line[k:], tolerance)))
