"""The physics of table-top pushing and the simulators that run it.

One fixed set of physics (``PHYSICS``) is part of the learned model's world: the push data
is generated with it and plans are executed in it. The table top is the plane z = 0, a
1.4 × 1.4 m slab; objects are footprints extruded to their height, their centre of mass at
the footprint's centroid (uniform density); the pusher is a sphere whose centre is held at
z = radius and driven along a path.

``Physics.simulator`` names the world that runs it (:data:`SIMULATORS`): pybullet
(:mod:`robotplan.execution.pybullet_world`, the push data's) or MuJoCo
(:mod:`robotplan.execution.mujoco_world`). Both give the same contacts the same friction
coefficients (:meth:`Physics.friction`) and have one interface, :class:`PushSimulator`;
:func:`push_world` opens the one a ``Physics`` names. A further simulator is one module with
that interface and one entry in :data:`SIMULATORS`.
"""

from __future__ import annotations

import importlib
from dataclasses import asdict, dataclass
from typing import Protocol

import numpy as np

__all__ = ["PHYSICS", "SIMULATORS", "ArmDriver", "Physics", "PushSimulator", "damped_step",
           "open_simulator", "push_world", "simulator_problem"]

SIMULATORS = {"pybullet": "robotplan.execution.pybullet_world:PushWorld",
              "mujoco": "robotplan.execution.mujoco_world:MujocoPushWorld"}
"""Each simulator's name and the class of its :class:`PushSimulator` (``module:class``)."""


@dataclass(frozen=True)
class Physics:
    """Simulation constants (SI units). A contact's friction coefficient is the product of
    its two bodies' (pybullet's rule, :meth:`friction`)."""

    timestep: float = 1.0 / 240.0
    keep_every: int = 20  # keep the state every 20th step (paper, appendix I)
    gravity: float = 9.81
    table_size: float = 1.4
    table_friction: float = 1.0
    object_mass: float = 0.5  # kg, whatever the size
    object_friction: float = 0.5  # → object–table μ = 0.5
    pusher_friction: float = 0.3  # → pusher–object μ = 0.15
    restitution: float = 0.0
    pusher_max_force: float = 500.0  # N, the most that drives the pusher
    solver_iterations: int = 50
    link_friction: float = 0.5  # an arm's links (a URDF's default in pybullet)
    simulator: str = "pybullet"  # the world that runs it: a key of SIMULATORS

    def as_dict(self) -> dict:
        return asdict(self)

    def friction(self, a: str, b: str) -> float:
        """The friction coefficient of a contact between bodies of kinds ``a`` and ``b``
        (``table``, ``object``, ``pusher``, ``link``): the product of theirs."""
        own = {"table": self.table_friction, "object": self.object_friction,
               "pusher": self.pusher_friction, "link": self.link_friction}
        return own[a] * own[b]


PHYSICS = Physics()


def simulator_problem(names: str | list[str] | tuple[str, ...],
                      known: dict[str, str] = SIMULATORS) -> str | None:
    """Why ``names`` (one or several) are not all simulators of ``known`` (name →
    ``module:class``, default :data:`SIMULATORS`), or None."""
    for name in [names] if isinstance(names, str) else names:
        if name not in known:
            return f"unknown simulator {name!r}; expected one of {', '.join(known)}"
    return None


def open_simulator(name: str, known: dict[str, str], *args: object) -> object:
    """An instance of the class ``known[name]`` (``module:class``) made with ``args``;
    ValueError naming the choices for another name."""
    problem = simulator_problem(name, known)
    if problem is not None:
        raise ValueError(problem)
    module, cls = known[name].split(":")
    return getattr(importlib.import_module(module), cls)(*args)


class ArmDriver(Protocol):
    """One arm in a :class:`PushSimulator`, its joints under position control."""

    def drive(self, q: np.ndarray) -> None:
        """Set the joints' targets ``(dof,)`` for the steps that follow."""

    def steered(self, q: np.ndarray, shift: np.ndarray) -> np.ndarray:
        """Joint angles near ``q`` that move the tip centre by ``shift (3,)`` m (world
        frame), to first order (:func:`damped_step`)."""

    def tip_position(self) -> np.ndarray:
        """The tip sphere's centre ``(3,)`` in the world frame."""

    def joint_angles(self) -> np.ndarray:
        """The measured joint angles ``(dof,)``."""


class PushSimulator(Protocol):
    """A world of table-top pushing: a table, one object, fixed obstacles, more movable
    objects and a free spherical pusher or arms."""

    physics: Physics

    def reset(self, shape, height: float, pose, pusher_radius: float | None,
              pusher_xy=(0.0, 0.0), obstacles=(), movable=()) -> None:
        """A fresh scene: the object (footprint ``shape`` extruded to ``height`` at planar
        ``pose``), a pusher of ``pusher_radius`` at ``pusher_xy`` (none if None), fixed
        ``obstacles`` and ``movable`` objects as ``(footprint, height, pose)``."""

    def add_arm(self, spec) -> ArmDriver:
        """A robot (a scene's ``RobotSpec``) at its base and start joints, with its tip."""

    def step(self, pusher_target) -> bool:
        """One time step driving the pusher to ``pusher_target (x, y)``; whether it then
        touches the object."""

    def advance(self) -> None:
        """One time step, the arms driven to their targets."""

    def object_pose(self) -> tuple[np.ndarray, float]:
        """The object's planar pose ``(x, y, yaw)`` (shape frame) and its tilt (rad)."""

    def other_poses(self) -> list[np.ndarray]:
        """The movable objects' planar poses, in their order."""

    def pusher_position(self) -> np.ndarray:
        """The pusher's centre ``(x, y)``."""

    def pusher_touches_other(self, index: int) -> bool:
        """Whether the pusher touches the ``index``-th movable object."""

    def touches_obstacle(self, gap: float = 0.0) -> bool:
        """Whether an object is within ``gap`` (m) of an obstacle."""

    def close(self) -> None:
        """Free the simulator (also on leaving a ``with`` block)."""

    def __enter__(self) -> PushSimulator: ...

    def __exit__(self, *exc: object) -> None: ...


def push_world(physics: Physics = PHYSICS) -> PushSimulator:
    """A fresh :class:`PushSimulator` of ``physics.simulator`` running ``physics``."""
    return open_simulator(physics.simulator, SIMULATORS, physics)


DAMPING = 0.01  # m: the damped least-squares step of ArmDriver.steered near singularities


def damped_step(J: np.ndarray, q: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """Joint angles ``q + Jᵀ(JJᵀ + λ²I)⁻¹ shift``: one damped least-squares step that moves
    the point of the Jacobian ``J (3, dof)`` by ``shift (3,)`` to first order."""
    step = J.T @ np.linalg.solve(J @ J.T + DAMPING**2 * np.eye(3), np.asarray(shift, float))
    return np.asarray(q, dtype=float) + step
