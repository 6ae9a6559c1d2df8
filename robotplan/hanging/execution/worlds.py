"""The simulators a mug can be dropped in (:data:`HANG_SIMULATORS`) and :func:`hang_world`,
which opens a world of the one named. Each runs the same drop test
(:class:`~robotplan.hanging.execution.drop.DropTest`) on the same bodies."""

from __future__ import annotations

from robotplan.hanging.execution.drop import HANG_PHYSICS, DropTest, HangPhysics
from robotplan.sdf.mesh_solids import MeshHook, MeshMug
from robotplan.sdf.mug_hook import Hook, Mug

__all__ = ["HANG_SIMULATORS", "hang_simulator_problem", "hang_world"]

HANG_SIMULATORS = ("pybullet", "mujoco")


def hang_simulator_problem(names: str | list[str] | tuple[str, ...]) -> str | None:
    """Why ``names`` (one or several) are not all simulators of the drop test, or None."""
    for name in [names] if isinstance(names, str) else names:
        if name not in HANG_SIMULATORS:
            return (f"unknown simulator {name!r}; expected one of "
                    f"{', '.join(HANG_SIMULATORS)}")
    return None


def hang_world(hook: Hook | MeshHook, mug: Mug | MeshMug, simulator: str = "pybullet",
               physics: HangPhysics = HANG_PHYSICS) -> DropTest:
    """A world of ``simulator`` (:data:`HANG_SIMULATORS`) with the ground, ``hook`` at the
    origin and ``mug``; ValueError for another name."""
    problem = hang_simulator_problem(simulator)
    if problem is not None:
        raise ValueError(problem)
    if simulator == "mujoco":
        from robotplan.hanging.execution.mujoco_world import MujocoHangWorld

        return MujocoHangWorld(hook, mug, physics)
    from robotplan.hanging.execution.world import HangWorld

    return HangWorld(hook, mug, physics)
