"""A mesh as the convex pieces a simulator needs for a moving body.

pybullet collides a moving mesh as its convex hull. A convex mesh is its own one piece; any
other is split by V-HACD (pybullet's built-in approximate convex decomposition). The pieces
are written as one Wavefront OBJ with an ``o`` group per piece, in the mesh file's own
units, and cached by the file's content hash, so a mesh is split once per machine.
"""

from __future__ import annotations

import hashlib
import tempfile
from pathlib import Path

from robotplan.base.files import write_atomically
from robotplan.base.quiet import c_output_silenced, import_pybullet
from robotplan.base.resources import cache_dir

__all__ = ["VHACD_RESOLUTION", "convex_pieces_file"]

# voxels of V-HACD's grid: a mug's pieces within 4 mm of it, split in ~5 s
# (measured: docs/experiments.md#mesh-pieces)
VHACD_RESOLUTION = 300_000


def convex_pieces_file(mesh_file: str | Path) -> Path:
    """The OBJ file of ``mesh_file``'s convex pieces (same units and frame as the file)."""
    import trimesh

    raw = Path(mesh_file).read_bytes()
    key = hashlib.sha256(raw + f"|vhacd{VHACD_RESOLUTION}".encode()).hexdigest()[:32]
    out = cache_dir("convex_pieces") / f"{key}.obj"
    if out.is_file():
        return out
    mesh = trimesh.load_mesh(str(mesh_file), force="mesh", process=True)
    if mesh.is_convex:
        write_atomically(out, lambda tmp: tmp.write_text("o piece0\n" + _obj_body(mesh)))
        return out
    pb = import_pybullet()
    with tempfile.TemporaryDirectory() as tmp:
        whole, pieces = Path(tmp) / "whole.obj", Path(tmp) / "pieces.obj"
        mesh.export(str(whole))
        with c_output_silenced():
            pb.vhacd(str(whole), str(pieces), str(Path(tmp) / "log.txt"),
                     resolution=VHACD_RESOLUTION)
        text = pieces.read_text()
    write_atomically(out, lambda tmp: tmp.write_text(text))
    return out


def _obj_body(mesh) -> str:
    lines = [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in mesh.vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in mesh.faces]
    return "\n".join(lines) + "\n"
