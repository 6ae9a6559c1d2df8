"""Load any learned pushing-dynamics folder by the kind its ``spec.json`` names."""

from __future__ import annotations

import json
from pathlib import Path

import torch

from robotplan.models.dynamics import PushDynamics, load_model
from robotplan.models.rigid import RigidMotion, load_rigid

__all__ = ["dynamics_kind", "load_dynamics"]


def dynamics_kind(folder: str | Path) -> str:
    """The kind a model folder's ``spec.json`` names: ``flow``, ``direct`` or ``rigid``."""
    spec = Path(folder) / "spec.json"
    if not spec.is_file():
        raise FileNotFoundError(f"{folder}: no spec.json; not a robotplan model folder")
    return json.loads(spec.read_text()).get("kind", "flow")


def load_dynamics(folder: str | Path, device: str | torch.device = "cpu"
                  ) -> PushDynamics | RigidMotion:
    """F_flow or F (:class:`PushDynamics`) or F_q (:class:`RigidMotion`), as ``spec.json``
    says (weights read with ``weights_only=True``)."""
    if dynamics_kind(folder) == "rigid":
        return load_rigid(folder, device)
    return load_model(folder, device)
