"""The learned dynamics a push task plans with when none is named: by the task's classes
(:data:`~robotplan.scene.task.PUSH_CLASSES`), ``skeletons/dynamics.yaml``."""

from __future__ import annotations

from functools import cache
from pathlib import Path

import yaml

from robotplan.base.resources import DYNAMICS_FOLDERS, skeletons_dir
from robotplan.scene.task import PUSH_CLASSES, PushTask

__all__ = ["default_dynamics", "load_default_dynamics"]


@cache
def load_default_dynamics(path: Path | None = None) -> dict[str, str]:
    """``skeletons/dynamics.yaml``: task class (or ``default``) → dynamics kind."""
    path = path or skeletons_dir() / "dynamics.yaml"
    data = yaml.safe_load(path.read_text()) or {}
    if not isinstance(data, dict) or "default" not in data:
        raise ValueError(f"{path}: must map task classes and 'default' to dynamics kinds")
    for name, kind in data.items():
        if name != "default" and name not in PUSH_CLASSES:
            raise ValueError(f"{path}: {name}: not a task class; one of {PUSH_CLASSES}")
        if kind not in DYNAMICS_FOLDERS:
            raise ValueError(f"{path}: {name}: {kind!r} is not a dynamics kind; one of "
                             f"{tuple(DYNAMICS_FOLDERS)}")
    return data


def default_dynamics(task: PushTask) -> str:
    """The dynamics kind (``flow``, ``rigid``, ``direct``) ``task`` plans with when none is
    named: that of its first class listed in ``skeletons/dynamics.yaml``, else ``default``."""
    table = load_default_dynamics()
    return next((table[c] for c in task.classes if c in table), table["default"])
