"""The arms in the MeshCat playback, posed by Drake's forward kinematics at every state: the
executed arm with each link's visual meshes from the robot folder's URDF, a planned arm
(ghost) as translucent rods between its links' frames, so each mesh is embedded once; on
both, the tool (a rod from the flange to the tip sphere) and the tip."""

from __future__ import annotations

import itertools
import xml.etree.ElementTree as ET
from functools import cache
from pathlib import Path

import numpy as np

from robotplan.base.quiet import drake_quiet
from robotplan.scene import Scene

__all__ = ["add_arms", "link_visuals"]

ROD_RADIUS = 0.02  # m: a planned arm's links
TOOL_RADIUS = 0.008  # m: the rod that carries the tip


@cache
def link_visuals(urdf: Path) -> dict[str, list[tuple[Path, tuple, tuple]]]:
    """Link name → [(mesh file, xyz, rpy)] of the URDF's visual meshes."""
    out: dict[str, list[tuple[Path, tuple, tuple]]] = {}
    for link in ET.parse(urdf).getroot().iter("link"):
        for visual in link.iter("visual"):
            mesh = visual.find("geometry/mesh")
            if mesh is None:
                continue
            origin = visual.find("origin")
            xyz = tuple(map(float, (origin.get("xyz", "0 0 0") if origin is not None
                                    else "0 0 0").split()))
            rpy = tuple(map(float, (origin.get("rpy", "0 0 0") if origin is not None
                                    else "0 0 0").split()))
            out.setdefault(link.get("name"), []).append(
                (urdf.parent / mesh.get("filename"), xyz, rpy))
    return out


def _rod(d: np.ndarray):
    """The transform that places a z-axis cylinder centred at the origin along the segment
    from the origin to ``d``."""
    from pydrake.math import RigidTransform, RotationMatrix

    length = float(np.linalg.norm(d))
    z = d / length if length > 1e-9 else np.array([0.0, 0.0, 1.0])
    R = RotationMatrix.MakeFromOneVector(z, 2)
    return RigidTransform(R, d / 2), length


def add_arms(meshcat, animation, scene: Scene, layer: str, joints: dict[str, np.ndarray],
             frames: np.ndarray, ghost: bool) -> None:
    """Add the arms of ``scene`` that have ``joints`` (robot → ``(M+1, dof)``) under
    ``/<layer>`` and animate them at animation ``frames``."""
    from pydrake.geometry import Cylinder, Mesh, Rgba, Sphere
    from pydrake.math import RigidTransform, RollPitchYaw

    from robotplan.functionals.kinematics import arm_kinematics

    alpha = 0.3 if ghost else 1.0
    for robot in scene.robots:
        traj = joints.get(robot.name)
        if traj is None:
            continue
        kin = arm_kinematics(robot)
        plant, ctx = kin.arm.plant, kin.arm.context
        visuals = link_visuals(kin.model.urdf_path)
        root = f"/{layer}/{robot.name}"
        links = list(visuals)
        # parts: (path, link, transform in the link frame)
        parts: list[tuple[str, str, RigidTransform]] = []
        if ghost:  # rods from each link's frame to the next one's, fixed in the first
            plant.SetPositions(ctx, kin.q0)
            poses = [plant.EvalBodyPoseInWorld(ctx, plant.GetBodyByName(n)) for n in links]
            color = Rgba(0.55, 0.35, 0.8, alpha)
            for k, (a, b) in enumerate(itertools.pairwise(poses)):
                X, length = _rod(a.inverse() @ b.translation())
                if length > 1e-3:
                    meshcat.SetObject(f"{root}/rod{k}", Cylinder(ROD_RADIUS, length), color)
                    parts.append((f"{root}/rod{k}", links[k], X))
        else:
            for link, items in visuals.items():
                for i, (mesh, xyz, rpy) in enumerate(items):
                    if mesh.suffix.lower() in (".obj", ".stl", ".dae", ".gltf"):
                        with drake_quiet():  # an OBJ's missing material file: grey anyway
                            meshcat.SetObject(f"{root}/{link}/{i}", Mesh(str(mesh)),
                                              Rgba(0.8, 0.8, 0.85, 1.0))
                        parts.append((f"{root}/{link}/{i}", link,
                                      RigidTransform(RollPitchYaw(*rpy), list(xyz))))
        offset = np.asarray(kin.model.tip.offset, dtype=float)
        X_tool, length = _rod(offset)
        tool_color = Rgba(0.3, 0.3, 0.3, alpha)
        meshcat.SetObject(f"{root}/tool", Cylinder(TOOL_RADIUS, max(length, 1e-3)), tool_color)
        meshcat.SetObject(f"{root}/tip", Sphere(robot.tip_radius), Rgba(0.95, 0.8, 0.1, alpha))
        flange = kin.model.tip.link
        parts += [(f"{root}/tool", flange, X_tool),
                  (f"{root}/tip", flange, RigidTransform(list(offset)))]
        for k, q in zip(frames, np.asarray(traj), strict=True):
            plant.SetPositions(ctx, np.asarray(q, dtype=float))
            X_link = {}
            for path, link, local in parts:
                if link not in X_link:
                    X_link[link] = plant.EvalBodyPoseInWorld(ctx, plant.GetBodyByName(link))
                animation.SetTransform(int(k), path, X_link[link] @ local)
