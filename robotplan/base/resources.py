"""Where the data folders are: robot descriptions, skeleton tables, learned models, tasks.

A regular install carries them inside the package (``robotplan/_data/``, copied by
``setup.py``); a source checkout or an editable install reads them beside the package.
``ROBOTPLAN_DATA`` names another folder that holds them.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["DYNAMICS_FOLDERS", "OBJECT_FRAME_FOLDERS", "REHEARSAL_FOLDERS", "cache_dir",
           "data_root", "learned_dir", "robots_dir", "skeletons_dir", "tasks_dir"]

_PACKAGE = Path(__file__).resolve().parents[1]


def data_root() -> Path:
    """The folder that holds ``robots/``, ``skeletons/``, ``learned/`` and ``tasks/``."""
    given = os.environ.get("ROBOTPLAN_DATA")
    if given:
        return Path(given)
    installed = _PACKAGE / "_data"
    return installed if installed.is_dir() else _PACKAGE.parent


def robots_dir() -> Path:
    return data_root() / "robots"


def skeletons_dir() -> Path:
    return data_root() / "skeletons"


# the shipped model of each kind of learned dynamics (``--dynamics``), under learned/
DYNAMICS_FOLDERS = {"flow": "push_flow", "rigid": "push_rigid", "direct": "push_direct"}
# F_flow and F with X_h attached to the object (``train push --frame object``), beside them
OBJECT_FRAME_FOLDERS = {"flow": "push_flow_object", "direct": "push_direct_object"}
# the F_q a plan is rehearsed in before the open loop, by footprint type: the object-frame one
# where it was trained (it follows pybullet closest over whole plans); any other footprint in
# the plan's own F_q (the object-frame one errs 3x as much on footprints never trained on)
# (measured: docs/experiments.md#rehearsal, docs/experiments.md#fq-object-frame)
REHEARSAL_FOLDERS = {"box": "push_rigid_object", "lshape": "push_rigid_object"}


def learned_dir(model: str = "push_flow") -> Path:
    """A shipped model's folder (spec, weights, metrics, model card)."""
    return data_root() / "learned" / model


def tasks_dir() -> Path:
    return data_root() / "tasks"


def cache_dir(kind: str) -> Path:
    """A folder for results derived from a user's files (keyed by their content), created on
    demand: ``$ROBOTPLAN_CACHE/<kind>``, else ``$XDG_CACHE_HOME/robotplan/<kind>``, else
    ``~/.cache/robotplan/<kind>``."""
    given = os.environ.get("ROBOTPLAN_CACHE")
    if given:
        root = Path(given)
    else:
        xdg = os.environ.get("XDG_CACHE_HOME")
        root = (Path(xdg) if xdg else Path.home() / ".cache") / "robotplan"
    folder = root / kind
    folder.mkdir(parents=True, exist_ok=True)
    return folder
