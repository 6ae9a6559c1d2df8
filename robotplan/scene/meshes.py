"""Mesh shapes of a scene file: ``shape: {type: mesh, file: meshes/bracket.stl, scale: 0.001}``.

The file is read relative to the scene file's folder and must stay inside it (no URL, no
``..`` out of it). In a pushing scene the mesh becomes its footprint, a
:class:`~robotplan.sdf.mesh_footprint.MeshFootprint`, and its body's height the mesh's own;
the 2D planner then runs on it as on any polygon.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Literal

import numpy as np

from robotplan.geometry.meshes import MeshProblem, footprint_loops, read_mesh
from robotplan.geometry.polygons import area_centroid, signed_area
from robotplan.scene.limits import MAX_POLYGON_VERTICES
from robotplan.scene.reader import SchemaError

if TYPE_CHECKING:
    import trimesh

    from robotplan.scene.schema import Scene

__all__ = ["MeshShape", "MeshSolid", "load_mesh_shape", "mesh_footprint", "mesh_path",
           "resolve_mesh_footprints", "resolve_mesh_solids"]

# a mesh within 0.5 % of its footprint's prism volume is that prism; the footprint's default
# tolerance: docs/experiments.md#mesh-footprint
PRISM_SLACK = 0.005
_URL = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*://")


@dataclass(frozen=True)
class MeshShape:
    """A body given as a mesh file. ``scale`` turns the file's units into metres (0.001 for
    millimetres); ``tolerance`` (m) is how far the footprint's simplified outline may stray
    from the mesh's exact one."""

    file: str
    scale: float = field(default=1.0, metadata={"positive": True})
    tolerance: float = field(default=0.001, metadata={"positive": True})
    type: Literal["mesh"] = "mesh"

    def check(self) -> tuple[str, str] | None:
        if _URL.match(self.file):
            return "file", "must be a path beside the scene file, not a URL"
        if self.tolerance > 0.01:
            return "tolerance", "at most 0.01 m: coarser outlines lose the object's shape"
        return None


def mesh_path(shape: MeshShape, scene_file: Path) -> Path:
    """The absolute path of ``shape.file``, relative to the scene file's folder and inside
    it. Raises SchemaError (field ``file``)."""
    folder = scene_file.resolve().parent
    path = (folder / shape.file).resolve()
    if not path.is_relative_to(folder):
        raise SchemaError("file", f"{shape.file!r} lies outside the scene's folder {folder}; "
                          "keep meshes beside the scene file")
    return path


def load_mesh_shape(shape: MeshShape, scene_file: Path) -> tuple[trimesh.Trimesh, Path]:
    """The checked, scaled mesh of ``shape`` and its file's absolute path. Raises
    SchemaError (field ``file``)."""
    path = mesh_path(shape, scene_file)
    try:
        return read_mesh(path, shape.scale), path
    except MeshProblem as err:
        raise SchemaError("file", str(err)) from None


@contextmanager
def _under(where: str) -> Iterator[None]:
    """Re-raise a SchemaError of a shape's field as the field under ``where``."""
    try:
        yield
    except SchemaError as err:
        raise SchemaError(f"{where}.{err.field}", err.message) from None


def mesh_footprint(shape: MeshShape, scene_file: Path):
    """``(MeshFootprint, height)`` of a mesh shape in a scene file. Raises SchemaError."""
    from robotplan.sdf.mesh_footprint import MeshFootprint

    mesh, path = load_mesh_shape(shape, scene_file)
    try:
        outer, holes = footprint_loops(mesh, shape.tolerance)
    except MeshProblem as err:
        raise SchemaError("file", str(err)) from None
    count = len(outer) + sum(len(h) for h in holes)
    if count > MAX_POLYGON_VERTICES:
        raise SchemaError("tolerance", f"the footprint keeps {count} vertices at tolerance "
                          f"{shape.tolerance:g} m; at most {MAX_POLYGON_VERTICES}: raise it")
    centre = area_centroid([outer, *holes])
    z0 = float(mesh.vertices[:, 2].min())

    def loop(points: np.ndarray) -> tuple[tuple[float, float], ...]:
        return tuple((float(x), float(y)) for x, y in points - centre)

    height = float(mesh.vertices[:, 2].max()) - z0
    area = signed_area(outer) + sum(signed_area(h) for h in holes)  # holes: negative
    extruded = area * height
    footprint = MeshFootprint(vertices=loop(outer), holes=tuple(loop(h) for h in holes),
                              mesh_file=str(path), scale=shape.scale,
                              mesh_offset=(float(centre[0]), float(centre[1]), z0),
                              prism=abs(mesh.volume - extruded) < PRISM_SLACK * extruded)
    return footprint, height


def resolve_mesh_footprints(scene: Scene, scene_file: Path) -> Scene:
    """``scene`` with every mesh object, obstacle and goal region replaced by its footprint
    (objects and obstacles also take the mesh's height). Raises SchemaError naming the
    field."""
    made: dict[MeshShape, tuple] = {}

    def resolved(shape: MeshShape, where: str):
        if shape not in made:
            with _under(where):
                made[shape] = mesh_footprint(shape, scene_file)
        return made[shape]

    def bodies(group: str) -> list:
        out = []
        for i, body in enumerate(getattr(scene, group)):
            if isinstance(body.shape, MeshShape):
                footprint, height = resolved(body.shape, f"{group}[{i}].shape")
                body = replace(body, shape=footprint, height=height)
            out.append(body)
        return out

    changes: dict = {"objects": bodies("objects"), "obstacles": bodies("obstacles")}
    region = getattr(scene.goal, "region", None)
    if region is not None and isinstance(region.shape, MeshShape):
        footprint, _ = resolved(region.shape, "goal.region.shape")
        changes["goal"] = replace(scene.goal, region=replace(region, shape=footprint))
    return replace(scene, **changes)


@dataclass(frozen=True)
class MeshSolid:
    """A hang scene's mug or hook given as a mesh, resolved: the file's absolute path, its
    scale and which of the two it is. ``solid()`` is the :class:`MeshMug` or
    :class:`MeshHook` the hanging task reads."""

    file: str
    scale: float
    role: Literal["mug", "hook"]
    type: Literal["mesh"] = "mesh"

    def solid(self):
        return _solid(self.file, self.scale, self.role)


@lru_cache(maxsize=16)
def _solid(file: str, scale: float, role: str):
    from robotplan.geometry.meshes import read_mesh
    from robotplan.sdf.mesh_solids import MeshHook, MeshMug

    kind = MeshMug if role == "mug" else MeshHook
    return kind(read_mesh(Path(file), scale), file, scale)


def resolve_mesh_solids(scene: Scene, scene_file: Path) -> Scene:
    """A hang scene with its mesh mug (the object) and mesh hook (the obstacle) resolved
    and checked: readable, and with a handle's opening or an arm found. Raises SchemaError
    naming the field."""
    from robotplan.sdf.mesh_solids import MeshSolidProblem

    def resolved(group: str, role: str) -> list:
        out = []
        for i, body in enumerate(getattr(scene, group)):
            if isinstance(body.shape, MeshShape):
                with _under(f"{group}[{i}].shape"):
                    spec = MeshSolid(str(mesh_path(body.shape, scene_file)), body.shape.scale,
                                     role)
                    try:
                        spec.solid()  # reads and checks the mesh, finds the opening or arm
                    except (MeshProblem, MeshSolidProblem) as err:
                        raise SchemaError("file", str(err)) from None
                body = replace(body, shape=spec)
            out.append(body)
        return out

    return replace(scene, objects=resolved("objects", "mug"),
                   obstacles=resolved("obstacles", "hook"))
