"""The pybullet world of mug hanging (paper §7.1, app. H): a static hook on the ground and a
mug dropped from a pose; the drop, and an impulse after it, decide whether the pose hangs.

Bodies are compounds of convex primitives built from the same parameters as their SDFs
(:mod:`robotplan.sdf.mug_hook`): the cup's wall is a ring of boxes, its bottom a
cylinder, the handle and the hook's arm capsules along their centre lines, the post a
cylinder. A mesh hook is its mesh, a mesh mug its mesh's convex pieces.

A pose *hangs* when the mug is not in collision with the hook where it starts and,
after the drop and the impulse, still touches the hook and keeps clear of the ground; it
hangs *in place* when, besides, it came to rest (before the impulse) at most a few
centimetres below where it was released. A mug released above the
hook often falls onto the arm and catches there: it hangs, but the pose was not a placement.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import asdict, dataclass

import numpy as np

from robotplan.base.quiet import connect_direct, import_pybullet
from robotplan.execution.convex_pieces import convex_pieces_file, obj_file
from robotplan.sdf.mesh_solids import MeshHook, MeshMug
from robotplan.sdf.mug_hook import Hook, Mug

__all__ = ["HANG_PHYSICS", "DropResult", "HangPhysics", "HangWorld"]


@dataclass(frozen=True)
class HangPhysics:
    """Simulation constants of the drop test (SI units)."""

    timestep: float = 1.0 / 240.0
    gravity: float = 9.81
    mug_mass: float = 0.3
    friction: float = 0.5
    settle_s: float = 1.5  # fall and settle before the impulse
    # the impulse that checks stability: a velocity kick off the arm's end and upwards
    kick_speed: float = 0.3  # m/s along (+x_H + z) / √2
    after_kick_s: float = 1.5
    ground_clearance: float = 0.01  # m: the mug's lowest point above the ground
    start_penetration: float = 0.001  # m: deeper contact at the start counts as collision
    # a hang *in place*: the mug's centre comes down at most this far (m) before it rests, so
    # the pose was a placement, not a fall that caught the arm (docs/experiments.md#hang-labels)
    in_place_fall: float = 0.05
    wall_boxes: int = 16

    def as_dict(self) -> dict:
        return asdict(self)


HANG_PHYSICS = HangPhysics()


@dataclass(frozen=True)
class DropResult:
    """What one drop gave: ``hangs`` is the label y of the data set."""

    hangs: bool
    collision_at_start: bool
    on_hook: bool
    on_ground: bool
    X_WM_end: tuple[float, ...]  # (x, y, z, qw, qx, qy, qz) after the drop and the impulse
    fall_m: float = 0.0  # how far the mug's centre came down before the impulse

    def in_place(self, physics: HangPhysics = HANG_PHYSICS) -> bool:
        """Hangs, and came to rest near its release height (``physics.in_place_fall``)."""
        return bool(self.hangs and self.fall_m <= physics.in_place_fall)


RECORD_EVERY = 8  # simulation steps between recorded poses (30 per second)
MAX_COMPOUND = 16  # pybullet's limit on the parts of one compound collision shape


def _volume(part: dict) -> float:
    if part["kind"] == "box":
        return 8.0 * float(np.prod(part["half"]))
    r, length = part["radius"], part["length"]
    cap = 4.0 / 3.0 * r if part["kind"] == "capsule" else 0.0
    return math.pi * r * r * (length + cap)


def _pb_quat(wxyz) -> list[float]:
    w, x, y, z = wxyz
    return [x, y, z, w]


def _wxyz(xyzw) -> tuple[float, float, float, float]:
    x, y, z, w = xyzw
    return (w, x, y, z)


def _capsules(points: np.ndarray, radius: float) -> list[dict]:
    """Capsule parts along the segments of a polyline in a frame's xz-plane."""
    parts = []
    for a, b in itertools.pairwise(points):
        d = b - a
        length = float(np.linalg.norm(d))
        tilt = math.atan2(d[0], d[2])  # about y, taking z onto the segment
        parts.append(dict(kind="capsule", radius=radius, length=length, pos=(a + b) / 2,
                          quat=(math.cos(tilt / 2), 0.0, math.sin(tilt / 2), 0.0)))
    return parts


def mug_parts(mug: Mug, wall_boxes: int = HANG_PHYSICS.wall_boxes) -> list[dict]:
    """The mug as convex primitives in its frame (box half extents, cylinder and capsule
    radius and length, pose)."""
    r, h, w = mug.radius, mug.height, mug.wall
    parts = [dict(kind="cylinder", radius=r, length=w, pos=np.array([0.0, 0.0, w / 2]),
                  quat=(1.0, 0.0, 0.0, 0.0))]
    half_width = (r - w / 2) * math.tan(math.pi / wall_boxes) + w / 2
    for k in range(wall_boxes):
        a = 2 * math.pi * k / wall_boxes
        pos = np.array([(r - w / 2) * math.cos(a), (r - w / 2) * math.sin(a), h / 2])
        parts.append(dict(kind="box", half=(w / 2, half_width, h / 2), pos=pos,
                          quat=(math.cos(a / 2), 0.0, 0.0, math.sin(a / 2))))
    return parts + _capsules(mug.handle_points(), mug.handle_radius)


def hook_parts(hook: Hook) -> list[dict]:
    """The hook as convex primitives in its frame."""
    post = dict(kind="cylinder", radius=hook.post_radius, length=hook.post_height,
                pos=np.array([0.0, 0.0, hook.post_height / 2]), quat=(1.0, 0.0, 0.0, 0.0))
    return [post, *_capsules(hook.arm_points(), hook.rod_radius)]


class HangWorld:
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
        self._record: list | None = None
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
        volumes = [sum(_volume(p) for p in g) for g in groups]
        masses = [mass * v / sum(volumes) for v in volumes]
        shapes = [self._compound(g) for g in groups]
        centroids = [list(map(float, sum(_volume(p) * np.asarray(p["pos"]) for p in g) / v))
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
        """Put the mug's frame at ``X_WM (7,)``."""
        R = np.array(self.pb.getMatrixFromQuaternion(_pb_quat(X_WM[3:]))).reshape(3, 3)
        self.pb.resetBasePositionAndOrientation(self.mug, (X_WM[:3] + R @ self._com).tolist(),
                                                _pb_quat(X_WM[3:]), physicsClientId=self.client)

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

    def __enter__(self) -> HangWorld:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _centre_z(self, X_WM) -> float:
        """Height of the mug's centre (on its axis, half way up) at pose ``X_WM``."""
        _, x, y, _ = X_WM[3:7]
        n = math.sqrt(sum(v * v for v in X_WM[3:7]))
        zz = 1.0 - 2.0 * (x * x + y * y) / (n * n)  # z component of the mug's rotated z axis
        return float(X_WM[2]) + zz * self.mug_height / 2

    def _steps(self, seconds: float) -> int:
        return round(seconds / self.physics.timestep)

    def _lowest(self) -> float:
        return min(self.pb.getAABB(self.mug, link, physicsClientId=self.client)[0][2]
                   for link in self.mug_links)

    def _touches(self, other: int) -> bool:
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

    def collides(self, X_WM) -> bool:
        """The mug placed at ``X_WM (7,)`` starts in collision with the hook (deeper than
        ``physics.start_penetration``): a drop from there is a failure without simulating."""
        X = np.asarray(X_WM, dtype=float)
        self._place(X)
        return self._depth() > self.physics.start_penetration

    def drop(self, X_WM, record: list | None = None) -> DropResult:
        """Place the mug at ``X_WM (7,)`` at rest, let it fall and settle, kick it, and
        decide whether it hangs. A fall to the ground ends the run early. ``record``, if
        given, receives ``(t, X_WM)`` every ``RECORD_EVERY`` steps (for a playback)."""
        self._record = record
        pb, c, ph = self.pb, self.client, self.physics
        X = np.asarray(X_WM, dtype=float)
        self._place(X)
        pb.resetBaseVelocity(self.mug, [0, 0, 0], [0, 0, 0], physicsClientId=c)
        if record is not None:
            record.append((0.0, self.pose()))
        if self._depth() > ph.start_penetration:
            return DropResult(False, True, True, False, self.pose())
        fallen = self._run(self._steps(ph.settle_s))
        fall = self._centre_z(X) - self._centre_z(self.pose())
        if not fallen:
            v = ph.kick_speed / math.sqrt(2.0)
            pb.resetBaseVelocity(self.mug, [v, 0.0, v], [0, 0, 0], physicsClientId=c)
            fallen = self._run(self._steps(ph.after_kick_s))
        on_ground = fallen or self._touches(self.ground)
        on_hook = self._touches(self.hook)
        return DropResult(on_hook and not on_ground, False, on_hook, on_ground, self.pose(),
                          fall)

    def _run(self, steps: int) -> bool:
        """Step the world; True as soon as the mug comes down to the ground."""
        record = self._record
        for k in range(steps):
            self.pb.stepSimulation(physicsClientId=self.client)
            if record is not None and k % RECORD_EVERY == 0:
                t = (record[-1][0] if record else 0.0) + RECORD_EVERY * self.physics.timestep
                record.append((t, self.pose()))
            if self._lowest() < self.physics.ground_clearance:
                return True
        return False
