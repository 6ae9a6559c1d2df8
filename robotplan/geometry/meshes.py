"""Triangle meshes a user gives: read and checked, and their footprint on the table.

A mesh file (OBJ, STL, PLY, GLB/GLTF, read by trimesh) is scaled to metres and checked: it
must hold triangles, be watertight (inside and outside are defined only then), have a
volume, and fit the workspace. Its *footprint* is its projection onto the table (what a
camera above it sees and what blocks a pusher sliding on the table), simplified to within a
tolerance with its holes and concavities kept.

Every problem raises :class:`MeshProblem` whose text is one line for the user.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from robotplan.geometry.polygons import as_ccw

if TYPE_CHECKING:  # trimesh is imported where a mesh is read: it costs ~1 s at start-up
    import trimesh

__all__ = ["MESH_SUFFIXES", "MeshLimits", "MeshProblem", "footprint_loops", "read_mesh"]

MESH_SUFFIXES = (".obj", ".stl", ".ply", ".glb", ".gltf", ".off")


class MeshProblem(ValueError):
    """A mesh file cannot be used; ``str(err)`` says why in one line."""


@dataclass(frozen=True)
class MeshLimits:
    """What a mesh may be. Far above any table-top object, far below what would take
    minutes to check or gigabytes to hold."""

    max_bytes: int = 64_000_000
    max_triangles: int = 200_000
    max_extent: float = 2.0  # m, after scaling: the table is 1.4 m across
    min_extent: float = 0.002  # m, after scaling: thinner is a sheet, not a solid


def read_mesh(path: Path, scale: float = 1.0, limits: MeshLimits = MeshLimits()
              ) -> trimesh.Trimesh:
    """The mesh in ``path`` scaled by ``scale`` (to metres), checked as the module says."""
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise MeshProblem(f"{path.name}: unknown mesh format {path.suffix or '(none)'!r}; "
                          f"one of {', '.join(MESH_SUFFIXES)}")
    try:
        size = path.stat().st_size
    except FileNotFoundError:
        raise MeshProblem(f"{path}: no such file") from None
    except OSError as err:
        raise MeshProblem(f"{path}: cannot read: {err.strerror}") from None
    if not path.is_file():
        raise MeshProblem(f"{path}: not a file")
    if size > limits.max_bytes:
        raise MeshProblem(f"{path.name}: {size / 1e6:.1f} MB is too large for a mesh (at most "
                          f"{limits.max_bytes / 1e6:g} MB)")
    import trimesh

    try:
        mesh = trimesh.load_mesh(str(path), force="mesh", process=True)
    except Exception as err:  # trimesh raises many kinds for a broken file
        text = " ".join(str(err).split())[:160] or type(err).__name__
        raise MeshProblem(f"{path.name}: not a readable mesh ({text})") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise MeshProblem(f"{path.name}: the mesh holds no triangles")
    if len(mesh.faces) > limits.max_triangles:
        raise MeshProblem(f"{path.name}: {len(mesh.faces)} triangles are too many (at most "
                          f"{limits.max_triangles}); simplify the mesh first")
    mesh.apply_scale(scale)
    extent = float(np.ptp(mesh.vertices, axis=0).max())
    if extent > limits.max_extent:
        raise MeshProblem(f"{path.name}: {extent:.3g} m across after scale {scale:g} is larger "
                          f"than the workspace allows ({limits.max_extent:g} m); is the scale "
                          "right (e.g. 0.001 for millimetres)?")
    if float(np.ptp(mesh.vertices, axis=0).min()) < limits.min_extent:
        raise MeshProblem(f"{path.name}: the mesh is flat (thinner than "
                          f"{limits.min_extent * 1e3:g} mm after scale {scale:g}): a solid is "
                          "needed")
    if not mesh.is_watertight:
        raise MeshProblem(f"{path.name}: the mesh is not watertight (it has open edges), so "
                          "its inside is undefined; close its holes first")
    if mesh.volume <= 0:
        mesh.invert()  # faces wound inwards: the same solid
    if not mesh.volume > (limits.min_extent ** 3):
        raise MeshProblem(f"{path.name}: the mesh encloses no volume (degenerate)")
    return mesh


def footprint_loops(mesh: trimesh.Trimesh, tolerance: float
                    ) -> tuple[np.ndarray, list[np.ndarray]]:
    """The mesh's projection onto the table plane as ``(outer (V, 2), holes [(H, 2)])``,
    counter-clockwise (holes clockwise), in the mesh's x–y coordinates, each vertex within
    ``tolerance`` (m) of the exact outline. Raises MeshProblem when the projection falls
    apart into several pieces (one object rests as one piece)."""
    from shapely import MultiPolygon, Polygon, union_all

    tri = mesh.vertices[mesh.faces][:, :, :2]  # (F, 3, 2)
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    twice_area = np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    keep = twice_area > 1e-14  # faces seen edge-on add nothing to the projection
    shadow = union_all([Polygon(t) for t in tri[keep]], grid_size=tolerance * 1e-3)
    # A union of triangles sharing edges leaves slivers along them: close them, then reopen.
    gap = tolerance * 1e-3
    shadow = shadow.buffer(gap, join_style="mitre").buffer(-gap, join_style="mitre")
    pieces = list(shadow.geoms) if isinstance(shadow, MultiPolygon) else [shadow]
    pieces = [p for p in pieces if p.area > tolerance ** 2]
    if len(pieces) != 1:
        raise MeshProblem(f"the mesh's footprint on the table is {len(pieces)} separate pieces; "
                          "an object must rest as one piece")
    outline = pieces[0].simplify(tolerance, preserve_topology=True)
    outer = as_ccw(np.asarray(outline.exterior.coords)[:-1])
    holes = [as_ccw(np.asarray(r.coords)[:-1])[::-1].copy() for r in outline.interiors
             if Polygon(r).area > tolerance ** 2]
    return outer, holes
