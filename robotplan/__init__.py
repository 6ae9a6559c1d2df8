"""robotplan: manipulation planning with functionals of signed-distance fields.

The planner follows Driess et al., "Learning Models as Functionals of Signed-Distance
Fields for Manipulation Planning" (CoRL 2021): every object is an SDF, moving it is a rigid
transform of its SDF, and a plan is one trajectory optimisation whose constraints are
analytic and learned functionals of those SDFs.
"""

from robotplan.base.arith import pin_arithmetic

pin_arithmetic()  # before any module of ours imports torch

from robotplan.scene import Body, Scene, SceneError, load_scene  # noqa: E402
from robotplan.scene.task import (  # noqa: E402
    HangTask,
    PushTask,
    Task,
    UnsupportedScene,
    load_task,
    make_task,
)

__all__ = ["Body", "Execution", "HangPlan", "HangTask", "PushPlan", "PushTask", "Scene",
           "SceneError", "Task", "UnsupportedScene", "execute", "load_scene", "load_task",
           "make_task", "plan", "solve", "write_playback"]

_FACADE = {"Execution", "HangPlan", "PushPlan", "execute", "plan", "solve", "write_playback"}


def __getattr__(name: str) -> object:
    """The facade (:mod:`robotplan.api`), imported on first use: ``import robotplan`` alone
    stays light (no Drake, pybullet or models) for scene checks."""
    if name in _FACADE:
        from robotplan import api

        return getattr(api, name)
    raise AttributeError(f"module 'robotplan' has no attribute {name!r}")
__version__ = "0.1.0"
