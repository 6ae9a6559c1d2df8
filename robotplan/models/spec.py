"""The constructor arguments of a dynamics model (``spec.json`` beside its weights) and the
dtype its head multiplies in."""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Literal

import torch
from torch import nn

from robotplan.base.arith import bfloat16_head
from robotplan.sdf.grid import Workspace

__all__ = ["OBJECT_WINDOW", "DynamicsSpec", "conv_output_side", "head_matmul_dtype",
           "read_model_folder", "read_spec", "write_model_folder"]


# X_h of an object-frame F_q: 64 × 64 points over 0.64 m (1 cm cells, as on the table),
# which hold every footprint of the data and a pusher touching it
# (measured: docs/experiments.md#fq-object-frame)
OBJECT_WINDOW = {"grid": (64, 64), "workspace_center": (0.0, 0.0),
                 "workspace_size": (0.64, 0.64)}


def head_matmul_dtype(model_dtype: torch.dtype) -> torch.dtype:
    """The dtype of the head's hidden-to-hidden products: the model's own, or bfloat16 for a
    float32 model where the user opted in (:func:`robotplan.base.arith.bfloat16_head`)."""
    if model_dtype == torch.float32 and bfloat16_head():
        return torch.bfloat16
    return model_dtype


def conv_output_side(side: int, kernel: int, stride: int) -> int:
    """The side of a convolution's output map (no padding) over an input of ``side``."""
    return (side - kernel) // stride + 1


@dataclass(frozen=True)
class DynamicsSpec:
    """Constructor arguments of :class:`PushDynamics` and of F_q's :class:`RigidMotion`
    (written to ``spec.json``)."""

    kind: Literal["flow", "direct", "rigid"] = "flow"
    grid: tuple[int, int] = (140, 140)
    workspace_center: tuple[float, float] = (0.0, 0.0)
    workspace_size: tuple[float, float] = (1.4, 1.4)
    channels: tuple[int, ...] = (3, 5, 5)
    kernels: tuple[int, ...] = (3, 5, 5)
    strides: tuple[int, ...] = (1, 2, 2)
    sdf_features: int = 200
    point_features: int = 100
    hidden: tuple[int, ...] = (300, 300)
    encoder: Literal["shared", "joint"] = "shared"  # joint: one encoder sees all 3 SDFs
    sdf_scale: float = 5.0  # input SDF values (m) are multiplied by this
    # what the encoder reads of each grid φ: the SDF itself (the paper's proposal), or the
    # baselines of its app. A: the occupancy measure ψ = sign(φ) (eq. 10) or its smooth
    # version ψ_s = tanh(b φ) (eq. 11); the boundary's point cloud (eq. 12, F_q only)
    representation: Literal["sdf", "occupancy", "smooth_occupancy", "pointcloud"] = "sdf"
    occupancy_sharpness: float = 100.0  # b of ψ_s = tanh(b φ), 1/m (eq. 11)
    cloud_points: int = 128  # points per boundary cloud (pointcloud)
    cloud_widths: tuple[int, ...] = (64, 128, 256)  # PointNet's per-point MLP (pointcloud)
    # the point-cloud encoder: PointNet, or PointNet++ with one set-abstraction level of
    # cloud_centroids centroids, each with its cloud_neighbours nearest points through the
    # local MLP cloud_local_widths (offsets in m times cloud_local_scale)
    cloud_encoder: Literal["pointnet", "pointnet2"] = "pointnet"
    cloud_centroids: int = 32
    cloud_neighbours: int = 16
    cloud_local_widths: tuple[int, ...] = (32, 64)
    cloud_local_scale: float = 50.0
    # where X_h lies: "table", fixed on the table (the paper's); "object", attached to the
    # object at t−1, its origin at the footprint's centroid and its axes the body's, so that
    # the inputs and Δq (given in that frame) are the same for a push anywhere on the table
    # at any heading: planar pushing's exact symmetry (see docs/experiments.md#fq-object-frame)
    frame: Literal["table", "object"] = "table"
    out_scale: float = 0.01  # the network's output is multiplied by this (m)
    turn_scale: float = 0.05  # F_q's turn output is multiplied by this (rad)
    extra: dict = field(default_factory=dict)  # free-form notes (not used by the network)

    def workspace(self) -> Workspace:
        """X_h: the table region the grids sample, ``grid`` points over ``workspace_size``."""
        return Workspace(self.workspace_center, self.workspace_size,
                         self.workspace_size[0] / self.grid[1])

    @classmethod
    def from_json(cls, data: dict) -> DynamicsSpec:
        kw = dict(data)
        for k in ("grid", "workspace_center", "workspace_size", "channels", "kernels",
                  "strides", "hidden", "cloud_widths", "cloud_local_widths"):
            if k in kw:
                kw[k] = tuple(kw[k])
        return cls(**kw)


def _spec_json(folder: str | Path) -> dict:
    path = Path(folder) / "spec.json"
    if not path.is_file():
        raise FileNotFoundError(f"{folder}: no spec.json; not a robotplan model folder")
    return json.loads(path.read_text())


def read_spec(folder: str | Path, spec_type: type = DynamicsSpec):
    """The ``spec.json`` of a model folder, as ``spec_type`` (a dataclass with
    ``from_json``)."""
    return spec_type.from_json(_spec_json(folder))


def read_model_folder(folder: str | Path, kinds: tuple[str, ...],
                      device: str | torch.device = "cpu", spec_type: type = DynamicsSpec):
    """A model folder's spec (``spec_type``), whose kind must be one of ``kinds``, and its
    state_dict (``weights.pt``, read with ``weights_only=True``)."""
    data = _spec_json(folder)
    kind = data.get("kind", "flow")
    if kind not in kinds:
        raise ValueError(f"{folder}: spec.json kind {kind!r}, expected "
                         + " or ".join(repr(k) for k in kinds))
    spec = spec_type.from_json(data)
    weights = Path(folder) / "weights.pt"
    if not weights.is_file():
        raise FileNotFoundError(f"{folder}: no weights.pt; not a robotplan model folder")
    return spec, torch.load(weights, map_location=device, weights_only=True)


def write_model_folder(model: nn.Module, spec, folder: Path) -> None:
    """``weights.pt`` (state_dict) and ``spec.json`` into ``folder``, each written whole."""
    folder.mkdir(parents=True, exist_ok=True)
    tmp = folder / ".weights.pt.tmp"
    torch.save(model.state_dict(), tmp)
    os.replace(tmp, folder / "weights.pt")
    tmp = folder / ".spec.json.tmp"
    tmp.write_text(json.dumps(asdict(spec), indent=1))
    os.replace(tmp, folder / "spec.json")
