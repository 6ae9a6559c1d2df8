"""MeshCat playback of plans and their simulated execution: one self-contained HTML page
(Drake ``Meshcat.StaticHtml()``) with the table, the goal region and layers on one
timeline: the executed motion (solid), the plan and each re-plan (ghosted, each shown from
the time it was made until the next one; the MeshCat controls switch a layer off)."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robotplan.geometry.polygons import triangulate
from robotplan.scene import Scene
from robotplan.sdf.mesh_footprint import MeshFootprint

__all__ = ["GHOST_ALPHA", "Layer", "extrude", "write_playback"]

GHOST_ALPHA = 0.3  # opacity of planned (ghosted) bodies

os.environ.setdefault("DRAKE_ALLOW_NETWORK", "meshcat")


def extrude(outline: np.ndarray, height: float, z0: float = 0.0):
    """A closed TriangleSurfaceMesh of a footprint ``(V, 2)`` extruded from z0 to z0+height."""
    from pydrake.geometry import SurfaceTriangle, TriangleSurfaceMesh

    from robotplan.geometry.polygons import as_ccw

    ring = as_ccw(outline)
    n = len(ring)
    verts = [np.array([x, y, z0]) for x, y in ring] + [np.array([x, y, z0 + height])
                                                        for x, y in ring]
    index = {tuple(np.round(v, 12)): i for i, v in enumerate(ring)}
    tris = []
    for tri in triangulate(ring):
        ids = [index[tuple(np.round(v, 12))] for v in tri]
        tris.append(SurfaceTriangle(ids[0] + n, ids[1] + n, ids[2] + n))  # top, CCW up
        tris.append(SurfaceTriangle(ids[2], ids[1], ids[0]))  # bottom, facing down
    for i in range(n):
        j = (i + 1) % n
        tris.append(SurfaceTriangle(i, j, j + n))
        tris.append(SurfaceTriangle(i, j + n, i + n))
    return TriangleSurfaceMesh(tris, verts)


def _pose(x: float, y: float, yaw: float, z: float = 0.0):
    from pydrake.math import RigidTransform, RollPitchYaw

    return RigidTransform(RollPitchYaw(0.0, 0.0, yaw), [x, y, z])


# objects named after a colour get it; the others take the palette in scene order
OBJECT_COLORS = {"red": (0.85, 0.2, 0.2), "blue": (0.2, 0.4, 0.9), "green": (0.2, 0.7, 0.3),
                 "yellow": (0.95, 0.85, 0.2), "orange": (0.95, 0.55, 0.15),
                 "purple": (0.6, 0.3, 0.8)}
PALETTE = ((0.95, 0.55, 0.15), (0.2, 0.4, 0.9), (0.85, 0.2, 0.2), (0.2, 0.7, 0.3))


@dataclass
class Layer:
    """One motion on the timeline, drawn under ``/<name>``: ``tracks`` map body names to
    ``(M+1, 3)`` object poses or ``(M+1, 2)`` pusher positions, ``joints`` robots to
    ``(M+1, dof)`` angles, at ``times (M+1,)`` s. A ghost is translucent; ``shown`` =
    (from, until) s limits when it is visible (None: always)."""

    name: str
    times: np.ndarray
    tracks: dict[str, np.ndarray]
    joints: dict[str, np.ndarray] = field(default_factory=dict)
    ghost: bool = True
    shown: tuple[float, float | None] | None = None


def write_playback(scene: Scene, path: Path, layers: list[Layer], fps: float = 12.0) -> None:
    """Write the page of ``layers`` over ``scene`` to ``path``, whole or not at all.
    Bodies without a track in any layer (obstacles, objects never moved) are drawn once,
    at their pose in the scene."""
    import logging

    from pydrake.geometry import Box, Meshcat, MeshcatAnimation, Rgba

    from robotplan.base.files import write_atomically
    from robotplan.base.quiet import drake_quiet

    with drake_quiet(logging.WARNING):  # no "Meshcat listening at …": nothing is served
        meshcat = Meshcat()
    meshcat.SetProperty("/Grid", "visible", False)
    meshcat.SetProperty("/Axes", "visible", False)
    meshcat.SetCameraPose(np.array([0.0, -1.25, 1.05]), np.array([0.0, 0.0, 0.0]))
    ws = scene.workspace
    meshcat.SetObject("/table", Box(ws.size[0], ws.size[1], 0.02), Rgba(0.85, 0.85, 0.82, 1))
    meshcat.SetTransform("/table", _pose(*ws.center, 0.0, -0.0101))
    if scene.goal_region is not None:
        g = scene.goal_region
        meshcat.SetObject("/goal", extrude(g.shape.outline(), 0.002), Rgba(0.2, 0.8, 0.3, 0.5))
        meshcat.SetTransform("/goal", _pose(*g.pose))
    moved = {name for layer in layers for name in layer.tracks}
    animation = MeshcatAnimation(fps)
    for layer in layers:
        _add_layer(meshcat, animation, scene, layer, fps)
    for name in (*(o.name for o in scene.objects), *(o.name for o in scene.obstacles)):
        if name not in moved:
            body = scene.bodies[name]
            meshcat.SetObject(f"/scene/{name}", _body_mesh(scene, name), _color(scene, name))
            meshcat.SetTransform(f"/scene/{name}", _pose(*body.pose))
    meshcat.SetAnimation(animation)
    html = meshcat.StaticHtml()
    write_atomically(path, lambda tmp: tmp.write_text(html))


def _body_mesh(scene: Scene, name: str):
    """A body's surface in its frame: a mesh object's own mesh, else its footprint
    extruded."""
    spec = next(o for o in (*scene.objects, *scene.obstacles) if o.name == name)
    shape = scene.bodies[name].shape
    if isinstance(shape, MeshFootprint):
        return _mesh_surface(shape)
    return extrude(shape.outline(), spec.height)


def _mesh_surface(shape: MeshFootprint):
    """The mesh of a mesh footprint, scaled and placed in the footprint's frame."""
    import trimesh
    from pydrake.geometry import SurfaceTriangle, TriangleSurfaceMesh

    mesh = trimesh.load_mesh(shape.mesh_file, force="mesh")
    vertices = mesh.vertices * shape.scale - np.asarray(shape.mesh_offset)
    return TriangleSurfaceMesh([SurfaceTriangle(*map(int, f)) for f in mesh.faces],
                               list(vertices))


def _color(scene: Scene, name: str, alpha: float = 1.0):
    """An object's colour (its own name's, "red", else the palette in scene order), the
    obstacles' grey, the pushers' yellow."""
    from pydrake.geometry import Rgba

    role = scene.bodies[name].role
    if role == "object":
        i = [o.name for o in scene.objects].index(name)
        rgb = OBJECT_COLORS.get(name, PALETTE[i % len(PALETTE)])
    else:
        rgb = {"obstacle": (0.35, 0.35, 0.35), "pusher": (0.95, 0.8, 0.1)}[role]
    return Rgba(*rgb, alpha)


def _add_layer(meshcat, animation, scene: Scene, layer: Layer, fps: float) -> None:
    from pydrake.geometry import Sphere

    alpha = GHOST_ALPHA if layer.ghost else 1.0
    frames = np.round(np.asarray(layer.times) * fps).astype(int)
    root = f"/{layer.name}"
    for name, traj in layer.tracks.items():
        body = scene.bodies[name]
        if body.role == "pusher":
            meshcat.SetObject(f"{root}/{name}", Sphere(body.shape.radius),
                              _color(scene, name, alpha))
        else:
            meshcat.SetObject(f"{root}/{name}", _body_mesh(scene, name),
                              _color(scene, name, alpha))
        for k, q in zip(frames, np.asarray(traj), strict=True):
            X = (_pose(q[0], q[1], 0.0, body.top / 2) if body.role == "pusher"
                 else _pose(q[0], q[1], q[2]))
            animation.SetTransform(int(k), f"{root}/{name}", X)
    if layer.joints:
        from robotplan.viz.viewer_arms import add_arms

        add_arms(meshcat, animation, scene, layer.name, layer.joints, frames, layer.ghost)
    if layer.shown is not None:
        start, until = layer.shown
        first = round(start * fps)
        if first > 0:
            animation.SetProperty(0, root, "visible", False)
        animation.SetProperty(first, root, "visible", True)
        if until is not None:
            animation.SetProperty(round(until * fps), root, "visible", False)
