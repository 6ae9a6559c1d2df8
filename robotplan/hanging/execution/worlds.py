"""The simulators a mug can be dropped in (:data:`HANG_SIMULATORS`) and :func:`hang_world`,
which opens a world of the one named. Each runs the same drop test
(:class:`~robotplan.hanging.execution.drop.DropTest`) on the same bodies; a further
simulator is one module with a ``DropTest`` and one entry here."""

from __future__ import annotations

from robotplan.execution.physics import open_simulator, simulator_problem
from robotplan.hanging.execution.drop import HANG_PHYSICS, DropTest, HangPhysics
from robotplan.sdf.mesh_solids import MeshHook, MeshMug
from robotplan.sdf.mug_hook import Hook, Mug

__all__ = ["HANG_SIMULATORS", "hang_simulator_problem", "hang_world"]

HANG_SIMULATORS = {"pybullet": "robotplan.hanging.execution.world:HangWorld",
                   "mujoco": "robotplan.hanging.execution.mujoco_world:MujocoHangWorld"}
"""Each simulator's name and its drop test (``module:class``)."""


def hang_simulator_problem(names: str | list[str] | tuple[str, ...]) -> str | None:
    """Why ``names`` (one or several) are not all simulators of the drop test, or None."""
    return simulator_problem(names, HANG_SIMULATORS)


def hang_world(hook: Hook | MeshHook, mug: Mug | MeshMug, simulator: str = "pybullet",
               physics: HangPhysics = HANG_PHYSICS) -> DropTest:
    """A world of ``simulator`` (:data:`HANG_SIMULATORS`) with the ground, ``hook`` at the
    origin and ``mug``; ValueError for another name."""
    return open_simulator(simulator, HANG_SIMULATORS, hook, mug, physics)
