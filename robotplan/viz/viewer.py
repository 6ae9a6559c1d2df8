"""MeshCat playback of a plan and its simulated execution: one self-contained HTML page
(Drake ``Meshcat.StaticHtml()``) with the table, the goal region, the executed motion
(solid) and the planned motion (ghosted) on one timeline."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from robotplan.geometry.polygons import triangulate
from robotplan.scene import Scene

__all__ = ["extrude", "write_playback"]

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


def write_playback(scene: Scene, path: Path, plan: dict[str, np.ndarray],
                   executed: dict[str, np.ndarray], fps: float = 12.0,
                   joints: tuple[dict, dict] | None = None,
                   times: np.ndarray | None = None) -> None:
    """``plan`` and ``executed`` map body names to trajectories ``(N+1, 3)`` (objects) or
    ``(N+1, 2)`` (pushers); ``joints`` = (planned, executed) joint trajectories of the
    arms, ``(N+1, dof)`` by robot; ``times`` (s) of the states (default 1/fps apart).
    Writes ``path`` whole or not at all."""
    import logging

    from pydrake.geometry import Box, Meshcat, MeshcatAnimation, Rgba, Sphere

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
    colors = {"object": Rgba(0.95, 0.55, 0.15, 1), "obstacle": Rgba(0.35, 0.35, 0.35, 1),
              "pusher": Rgba(0.95, 0.8, 0.1, 1), "robot": Rgba(0.6, 0.3, 0.8, 1)}
    for spec_list in (scene.objects, scene.obstacles):
        for i, spec in enumerate(spec_list):
            body = scene.bodies[spec.name]
            mesh = extrude(body.shape.outline(), spec.height)
            color = colors[body.role]
            if body.role == "object":  # its own name's colour ("red"), else the palette
                color = Rgba(*OBJECT_COLORS.get(body.name, PALETTE[i % len(PALETTE)]), 1)
            meshcat.SetObject(f"/executed/{body.name}", mesh, color)
            meshcat.SetTransform(f"/executed/{body.name}", _pose(*body.pose))
            if body.name in plan:
                ghost = color
                meshcat.SetObject(f"/plan/{body.name}", mesh,
                                  Rgba(ghost.r(), ghost.g(), ghost.b(), 0.3))
    for p in scene.pushers:
        for layer, alpha in (("executed", 1.0), ("plan", 0.3)):
            c = colors["pusher"]
            meshcat.SetObject(f"/{layer}/{p.name}", Sphere(p.radius),
                              Rgba(c.r(), c.g(), c.b(), alpha))
            meshcat.SetTransform(f"/{layer}/{p.name}", _pose(*p.position, 0.0, p.radius))
    animation = MeshcatAnimation(fps)
    n = len(next(iter(plan.values())))
    frames = (np.arange(n) if times is None
              else np.round(np.asarray(times) * fps).astype(int))
    for layer, trajs in (("plan", plan), ("executed", executed)):
        for name, traj in trajs.items():
            body = scene.bodies[name]
            for k, q in zip(frames, np.asarray(traj), strict=True):
                if body.role == "pusher":
                    X = _pose(q[0], q[1], 0.0, body.top / 2)
                else:
                    X = _pose(q[0], q[1], q[2])
                animation.SetTransform(int(k), f"/{layer}/{name}", X)
    if joints is not None:
        from robotplan.viz.viewer_arms import add_arms

        add_arms(meshcat, animation, scene, joints, frames)
    meshcat.SetAnimation(animation)
    html = meshcat.StaticHtml()
    write_atomically(path, lambda tmp: tmp.write_text(html))
