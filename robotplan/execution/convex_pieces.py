"""A mesh as the convex pieces a simulator needs for a moving body.

pybullet collides a moving mesh as its convex hull, so a concave mesh goes to it as a
compound of convex pieces. Each piece here is a patch of the mesh's surface (the
triangles whose centres fall in one cube of ``PATCH`` m) with the patch's vertices also
moved ``SKIN`` m inwards along their normals (less where the solid is thinner, so that no
piece comes out on the other side): a thin solid that follows the surface to
within the patch's sagitta (~0.2 mm on a 7 mm handle), where an approximate convex
decomposition (V-HACD) swells a mug's pieces by 2–3 mm and closes most of a handle's
opening (measured: docs/experiments.md#mesh-pieces). The solid is its skin: a body that
only ever meets others from outside needs no more, if the skin is deeper than a body moves
in one time step (4 mm: 1 m/s at 240 Hz).

The pieces are written as one Wavefront OBJ with an ``o`` group per piece, in the mesh
file's own units, cached by the file's content and scale.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np

from robotplan.base.files import write_atomically
from robotplan.base.resources import cache_dir

__all__ = ["PATCH", "SKIN", "convex_pieces_file", "obj_file"]

FORMAT = 2  # changes when the pieces do: older cached ones are not read
PATCH = 0.008  # m: the cube of mesh surface one piece covers
SKIN = 0.004  # m: how thick each piece is below the surface, at most 0.45 of the solid there


def convex_pieces_file(mesh_file: str | Path, scale: float = 1.0) -> Path:
    """The OBJ file of ``mesh_file``'s convex pieces (same units and frame as the file);
    ``scale`` turns the file's units into metres."""
    import trimesh

    raw = Path(mesh_file).read_bytes()
    tag = f"|skin{FORMAT}|{PATCH}|{SKIN}|{scale!r}".encode()
    out = cache_dir("convex_pieces") / f"{hashlib.sha256(raw + tag).hexdigest()[:32]}.obj"
    if out.is_file():
        return out
    mesh = trimesh.load_mesh(str(mesh_file), force="mesh", process=True)
    if mesh.is_convex:
        write_atomically(out, lambda tmp: tmp.write_text("o piece0\n" + _obj_body(mesh)))
        return out
    lines = []
    base = 1
    for k, piece in enumerate(_skin_pieces(mesh, PATCH / scale, SKIN / scale)):
        lines.append(f"o piece{k}")
        lines += [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in piece.vertices]
        lines += [f"f {a + base} {b + base} {c + base}" for a, b, c in piece.faces]
        base += len(piece.vertices)
    write_atomically(out, lambda tmp: tmp.write_text("\n".join(lines) + "\n"))
    return out


def _skin_pieces(mesh, patch: float, skin: float) -> list:
    """Convex hulls of each surface patch and its copy ``skin`` inwards (mesh units)."""
    import trimesh

    cells = np.floor(mesh.triangles_center / patch).astype(np.int64)
    _, group = np.unique(cells, axis=0, return_inverse=True)
    normals = mesh.vertex_normals
    depth = np.minimum(skin, 0.45 * _thickness(mesh, normals, skin / 20))[:, None]
    pieces = []
    for g in range(group.max() + 1):
        vertices = np.unique(mesh.faces[group.ravel() == g].ravel())
        points = np.vstack((mesh.vertices[vertices],
                            mesh.vertices[vertices] - depth[vertices] * normals[vertices]))
        try:
            hull = trimesh.convex.convex_hull(points)
        except Exception:  # a degenerate patch (collinear points): its neighbours cover it
            continue
        if hull.volume > 0:
            pieces.append(hull)
    return pieces


def _thickness(mesh, normals: np.ndarray, gap: float) -> np.ndarray:
    """How far inwards along its normal each vertex sees the mesh's other side ``(V,)``
    (infinite where a ray finds none), hits nearer than ``gap`` (the faces at the vertex
    itself) not counted: a piece reaches at most half-way through."""
    hits, rays, _ = mesh.ray.intersects_location(mesh.vertices, -normals, multiple_hits=True)
    far = np.linalg.norm(hits - mesh.vertices[rays], axis=1)
    keep = far > gap
    out = np.full(len(mesh.vertices), np.inf)
    np.minimum.at(out, rays[keep], far[keep])
    return out


def obj_file(mesh_file: str | Path) -> Path:
    """``mesh_file`` as a Wavefront OBJ (what pybullet reads of any format), cached."""
    import trimesh

    raw = Path(mesh_file).read_bytes()
    out = cache_dir("convex_pieces") / f"{hashlib.sha256(raw).hexdigest()[:32]}-whole.obj"
    if not out.is_file():
        mesh = trimesh.load_mesh(str(mesh_file), force="mesh", process=True)
        write_atomically(out, lambda tmp: tmp.write_text("o whole\n" + _obj_body(mesh)))
    return out


def _obj_body(mesh) -> str:
    lines = [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in mesh.vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in mesh.faces]
    return "\n".join(lines) + "\n"
