"""The arms in the MeshCat playback: each link's visual meshes from the robot folder's URDF,
posed by Drake's forward kinematics at every state; the planned arm ghosted."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from functools import cache
from pathlib import Path

import numpy as np

from robotplan.scene import Scene

__all__ = ["add_arms", "link_visuals"]


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


def add_arms(meshcat, animation, scene: Scene, joints: tuple[dict, dict],
             frames: np.ndarray) -> None:
    """Add every arm of ``scene`` under /plan and /executed and animate it along
    ``joints = (planned, executed)`` (robot → ``(N+1, dof)``) at animation ``frames``."""
    from pydrake.geometry import Mesh, Rgba, Sphere
    from pydrake.math import RigidTransform, RollPitchYaw

    from robotplan.functionals.kinematics import arm_kinematics

    for robot in scene.robots:
        kin = arm_kinematics(robot)
        plant, ctx = kin.arm.plant, kin.arm.context
        visuals = link_visuals(kin.model.urdf_path)
        offset = RigidTransform(list(kin.model.tip.offset))
        for layer, alpha in (("plan", 0.25), ("executed", 1.0)):
            color = Rgba(0.55, 0.35, 0.8, alpha) if layer == "plan" else Rgba(0.8, 0.8, 0.85)
            for link, items in visuals.items():
                for i, (mesh, _xyz, _rpy) in enumerate(items):
                    if mesh.suffix.lower() in (".obj", ".stl", ".dae", ".gltf"):
                        meshcat.SetObject(f"/{layer}/{robot.name}/{link}/{i}", Mesh(str(mesh)),
                                          color)
            meshcat.SetObject(f"/{layer}/{robot.name}/tip", Sphere(robot.tip_radius),
                              Rgba(0.95, 0.8, 0.1, alpha))
            traj = joints[0 if layer == "plan" else 1].get(robot.name)
            if traj is None:
                continue
            for k, q in zip(frames, np.asarray(traj), strict=True):
                plant.SetPositions(ctx, np.asarray(q, dtype=float))
                for link, items in visuals.items():
                    X = plant.EvalBodyPoseInWorld(ctx, plant.GetBodyByName(link))
                    for i, (_mesh, xyz, rpy) in enumerate(items):
                        local = RigidTransform(RollPitchYaw(*rpy), list(xyz))
                        animation.SetTransform(int(k), f"/{layer}/{robot.name}/{link}/{i}",
                                               X @ local)
                tip_body = plant.GetBodyByName(kin.model.tip.link)
                animation.SetTransform(int(k), f"/{layer}/{robot.name}/tip",
                                       plant.EvalBodyPoseInWorld(ctx, tip_body) @ offset)
