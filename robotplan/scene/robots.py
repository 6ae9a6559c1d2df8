"""Robot descriptions from ``robots/<model>/robot.yaml`` and the forward kinematics of the tip.

A robot folder names a URDF (``pybullet_data://…`` for models shipped inside the
``pybullet_data`` package, or a path relative to the folder), its joint and velocity limits,
the link that carries the spherical tip with the tip centre's offset in that link's frame,
and a home pose. Nothing is downloaded.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache, lru_cache
from pathlib import Path

import numpy as np
import yaml

from robotplan.base.quiet import connect_direct, drake_quiet, import_pybullet
from robotplan.base.resources import robots_dir
from robotplan.scene.reader import read

__all__ = ["ROBOTS_DIR", "DrakeArm", "RobotModel", "available_models", "load_robot_model",
           "welded_urdf"]

ROBOTS_DIR = robots_dir()


@dataclass(frozen=True)
class TipMount:
    """Where the tip sphere sits: its centre at ``offset`` in the frame of ``link``."""

    link: str
    offset: tuple[float, float, float]


@dataclass(frozen=True)
class RobotModel:
    """The schema of ``robot.yaml``."""

    name: str
    urdf: str
    joint_lower: tuple[float, ...]
    joint_upper: tuple[float, ...]
    velocity_limits: tuple[float, ...] = field(metadata={"positive": True})
    tip: TipMount
    home: tuple[float, ...]
    # horizontal distance (m) from the base axis at which the tip reaches push height with
    # the flange and links above the objects (measured by inverse kinematics)
    reach: tuple[float, float] = (0.0, float("inf"))
    # link origins kept above the objects and apart from the other arm, flange first
    check_links: tuple[str, ...] = ()
    # joints of the URDF held at zero, not planned (a gripper's fingers): welded
    fixed_joints: tuple[str, ...] = ()
    description: str = ""
    folder: Path = field(default=ROBOTS_DIR, compare=False, init=False)

    @property
    def dof(self) -> int:
        return len(self.joint_lower)

    def check(self) -> tuple[str, str] | None:
        n = len(self.joint_lower)
        for key in ("joint_upper", "velocity_limits", "home"):
            if len(getattr(self, key)) != n:
                return key, f"must have {n} entries like joint_lower"
        if any(lo >= hi for lo, hi in zip(self.joint_lower, self.joint_upper, strict=False)):
            return "joint_upper", "every upper limit must exceed its lower limit"
        if not self.within_limits(self.home):
            return "home", "must lie within the joint limits"
        if not self.check_links:
            return "check_links", "name at least the flange link"
        return None

    def within_limits(self, q: tuple[float, ...] | np.ndarray) -> bool:
        return all(lo <= v <= hi
                   for v, lo, hi in zip(q, self.joint_lower, self.joint_upper, strict=True))

    @property
    def source_urdf(self) -> Path:
        """The URDF file as the folder names it."""
        if self.urdf.startswith("pybullet_data://"):
            import pybullet_data

            return Path(pybullet_data.getDataPath()) / self.urdf.removeprefix("pybullet_data://")
        return self.folder / self.urdf

    @property
    def urdf_path(self) -> Path:
        """The URDF the planner and the simulator load: the source, or with ``fixed_joints``
        a copy in which they are welded (:func:`welded_urdf`)."""
        return welded_urdf(self.source_urdf, self.fixed_joints) if self.fixed_joints \
            else self.source_urdf

    def tip_position(self, q: tuple[float, ...], base: tuple[float, float, float, float]
                     ) -> np.ndarray:
        """Tip-sphere centre ``p_WT (3,)`` for joint angles ``q`` and ``base = (x, y, z, yaw)``."""
        return _tip_position(self, tuple(map(float, q)), tuple(map(float, base)))


@cache
def welded_urdf(source: Path, joints: tuple[str, ...]) -> Path:
    """A copy of the URDF ``source`` with ``joints`` made fixed (at zero) and every mesh file
    named by its absolute path (the copy lives in the cache, not beside its meshes)."""
    import hashlib
    import xml.etree.ElementTree as ET

    from robotplan.base.files import write_atomically
    from robotplan.base.resources import cache_dir

    tree = ET.parse(source)
    named = {j.get("name"): j for j in tree.getroot().iter("joint")}
    missing = sorted(set(joints) - set(named))
    if missing:
        raise ValueError(f"{source}: no joint named {missing[0]!r} to fix")
    for name in joints:
        named[name].set("type", "fixed")
    for mesh in tree.getroot().iter("mesh"):
        file = mesh.get("filename", "")
        relative = file.removeprefix("package://")  # pybullet's rule: beside the URDF
        mesh.set("filename", str((source.parent / relative).resolve()))
    text = ET.tostring(tree.getroot(), encoding="unicode")
    key = hashlib.sha256(text.encode()).hexdigest()[:16]
    out = cache_dir("robots") / f"{source.stem}-{key}.urdf"
    if not out.is_file():
        write_atomically(out, lambda tmp: tmp.write_text(text))
    return out


def available_models() -> list[str]:
    return sorted(p.parent.name for p in ROBOTS_DIR.glob("*/robot.yaml"))


@cache
def load_robot_model(name: str) -> RobotModel:
    """Read ``robots/<name>/robot.yaml``. Raises FileNotFoundError for an unknown model."""
    path = ROBOTS_DIR / name / "robot.yaml"
    if not path.is_file():
        raise FileNotFoundError(f"no robot model {name!r}; available: {available_models()}")
    with path.open() as f:
        model = read(RobotModel, yaml.safe_load(f))
    object.__setattr__(model, "folder", path.parent)
    return model


@cache
def _kinematics_handle(model: RobotModel) -> tuple[int, int, int, tuple[int, ...]]:
    """A pybullet DIRECT client holding the model at the origin, loaded once per process:
    ``(client, body, tip link index, movable joint indices)``."""
    pb = import_pybullet()
    client = connect_direct()
    body = pb.loadURDF(str(model.urdf_path), useFixedBase=True, physicsClientId=client)
    links: dict[str, int] = {}
    movable = []
    for j in range(pb.getNumJoints(body, physicsClientId=client)):
        info = pb.getJointInfo(body, j, physicsClientId=client)
        links[info[12].decode()] = j
        if info[2] != pb.JOINT_FIXED:
            movable.append(j)
    return client, body, links[model.tip.link], tuple(movable)


@lru_cache(maxsize=256)
def _tip_position(model: RobotModel, q: tuple[float, ...],
                  base: tuple[float, float, float, float]) -> np.ndarray:

    pb = import_pybullet()
    client, body, tip_link, movable = _kinematics_handle(model)
    for j, angle in zip(movable, q, strict=True):
        pb.resetJointState(body, j, angle, physicsClientId=client)
    state = pb.getLinkState(body, tip_link, computeForwardKinematics=True,
                            physicsClientId=client)
    R_link = np.array(pb.getMatrixFromQuaternion(state[5])).reshape(3, 3)
    p_base = np.asarray(state[4]) + R_link @ np.asarray(model.tip.offset)  # in the base frame
    c, s = np.cos(base[3]), np.sin(base[3])
    R_base = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return R_base @ p_base + np.asarray(base[:3])


class DrakeArm:
    """The same robot folder loaded into a Drake ``MultibodyPlant`` (base welded at ``base =
    (x, y, z, yaw)``): forward kinematics of the tip with exact gradients, for the programs
    over joint angles. Agrees with pybullet's kinematics (tests/scene/test_robots.py)."""

    def __init__(self, model: RobotModel, base: tuple[float, float, float, float]
                 = (0.0, 0.0, 0.0, 0.0)) -> None:
        from pydrake.math import RigidTransform, RollPitchYaw
        from pydrake.multibody.plant import MultibodyPlant


        self.model = model
        plant = MultibodyPlant(0.0)
        with drake_quiet():  # the URDF's massless base link warns; it is welded anyway
            (instance,) = _offline_parser(plant).AddModels(str(model.urdf_path))
        root = plant.GetBodyByName(_root_link(model), instance).body_frame()
        X_WB = RigidTransform(RollPitchYaw(0.0, 0.0, base[3]), list(base[:3]))
        plant.WeldFrames(plant.world_frame(), root, X_WB)
        plant.Finalize()
        self.plant = plant
        self.context = plant.CreateDefaultContext()
        self.tip_frame = plant.GetBodyByName(model.tip.link, instance).body_frame()
        if plant.num_positions() != model.dof:
            raise ValueError(f"{model.name}: Drake sees {plant.num_positions()} joints, "
                             f"robot.yaml {model.dof}")

    def tip_position(self, q: np.ndarray) -> np.ndarray:
        """Tip-sphere centre ``p_WT (3,)`` at joint angles ``q (dof,)``."""
        self.plant.SetPositions(self.context, np.asarray(q, dtype=float))
        offset = np.asarray(self.model.tip.offset, dtype=float).reshape(3, 1)
        return self.plant.CalcPointsPositions(self.context, self.tip_frame, offset,
                                              self.plant.world_frame())[:, 0]

    def tip_jacobian(self, q: np.ndarray) -> np.ndarray:
        """∂p_WT/∂q ``(3, dof)`` (translational Jacobian of the tip centre)."""
        from pydrake.multibody.tree import JacobianWrtVariable

        self.plant.SetPositions(self.context, np.asarray(q, dtype=float))
        return self.plant.CalcJacobianTranslationalVelocity(
            self.context, JacobianWrtVariable.kQDot, self.tip_frame,
            np.asarray(self.model.tip.offset, dtype=float), self.plant.world_frame(),
            self.plant.world_frame())


def _offline_parser(plant):
    """A Drake ``Parser`` whose package map holds local packages only. Its default map names
    the remote ``drake_models``, which Drake refuses to construct while networking is limited
    (``DRAKE_ALLOW_NETWORK=meshcat``, set by robotplan.viz.viewer): allow the map's construction,
    then drop the remote entry, so nothing can be fetched."""
    import os

    from pydrake.multibody.parsing import Parser

    key = "DRAKE_ALLOW_NETWORK"
    saved = os.environ.get(key)
    if saved is not None and "package_map" not in saved.split(":"):
        os.environ[key] = f"{saved}:package_map" if saved and saved != "none" else "package_map"
    try:
        parser = Parser(plant)
    finally:
        if saved is not None:
            os.environ[key] = saved
    packages = parser.package_map()
    for name in packages.GetPackageNames():
        if name.startswith("drake_models"):
            packages.Remove(name)
    return parser


@cache
def _root_link(model: RobotModel) -> str:
    """The URDF's root link: the one that is no joint's child."""
    import xml.etree.ElementTree as ET

    root = ET.parse(model.urdf_path).getroot()
    children = {j.find("child").get("link") for j in root.iter("joint")}
    return next(link.get("name") for link in root.iter("link")
                if link.get("name") not in children)
