"""Writes the mesh files of the task scenes and of ``robotplan bench push --shapes mesh``.

Every mesh is built here from trimesh primitives, watertight, in the units its scenes'
``scale`` names. Run from anywhere: ``python tasks/meshes/make_meshes.py``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh
from shapely.geometry import Point, Polygon

HERE = Path(__file__).resolve().parent


def l_bracket() -> trimesh.Trimesh:
    """An L-bracket in millimetres: 200 × 150 mm, bars 60 mm wide, 40 mm thick."""
    outline = Polygon([(0, 0), (200, 0), (200, 60), (60, 60), (60, 150), (0, 150)])
    return trimesh.creation.extrude_polygon(outline, 40.0)


def hex_nut() -> trimesh.Trimesh:
    """A hexagonal nut in millimetres: 140 mm across the corners, a 50 mm bore, 30 mm high."""
    angles = np.arange(6) * np.pi / 3
    outline = Polygon(np.stack((70 * np.cos(angles), 70 * np.sin(angles)), 1))
    return trimesh.creation.extrude_polygon(outline.difference(Point(0, 0).buffer(25, 32)),
                                            30.0)


def arch() -> trimesh.Trimesh:
    """An arch in metres: half of a ring of radii 0.06 and 0.11, 0.05 high."""
    ring = Point(0, 0).buffer(0.11, 24).difference(Point(0, 0).buffer(0.06, 24))
    half = ring.intersection(Polygon([(-0.2, 0), (0.2, 0), (0.2, 0.2), (-0.2, 0.2)]))
    return trimesh.creation.extrude_polygon(half, 0.05)


def mug() -> trimesh.Trimesh:
    """A mug in metres: a cup of radius 0.045 and height 0.10 (walls 6 mm) and a handle, a
    tube of radius 7 mm along a half ellipse in the xz-plane reaching 0.035 m out, its ends
    sunk into the wall (two closed shells)."""
    r_out, r_in, height, floor = 0.045, 0.039, 0.10, 0.008
    profile = np.array([[0, 0], [r_out, 0], [r_out, height], [r_in, height], [r_in, floor],
                        [0, floor]])
    cup = trimesh.creation.revolve(profile, sections=48)
    t = np.linspace(-np.pi / 2, np.pi / 2, 25)
    path = np.stack((r_out - 0.003 + 0.038 * np.cos(t), np.zeros_like(t),
                     height / 2 + 0.03 * np.sin(t)), 1)
    handle = trimesh.creation.sweep_polygon(Point(0, 0).buffer(0.007, 4), path)
    return trimesh.util.concatenate([cup, handle])


MESHES = {"l_bracket.stl": l_bracket, "bench/hex_nut.stl": hex_nut, "bench/arch.ply": arch,
          "bench/mug.obj": mug}

if __name__ == "__main__":
    for name, make in MESHES.items():
        mesh = make()
        assert mesh.is_watertight, name
        (HERE / name).parent.mkdir(exist_ok=True)
        mesh.export(str(HERE / name))
        print(f"{name}: {len(mesh.faces)} triangles, {np.ptp(mesh.vertices, 0).round(4)}")
