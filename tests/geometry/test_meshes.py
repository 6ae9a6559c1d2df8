"""Mesh files as a user gives them: read and scaled, refused in one line when unusable, and
their footprint on the table with holes and concavities kept."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from shapely.geometry import Point, Polygon

from robotplan.geometry.meshes import MeshLimits, MeshProblem, footprint_loops, read_mesh
from robotplan.geometry.polygons import signed_area

L_OUTLINE = [(0, 0), (200, 0), (200, 60), (60, 60), (60, 150), (0, 150)]  # mm


def write(mesh: trimesh.Trimesh, path) -> object:
    mesh.export(str(path))
    return path


def test_an_stl_in_millimetres_is_read_in_metres(tmp_path):
    path = write(trimesh.creation.extrude_polygon(Polygon(L_OUTLINE), 40.0), tmp_path / "l.stl")
    mesh = read_mesh(path, scale=0.001)
    assert np.allclose(np.ptp(mesh.vertices, axis=0), [0.2, 0.15, 0.04])
    assert mesh.volume == pytest.approx((0.2 * 0.06 + 0.06 * 0.09) * 0.04)


def test_the_footprint_keeps_concavities_and_holes(tmp_path):
    plate = Polygon(L_OUTLINE).difference(Point(30, 100).buffer(12, 16))
    mesh = read_mesh(write(trimesh.creation.extrude_polygon(plate, 40.0), tmp_path / "p.ply"),
                     scale=0.001)
    outer, holes = footprint_loops(mesh, tolerance=0.0005)
    assert signed_area(outer) == pytest.approx(0.2 * 0.06 + 0.06 * 0.09, rel=1e-5)
    assert len(outer) == 6  # the L's notch is kept, not filled by a hull
    assert len(holes) == 1 and signed_area(holes[0]) < 0  # holes wind clockwise
    assert abs(signed_area(holes[0])) == pytest.approx(np.pi * 0.012**2, rel=0.05)


def test_the_footprint_is_the_projection_of_parts_above_the_table(tmp_path):
    """A mug's handle, off the table, widens its footprint: what blocks a sliding pusher."""
    cup = trimesh.creation.cylinder(radius=0.04, height=0.1)
    handle = trimesh.creation.box([0.05, 0.01, 0.02])
    handle.apply_translation([0.06, 0.0, 0.02])
    mesh = read_mesh(write(trimesh.util.concatenate([cup, handle]), tmp_path / "m.obj"))
    outer, holes = footprint_loops(mesh, tolerance=0.001)
    assert outer[:, 0].max() == pytest.approx(0.085, abs=1e-6) and not holes


def test_the_simplified_outline_stays_within_the_tolerance(tmp_path):
    disc = trimesh.creation.cylinder(radius=0.08, height=0.03, sections=256)
    mesh = read_mesh(write(disc, tmp_path / "d.stl"))
    for tolerance in (0.0005, 0.002):
        outer, _ = footprint_loops(mesh, tolerance)
        radii = np.linalg.norm(outer, axis=1)
        mids = np.linalg.norm((outer + np.roll(outer, -1, 0)) / 2, axis=1)
        assert radii.max() <= 0.08 + 1e-6 and 0.08 - mids.min() <= tolerance + 1e-6
    assert len(footprint_loops(mesh, 0.002)[0]) < len(footprint_loops(mesh, 0.0005)[0]) < 256


def _one_line(err: pytest.ExceptionInfo) -> str:
    text = str(err.value)
    assert "\n" not in text and len(text) < 300
    return text


def test_unusable_meshes_are_refused_in_one_line(tmp_path):
    box = trimesh.creation.box([0.1, 0.1, 0.05])
    open_box = trimesh.Trimesh(box.vertices, box.faces[:-2])
    cases = [
        ("not watertight", write(open_box, tmp_path / "open.stl"), 1.0, MeshLimits()),
        ("holds no triangles", tmp_path / "empty.obj", 1.0, MeshLimits()),
        ("flat", write(trimesh.creation.box([0.1, 0.1, 0.0005]), tmp_path / "f.stl"), 1.0,
         MeshLimits()),
        ("larger than the workspace", write(box, tmp_path / "b.stl"), 100.0, MeshLimits()),
        ("too many", write(trimesh.creation.icosphere(3, 0.05), tmp_path / "s.stl"), 1.0,
         MeshLimits(max_triangles=1000)),
        ("unknown mesh format", tmp_path / "box.step", 1.0, MeshLimits()),
        ("no such file", tmp_path / "missing.stl", 1.0, MeshLimits()),
        ("holds no triangles", tmp_path / "junk.stl", 1.0, MeshLimits()),
    ]
    (tmp_path / "empty.obj").write_text("# nothing\nv 0 0 0\n")
    (tmp_path / "box.step").write_text("ISO-10303-21;")
    (tmp_path / "junk.stl").write_bytes(b"solid x\n garbage \x00\x01 here\n")
    for words, path, scale, limits in cases:
        with pytest.raises(MeshProblem) as err:
            read_mesh(path, scale, limits)
        assert words in _one_line(err), (words, str(err.value))


def test_a_footprint_in_pieces_is_refused(tmp_path):
    a, b = trimesh.creation.box([0.05, 0.05, 0.05]), trimesh.creation.box([0.05, 0.05, 0.05])
    b.apply_translation([0.2, 0.0, 0.0])
    mesh = read_mesh(write(trimesh.util.concatenate([a, b]), tmp_path / "two.stl"))
    with pytest.raises(MeshProblem, match="2 separate pieces"):
        footprint_loops(mesh, 0.001)
