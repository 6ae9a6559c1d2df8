"""The pybullet world of mug hanging (paper §7.1, app. H): a static hook on the ground and a
mug dropped from a pose; the drop, and an impulse after it, decide whether the pose hangs
(the test and its labels: :mod:`robotplan.hanging.execution.drop`).

Bodies are compounds of the convex primitives of :mod:`robotplan.hanging.execution.parts`,
built from the same parameters as their SDFs (:mod:`robotplan.sdf.mug_hook`). A mesh hook is
its mesh, a mesh mug its mesh's convex pieces.

A mug released above the hook often falls onto the arm and catches there: it hangs, but the
pose was not a placement (:meth:`DropResult.in_place`).
"""

from __future__ import annotations

import numpy as np

from robotplan.base.quiet import connect_direct, import_pybullet
from robotplan.execution.convex_pieces import convex_pieces_file, obj_file
from robotplan.hanging.execution.drop import HANG_PHYSICS, DropResult, DropTest, HangPhysics
from robotplan.hanging.execution.parts import hook_parts, mug_parts, part_volume
from robotplan.sdf.mesh_solids import MeshHook, MeshMug
from robotplan.sdf.mug_hook import Hook, Mug

__all__ = ["HANG_PHYSICS", "DropResult", "HangPhysics", "HangWorld"]

MAX_COMPOUND = 16  # pybullet's limit on the parts of one compound collision shape


def _pb_quat(wxyz) -> list[float]:
    w, x, y, z = wxyz
    return [x, y, z, w]


def _wxyz(xyzw) -> tuple[float, float, float, float]:
    x, y, z, w = xyzw
    return (w, x, y, z)


class HangWorld(DropTest):
    """A pybullet DIRECT world with the ground, one static hook at the origin and one mug."""

    def __init__(self, hook: Hook | MeshHook, mug: Mug | MeshMug,
                 physics: HangPhysics = HANG_PHYSICS) -> None:
        self.pb = import_pybullet()
        self.physics = physics
        self.client = connect_direct()
        self._com = np.zeros(3)  # the mug body's centre of mass in the mug's frame
        pb, c = self.pb, self.client
        pb.setGravity(0, 0, -physics.gravity, physicsClientId=c)
        pb.setTimeStep(physics.timestep, physicsClientId=c)
        plane = pb.createCollisionShape(pb.GEOM_PLANE, physicsClientId=c)
        self.ground = pb.createMultiBody(0, plane, physicsClientId=c)
        self.hook = (self._mesh_body(0.0, hook) if isinstance(hook, MeshHook)
                     else self._body(0.0, hook_parts(hook)))
        self.mug = (self._mesh_body(physics.mug_mass, mug) if isinstance(mug, MeshMug)
                    else self._body(physics.mug_mass, mug_parts(mug)))
        self.mug_height = mug.height
        self.mug_links = range(-1, pb.getNumJoints(self.mug, physicsClientId=c))
        for body in (self.ground, self.hook, self.mug):
            for link in range(-1, pb.getNumJoints(body, physicsClientId=c)):
                pb.changeDynamics(body, link, lateralFriction=physics.friction,
                                  restitution=0.0, physicsClientId=c)

    def _body(self, mass: float, parts: list[dict]) -> int:
        """A rigid body of convex parts: pybullet takes at most MAX_COMPOUND parts per
        compound shape, so the parts go in groups, the first the base, the others links on
        fixed joints; the mass is split by the parts' volumes, each group's at its centroid,
        and the base's frame (and so the body's pose) is the shape's frame."""
        pb, c = self.pb, self.client
        groups = [parts[i:i + MAX_COMPOUND] for i in range(0, len(parts), MAX_COMPOUND)]
        volumes = [sum(part_volume(p) for p in g) for g in groups]
        masses = [mass * v / sum(volumes) for v in volumes]
        shapes = [self._compound(g) for g in groups]
        centroids = [list(map(float, sum(part_volume(p) * np.asarray(p["pos"]) for p in g) / v))
                     for g, v in zip(groups, volumes, strict=False)]
        n = len(groups) - 1
        return pb.createMultiBody(
            masses[0], shapes[0], baseInertialFramePosition=[0.0, 0.0, 0.0],
            linkMasses=masses[1:], linkCollisionShapeIndices=shapes[1:],
            linkVisualShapeIndices=[-1] * n, linkPositions=[[0.0, 0.0, 0.0]] * n,
            linkOrientations=[[0.0, 0.0, 0.0, 1.0]] * n,
            linkInertialFramePositions=centroids[1:],
            linkInertialFrameOrientations=[[0.0, 0.0, 0.0, 1.0]] * n,
            linkParentIndices=[0] * n, linkJointTypes=[pb.JOINT_FIXED] * n,
            linkJointAxis=[[0.0, 0.0, 1.0]] * n, physicsClientId=c)

    def _mesh_body(self, mass: float, solid: MeshHook | MeshMug) -> int:
        """A mesh as a body: a fixed one (mass 0) as the mesh itself (pybullet collides a
        static triangle mesh exactly), a moving one as its skin's convex pieces
        (:func:`robotplan.execution.convex_pieces.convex_pieces_file`) about its centre of
        mass (``self._com``, in the solid's frame: pybullet places a body by that point)."""
        pb, c = self.pb, self.client
        if mass == 0.0:
            shape = pb.createCollisionShape(pb.GEOM_MESH, fileName=str(obj_file(solid.mesh_file)),
                                            meshScale=[solid.scale] * 3,
                                            collisionFramePosition=(-solid.offset).tolist(),
                                            flags=pb.GEOM_FORCE_CONCAVE_TRIMESH,
                                            physicsClientId=c)
            return pb.createMultiBody(0.0, shape, physicsClientId=c)
        self._com = np.asarray(solid.mesh.center_mass, dtype=float)
        pieces = convex_pieces_file(solid.mesh_file, solid.scale)
        shape = pb.createCollisionShape(pb.GEOM_MESH, fileName=str(pieces),
                                        meshScale=[solid.scale] * 3,
                                        collisionFramePosition=(-solid.offset).tolist(),
                                        physicsClientId=c)
        return pb.createMultiBody(mass, shape, baseInertialFramePosition=self._com.tolist(),
                                  physicsClientId=c)

    def _place(self, X_WM: np.ndarray) -> None:
        """Put the mug's frame at ``X_WM (7,)``, at rest."""
        pb, c = self.pb, self.client
        R = np.array(pb.getMatrixFromQuaternion(_pb_quat(X_WM[3:]))).reshape(3, 3)
        pb.resetBasePositionAndOrientation(self.mug, (X_WM[:3] + R @ self._com).tolist(),
                                           _pb_quat(X_WM[3:]), physicsClientId=c)
        pb.resetBaseVelocity(self.mug, [0, 0, 0], [0, 0, 0], physicsClientId=c)

    def _compound(self, parts: list[dict]) -> int:
        pb = self.pb
        kinds = {"box": pb.GEOM_BOX, "cylinder": pb.GEOM_CYLINDER, "capsule": pb.GEOM_CAPSULE}
        return pb.createCollisionShapeArray(
            shapeTypes=[kinds[p["kind"]] for p in parts],
            radii=[p.get("radius", 0.0) for p in parts],
            halfExtents=[list(p.get("half", (0.0, 0.0, 0.0))) for p in parts],
            lengths=[p.get("length", 0.0) for p in parts],
            collisionFramePositions=[list(map(float, p["pos"])) for p in parts],
            collisionFrameOrientations=[_pb_quat(p["quat"]) for p in parts],
            physicsClientId=self.client)

    def close(self) -> None:
        self.pb.disconnect(self.client)

    def _lowest(self) -> float:
        return min(self.pb.getAABB(self.mug, link, physicsClientId=self.client)[0][2]
                   for link in self.mug_links)

    def _touches(self, body: str) -> bool:
        other = self.hook if body == "hook" else self.ground
        return bool(self.pb.getContactPoints(self.mug, other, physicsClientId=self.client))

    def pose(self) -> tuple[float, ...]:
        """The mug frame's pose ``(x, y, z, qw, qx, qy, qz)``."""
        pos, quat = self.pb.getBasePositionAndOrientation(self.mug, physicsClientId=self.client)
        R = np.array(self.pb.getMatrixFromQuaternion(quat)).reshape(3, 3)
        return (*(np.asarray(pos) - R @ self._com).tolist(), *_wxyz(quat))

    def _depth(self) -> float:
        """How deep (m, ≥ 0) the mug where it is now reaches into the hook."""
        c = self.client
        self.pb.performCollisionDetection(physicsClientId=c)
        return -min((p[8] for p in self.pb.getClosestPoints(self.mug, self.hook, 0.0,
                                                            physicsClientId=c)), default=0.0)

    def _step(self) -> None:
        self.pb.stepSimulation(physicsClientId=self.client)

    def _set_velocity(self, linear: np.ndarray) -> None:
        self.pb.resetBaseVelocity(self.mug, list(linear), [0, 0, 0],
                                  physicsClientId=self.client)
