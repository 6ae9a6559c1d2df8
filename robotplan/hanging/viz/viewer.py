"""MeshCat playback of a hang: the hook, the mug carried from where it stands on the table
to the pose the optimiser found (ghosted there), then its simulated drop."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np

from robotplan.sdf.mesh_solids import MeshHook, MeshMug
from robotplan.sdf.mug_hook import Hook, Mug

__all__ = ["hang_meshes", "write_hang_playback"]

CARRY_S = 1.5  # seconds of the (kinematic) carry from the table to the found pose


def _capsules(points: np.ndarray, radius: float) -> list:
    import trimesh

    out = []
    for a, b in itertools.pairwise(points):
        length = float(np.linalg.norm(b - a))
        T = trimesh.geometry.align_vectors([0, 0, 1], (b - a) / length)
        T[:3, 3] = (a + b) / 2
        out.append(trimesh.creation.capsule(height=length, radius=radius, count=[16, 16],
                                            transform=T))
    return out


def hang_meshes(mug: Mug | MeshMug, hook: Hook | MeshHook) -> tuple[list, list]:
    """Trimesh parts of the mug (cup revolved from its profile, handle capsules; a mesh mug
    its mesh) and of the hook (post, arm capsules; a mesh hook its mesh), each in its own
    frame."""
    return _mug_meshes(mug), _hook_meshes(hook)


def _mug_meshes(mug: Mug | MeshMug) -> list:
    import trimesh

    if isinstance(mug, MeshMug):
        return [mug.mesh]
    r, h, w = mug.radius, mug.height, mug.wall
    cup = trimesh.creation.revolve([(0.0, 0.0), (r, 0.0), (r, h), (r - w, h), (r - w, w),
                                    (0.0, w)], sections=48)
    return [cup, *_capsules(mug.handle_points(), mug.handle_radius)]


def _hook_meshes(hook: Hook | MeshHook) -> list:
    import trimesh

    if isinstance(hook, MeshHook):
        return [hook.mesh]
    post = trimesh.creation.cylinder(hook.post_radius, hook.post_height, sections=32)
    post.apply_translation([0, 0, hook.post_height / 2])
    return [post, *_capsules(hook.arm_points(), hook.rod_radius)]


def _drake_mesh(part):
    from pydrake.geometry import SurfaceTriangle, TriangleSurfaceMesh

    return TriangleSurfaceMesh([SurfaceTriangle(*map(int, f)) for f in part.faces],
                               [np.asarray(v, dtype=float) for v in part.vertices])


def _transform(X: np.ndarray):
    from pydrake.common.eigen_geometry import Quaternion
    from pydrake.math import RigidTransform

    q = np.asarray(X[3:], dtype=float)
    return RigidTransform(Quaternion(q / np.linalg.norm(q)), np.asarray(X[:3], dtype=float))


def write_hang_playback(mug: Mug, hook: Hook, X_WH: np.ndarray, X_WM_start: np.ndarray,
                        X_WM_found: np.ndarray, drop: list[tuple[float, np.ndarray]],
                        path: Path, fps: float = 30.0) -> None:
    """One self-contained page: hook at ``X_WH``, the mug from ``X_WM_start`` carried to
    ``X_WM_found`` (shown ghosted there all along), then the drop ``[(t, X_WM)]``. Poses are
    ``(7,)`` (x, y, z, qw, qx, qy, qz) in the world; written whole or not at all."""
    import logging

    from pydrake.geometry import Box, Meshcat, MeshcatAnimation, Rgba

    from robotplan.base.files import write_atomically
    from robotplan.base.quiet import drake_quiet

    with drake_quiet(logging.WARNING):
        meshcat = Meshcat()
    meshcat.SetProperty("/Grid", "visible", False)
    meshcat.SetProperty("/Axes", "visible", False)
    centre = np.asarray(X_WH[:3], dtype=float) + np.array([0.05, 0.0, 0.2])
    meshcat.SetCameraPose(centre + np.array([0.55, -0.65, 0.3]), centre)
    meshcat.SetObject("/table", Box(1.0, 1.0, 0.02), Rgba(0.85, 0.85, 0.82, 1))
    meshcat.SetTransform("/table", _transform(np.array([*X_WH[:2], -0.0101, 1, 0, 0, 0])))
    mug_parts, hook_parts = hang_meshes(mug, hook)
    for i, part in enumerate(hook_parts):
        meshcat.SetObject(f"/hook/part{i}", _drake_mesh(part), Rgba(0.35, 0.35, 0.35, 1))
    meshcat.SetTransform("/hook", _transform(X_WH))
    for name, alpha in (("mug", 1.0), ("found", 0.3)):
        for i, part in enumerate(mug_parts):
            meshcat.SetObject(f"/{name}/part{i}", _drake_mesh(part),
                              Rgba(0.2, 0.45, 0.85, alpha))
    meshcat.SetTransform("/found", _transform(X_WM_found))
    animation = MeshcatAnimation(fps)
    carry = max(2, round(CARRY_S * fps))
    lift = np.array(X_WM_start, dtype=float)
    for k in range(carry + 1):  # up, across and turned: a straight blend, then the drop
        s = 0.5 - 0.5 * math.cos(math.pi * k / carry)
        X = (1 - s) * lift + s * np.asarray(X_WM_found, dtype=float)
        animation.SetTransform(k, "/mug", _transform(X))
    for t, X in drop:
        animation.SetTransform(carry + round(t * fps), "/mug", _transform(np.asarray(X)))
    meshcat.SetAnimation(animation)
    html = meshcat.StaticHtml()
    write_atomically(Path(path), lambda tmp: tmp.write_text(html))
