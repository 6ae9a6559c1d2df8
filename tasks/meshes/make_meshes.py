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


def _cup(r_out: float, height: float, wall: float = 0.006, taper: float = 0.0):
    """A cup revolved from its profile: outer radius ``r_out`` at the rim, ``taper`` less
    at the bottom."""
    r_in = r_out - wall
    profile = np.array([[0, 0], [r_out - taper, 0], [r_out, height], [r_in, height],
                        [r_in - taper * (1 - wall / height), wall], [0, wall]])
    return trimesh.creation.revolve(profile, sections=48)


def _tube(path: np.ndarray, radius: float, sides: int = 8) -> trimesh.Trimesh:
    return trimesh.creation.sweep_polygon(Point(0, 0).buffer(radius, max(sides // 4, 1)), path)


def mug_tapered() -> trimesh.Trimesh:
    """A mug in metres: a cup widening from 0.036 to 0.042 m up to 0.095 m, and a handle
    swept along a half ellipse reaching 0.03 m out."""
    cup = _cup(0.042, 0.095, taper=0.006)
    t = np.linspace(-np.pi / 2, np.pi / 2, 25)
    path = np.stack((0.037 + 0.038 * np.cos(t), np.zeros_like(t), 0.05 + 0.028 * np.sin(t)), 1)
    return trimesh.util.concatenate([cup, _tube(path, 0.006)])


def mug_square_handle() -> trimesh.Trimesh:
    """A mug in metres: a straight cup (radius 0.04, height 0.11) and a square-cornered
    handle, a bracket 1 cm thick and 1.2 cm wide (its opening 0.023 m out from the wall and
    0.05 m high)."""
    cup = _cup(0.04, 0.11)
    bracket = Polygon([(0.035, 0.02), (0.073, 0.02), (0.073, 0.09), (0.035, 0.09)]).difference(
        Polygon([(0.03, 0.03), (0.063, 0.03), (0.063, 0.08), (0.03, 0.08)]))
    handle = trimesh.creation.extrude_polygon(bracket, 0.012)
    handle.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
    handle.apply_translation([0.0, 0.006, 0.0])
    return trimesh.util.concatenate([cup, handle])


def mug_ring_handle() -> trimesh.Trimesh:
    """A mug in metres: a wide low cup (radius 0.048, height 0.08) and a ring handle, a torus
    of radius 0.024 about a point 0.06 m out, sunk into the wall."""
    cup = _cup(0.048, 0.08)
    ring = trimesh.creation.torus(major_radius=0.024, minor_radius=0.005, major_sections=32,
                                  minor_sections=8)
    ring.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
    ring.apply_translation([0.066, 0.0, 0.045])
    return trimesh.util.concatenate([cup, ring])


def hook_square_rod() -> trimesh.Trimesh:
    """A hook in metres: a square post (2.4 cm) 0.30 m high and an arm of square bars, 0.12 m
    rising at 0.15 rad, then 0.04 m at 0.9 rad."""
    post = trimesh.creation.box([0.024, 0.024, 0.30])
    post.apply_translation([0, 0, 0.15])
    parts, start = [post], np.array([0.0, 0.0, 0.295])
    for length, angle in ((0.12, 0.15), (0.04, 0.9)):
        d = np.array([np.cos(angle), 0.0, np.sin(angle)])
        bar = trimesh.creation.box([length + 0.01, 0.01, 0.01])
        bar.apply_transform(trimesh.transformations.rotation_matrix(-angle, [0, 1, 0]))
        bar.apply_translation(start + d * length / 2)
        parts.append(bar)
        start = start + d * length
    return trimesh.util.concatenate(parts)


def hook_curved() -> trimesh.Trimesh:
    """A hook in metres: a round post 0.29 m high and an arm bent along a circular arc (radius
    0.14 m, through 50°) from horizontal, a 5 mm tube."""
    post = trimesh.creation.cylinder(0.012, 0.29, sections=24)
    post.apply_translation([0, 0, 0.145])
    a = np.linspace(0.0, np.radians(50), 24)
    path = np.stack((-0.005 + 0.14 * np.sin(a), np.zeros_like(a),
                     0.285 + 0.14 * (1 - np.cos(a))), 1)
    return trimesh.util.concatenate([post, _tube(path, 0.005)])


MESHES = {"l_bracket.stl": l_bracket, "bench/hex_nut.stl": hex_nut, "bench/arch.ply": arch,
          "bench/mug.obj": mug, "hang/mug_tapered.obj": mug_tapered,
          "hang/mug_square_handle.stl": mug_square_handle,
          "hang/mug_ring_handle.obj": mug_ring_handle, "hang/hook_square_rod.stl": hook_square_rod,
          "hang/hook_curved.obj": hook_curved}

if __name__ == "__main__":
    for name, make in MESHES.items():
        mesh = make()
        assert mesh.is_watertight, name
        (HERE / name).parent.mkdir(exist_ok=True)
        mesh.export(str(HERE / name))
        print(f"{name}: {len(mesh.faces)} triangles, {np.ptp(mesh.vertices, 0).round(4)}")
