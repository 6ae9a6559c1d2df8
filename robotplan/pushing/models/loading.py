"""Load any learned pushing-dynamics folder by the kind its ``spec.json`` names."""

from __future__ import annotations

from pathlib import Path

import torch

from robotplan.models.spec import read_spec
from robotplan.pushing.models.dynamics import PushDynamics, load_model
from robotplan.pushing.models.rigid import RigidMotion, load_rigid

__all__ = ["dynamics_kind", "load_dynamics"]


def dynamics_kind(folder: str | Path) -> str:
    """The kind a model folder's ``spec.json`` names: ``flow``, ``direct`` or ``rigid``."""
    return read_spec(folder).kind


def load_dynamics(folder: str | Path, device: str | torch.device = "cpu"
                  ) -> PushDynamics | RigidMotion:
    """F_flow or F (:class:`PushDynamics`) or F_q (:class:`RigidMotion`), as ``spec.json``
    says (weights read with ``weights_only=True``)."""
    if dynamics_kind(folder) == "rigid":
        return load_rigid(folder, device)
    return load_model(folder, device)
