"""The constructor arguments of a dynamics model (``spec.json`` beside its weights) and the
dtype its head multiplies in."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import torch

from robotplan.base.arith import bfloat16_head

__all__ = ["DynamicsSpec", "head_matmul_dtype"]


def head_matmul_dtype(model_dtype: torch.dtype) -> torch.dtype:
    """The dtype of the head's hidden-to-hidden products: the model's own, or bfloat16 for a
    float32 model where the user opted in (:func:`robotplan.base.arith.bfloat16_head`)."""
    if model_dtype == torch.float32 and bfloat16_head():
        return torch.bfloat16
    return model_dtype


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
    out_scale: float = 0.01  # the network's output is multiplied by this (m)
    turn_scale: float = 0.05  # F_q's turn output is multiplied by this (rad)
    extra: dict = field(default_factory=dict)  # free-form notes (not used by the network)

    @classmethod
    def from_json(cls, data: dict) -> DynamicsSpec:
        kw = dict(data)
        for k in ("grid", "workspace_center", "workspace_size", "channels", "kernels",
                  "strides", "hidden"):
            if k in kw:
                kw[k] = tuple(kw[k])
        return cls(**kw)
