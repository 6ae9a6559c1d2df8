"""The MuJoCo world of mug hanging: the drop test of :mod:`robotplan.hanging.execution.drop`
on the bodies of the pybullet world (:class:`~robotplan.hanging.execution.world.HangWorld`)
built as a MuJoCo model.

The ground is a plane at z = 0; the hook a body fixed to the world at the origin; the mug a
free body whose frame is the mug's frame. A procedural mug or hook is the boxes, cylinders
and capsules of :mod:`robotplan.hanging.execution.parts` (MuJoCo's own primitives); a mesh
mug or hook the convex pieces of its mesh
(:func:`robotplan.execution.convex_pieces.convex_pieces_file`), one mesh geom per piece,
which MuJoCo collides as their convex hulls. The mug weighs ``physics.mug_mass``, its inertia
MuJoCo's of its geoms scaled to that mass, its centre of mass the geoms' (a procedural mug)
or the mesh's solid centre of mass (a mesh mug), as pybullet places it.

Every geom carries the friction coefficient ``physics.friction²`` at equal priority, so the
mug–hook and mug–ground contacts get pybullet's product of the two bodies' coefficients. The
mug's geoms report contacts out to ``TOUCH`` (their margin) that act only once they
penetrate (their gap as large): the mug *touches* a body within ``TOUCH``, and starts in
collision when a contact with the hook is deeper than ``physics.start_penetration``.
The options (integrator, elliptic friction cones) are the pushing world's
(:func:`robotplan.execution.mujoco_world.mujoco_spec`).
"""

from __future__ import annotations

import numpy as np

from robotplan.execution.convex_pieces import convex_pieces_file
from robotplan.execution.mujoco_model import mujoco_spec, sliding
from robotplan.execution.solids import read_pieces
from robotplan.hanging.execution.drop import HANG_PHYSICS, DropTest, HangPhysics
from robotplan.hanging.execution.parts import hook_parts, mug_parts
from robotplan.sdf.mesh_solids import MeshHook, MeshMug
from robotplan.sdf.mug_hook import Hook, Mug

__all__ = ["TOUCH", "MujocoHangWorld"]

TOUCH = 0.001  # m: the mug touches a body this close to it (contacts reported, not acting)


class MujocoHangWorld(DropTest):
    """A MuJoCo world with the ground, one static hook at the origin and one mug (see the
    module docstring); the interface of
    :class:`~robotplan.hanging.execution.world.HangWorld`."""

    def __init__(self, hook: Hook | MeshHook, mug: Mug | MeshMug,
                 physics: HangPhysics = HANG_PHYSICS) -> None:
        import mujoco

        self.mj, self.physics = mujoco, physics
        self.mug_height = mug.height
        spec = mujoco_spec(physics.timestep, physics.gravity)
        mu = physics.friction * physics.friction
        common = dict(friction=sliding(mu), priority=0)
        spec.worldbody.add_geom(name="ground", type=mujoco.mjtGeom.mjGEOM_PLANE,
                                size=[0.0, 0.0, 1.0], **common)
        self._add_solid(spec, spec.worldbody.add_body(name="hook"), hook, "hook", common)
        body = spec.worldbody.add_body(name="mug")
        body.add_freejoint()
        self._add_solid(spec, body, mug, "mug", dict(common, margin=TOUCH, gap=TOUCH))
        self.model = model = spec.compile()
        self.data = mujoco.MjData(model)
        self._body = model.body("mug").id
        scale = physics.mug_mass / model.body_mass[self._body]
        model.body_mass[self._body] *= scale
        model.body_inertia[self._body] *= scale
        if isinstance(mug, MeshMug):
            model.body_ipos[self._body] = np.asarray(mug.mesh.center_mass, dtype=float)
        mujoco.mj_setConst(model, self.data)
        self._mug_geoms = np.flatnonzero(model.geom_bodyid == self._body)
        self._bodies = {"hook": model.body("hook").id, "ground": 0}

    def _add_solid(self, spec, body, solid: Hook | Mug | MeshHook | MeshMug, name: str,
                   common: dict) -> None:
        """``solid``'s geoms on ``body``, in the solid's frame."""
        kinds = self.mj.mjtGeom
        if isinstance(solid, MeshHook | MeshMug):
            pieces = read_pieces(convex_pieces_file(solid.mesh_file, solid.scale))
            for k, vertices in enumerate(pieces):
                mesh = f"{name}_piece{k}"
                points = vertices * solid.scale - solid.offset
                spec.add_mesh(name=mesh, uservert=points.ravel().tolist())
                body.add_geom(type=kinds.mjGEOM_MESH, meshname=mesh, **common)
            return
        parts = hook_parts(solid) if isinstance(solid, Hook) else mug_parts(
            solid, self.physics.wall_boxes)
        for part in parts:
            if part["kind"] == "box":
                kind, size = kinds.mjGEOM_BOX, list(part["half"])
            else:
                kind = (kinds.mjGEOM_CAPSULE if part["kind"] == "capsule"
                        else kinds.mjGEOM_CYLINDER)
                size = [part["radius"], part["length"] / 2, 0.0]
            body.add_geom(type=kind, size=size, pos=[float(v) for v in part["pos"]],
                          quat=list(part["quat"]), **common)

    def close(self) -> None:
        self.model = self.data = None

    def _place(self, X_WM: np.ndarray) -> None:
        d = self.data
        d.qpos[:3] = X_WM[:3]
        d.qpos[3:7] = X_WM[3:7] / np.linalg.norm(X_WM[3:7])
        d.qvel[:] = 0.0
        d.qacc_warmstart[:] = 0.0
        self.mj.mj_forward(self.model, d)

    def _contacts(self, body: str) -> list[float]:
        """The distances (m, < 0 inside) of the mug's contacts with ``body`` now."""
        m, d = self.model, self.data
        n = d.ncon
        if n == 0:
            return []
        owner = m.geom_bodyid[np.stack((d.contact.geom1[:n], d.contact.geom2[:n]))]
        other = self._bodies[body]
        pair = (((owner[0] == self._body) & (owner[1] == other))
                | ((owner[1] == self._body) & (owner[0] == other)))
        return d.contact.dist[:n][pair].tolist()

    def _depth(self) -> float:
        return -min((*self._contacts("hook"), 0.0))

    def _touches(self, body: str) -> bool:
        self.mj.mj_forward(self.model, self.data)  # the contacts of the state now
        return bool(self._contacts(body))

    def _step(self) -> None:
        self.mj.mj_step(self.model, self.data)

    def _set_velocity(self, linear: np.ndarray) -> None:
        self.data.qvel[:3] = linear  # the frame's velocity: the centre of mass's, not turning
        self.data.qvel[3:6] = 0.0

    def _lowest(self) -> float:
        """The lowest point of the geoms' bounding boxes, each box in its geom's frame."""
        m, d, g = self.model, self.data, self._mug_geoms
        aabb = m.geom_aabb[g]  # (centre, half extents) in each geom's frame
        R = d.geom_xmat[g].reshape(-1, 3, 3)
        up = R[:, 2]  # each geom's axes' z components
        z = (d.geom_xpos[g, 2] + np.einsum("gj,gj->g", up, aabb[:, :3])
             - np.einsum("gj,gj->g", np.abs(up), aabb[:, 3:]))
        return float(z.min())

    def pose(self) -> tuple[float, ...]:
        """The mug frame's pose ``(x, y, z, qw, qx, qy, qz)``."""
        return tuple(float(v) for v in self.data.qpos[:7])
