"""Learned rigid motion of a pushed object from SDFs: F_q (paper app., eqs. 15, 17).

The encoder of the dynamics models (:class:`~robotplan.models.encoder.SDFEncoder`) reads
φ1_{t−1}, φ2_{t−1}, φ2_t on X_h; an MLP maps its features to the object's rigid motion over
the step, ``Δq = (Δx, Δy, Δα)``: a turn by Δα about the pivot, then a shift by (Δx, Δy),
all in the table frame. The pivot is a point the SDF itself defines, the area centroid of
φ1_{t−1} < 0 on X_h (:func:`sdf_pivot`), so the model needs no pose of the object: the
next SDF is φ1_t = T(Δq)[φ1_{t−1}], φ1_t(x) = φ1_{t−1}(T(Δq)⁻¹ x).

With ``spec.frame == "object"`` X_h is attached to the object at t−1 (:func:`object_frame`):
its origin is the pivot and its axes the body's, and the network's Δq is given in that frame
(:func:`delta_in_frame` turns it to the table's). Planar pushing on a uniform table does not
change when the whole scene is moved or turned, so such a model sees each push the same
wherever and at whatever heading it happens, and learns from far fewer samples.
"""

from __future__ import annotations

import math
from pathlib import Path

import torch
from torch import Tensor, nn

from robotplan.geometry.transforms import planar_to_world
from robotplan.models.encoder import SDFEncoder
from robotplan.models.pointnet import cloud_encoder
from robotplan.models.spec import DynamicsSpec, read_model_folder, write_model_folder
from robotplan.pushing.models.encoder_passes import EncoderPasses

__all__ = ["RigidMotion", "delta_in_frame", "load_rigid", "moved_pivot_delta", "moved_pose",
           "object_frame", "save_rigid", "sdf_pivot", "transform_points"]


def sdf_pivot(phi: Tensor, grid_points: Tensor) -> Tensor:
    """The area centroid of ``phi < 0``: ``phi (B, N)`` on ``grid_points (N, 2)`` → ``(B, 2)``
    (the grid's centre for an empty region)."""
    inside = (phi < 0).to(phi.dtype)
    area = inside.sum(1, keepdim=True)
    centre = grid_points.mean(0)
    return torch.where(area > 0, inside @ grid_points / area.clamp_min(1.0), centre)


def object_frame(X_WB: Tensor, centroid_B: Tensor) -> Tensor:
    """The object frame of poses ``X_WB (B, 3)`` as planar poses ``(B, 3)``: the origin at
    the footprint's centroid ``centroid_B (B, 2)`` (body frame), the axes the body's."""
    return torch.cat((planar_to_world(centroid_B[:, None], X_WB)[:, 0], X_WB[:, 2:]), 1)


def delta_in_frame(delta: Tensor, yaw: Tensor, to_table: bool = True) -> Tensor:
    """Δq ``(B, 3)`` given in frames of heading ``yaw (B,)`` in the table frame (or, with
    ``to_table`` False, the table's Δq in those frames): the shift turned, the turn kept."""
    c, s = torch.cos(yaw), torch.sin(yaw)
    s = s if to_table else -s
    return torch.stack((c * delta[:, 0] - s * delta[:, 1], s * delta[:, 0] + c * delta[:, 1],
                        delta[:, 2]), 1)


def moved_pivot_delta(pivot: Tensor, X_prev: Tensor, X_now: Tensor) -> Tensor:
    """The Δq ``(B, 3)`` that takes a body from pose ``X_prev`` to ``X_now`` (``(B, 3)``,
    x, y, yaw) as a turn about ``pivot (B, 2)`` followed by a shift."""
    c, s = torch.cos(X_prev[:, 2]), torch.sin(X_prev[:, 2])
    rel = pivot - X_prev[:, :2]
    body = torch.stack((c * rel[:, 0] + s * rel[:, 1], -s * rel[:, 0] + c * rel[:, 1]), 1)
    c2, s2 = torch.cos(X_now[:, 2]), torch.sin(X_now[:, 2])
    moved = X_now[:, :2] + torch.stack((c2 * body[:, 0] - s2 * body[:, 1],
                                        s2 * body[:, 0] + c2 * body[:, 1]), 1)
    turn = torch.remainder(X_now[:, 2] - X_prev[:, 2] + math.pi, 2 * math.pi) - math.pi
    return torch.cat((moved - pivot, turn[:, None]), 1)


def transform_points(points: Tensor, pivot: Tensor, delta: Tensor, inverse: bool = False
                     ) -> Tensor:
    """T(Δq) x (or T(Δq)⁻¹ x): ``points (B, N, 2)``, ``pivot (B, 2)``, ``delta (B, 3)``."""
    turn = -delta[:, 2] if inverse else delta[:, 2]
    c, s = torch.cos(turn)[:, None], torch.sin(turn)[:, None]
    p = pivot[:, None, :]
    shift = delta[:, None, :2]
    rel = points - p - shift if inverse else points - p
    rot = torch.stack((c * rel[..., 0] - s * rel[..., 1], s * rel[..., 0] + c * rel[..., 1]), -1)
    return p + rot if inverse else p + rot + shift


def moved_pose(X_WB: Tensor, pivot: Tensor, delta: Tensor) -> Tensor:
    """Poses ``X_WB (B, 3)`` after the steps ``delta (B, 3)``: T(Δq) about ``pivot (B, 2)``
    (table frame) applied to the body's origin, the heading turned by Δα; the inverse of
    :func:`moved_pivot_delta`."""
    origin = transform_points(X_WB[:, None, :2], pivot, delta)[:, 0]
    return torch.cat((origin, X_WB[:, 2:] + delta[:, 2:]), 1)


class RigidMotion(EncoderPasses, nn.Module):
    """F_q: ``inputs (B, 3, H, W)`` → Δq ``(B, 3)`` in m, m, rad (see the module docstring).

    ``spec.out_scale`` (m) and ``spec.turn_scale`` (rad) scale the network's outputs, so that
    it works at unit scale; ``spec.kind`` is ``"rigid"``."""

    def __init__(self, spec: DynamicsSpec | None = None) -> None:
        super().__init__()
        spec = self.spec = spec or DynamicsSpec(kind="rigid", encoder="joint")
        self.encoder = (cloud_encoder(spec) if spec.representation == "pointcloud"
                        else SDFEncoder(spec))
        layers: list[nn.Module] = []
        width = 3 * spec.sdf_features
        for h in spec.hidden:
            layers += [nn.Linear(width, h), nn.ReLU()]
            width = h
        layers.append(nn.Linear(width, 3))
        self.head = nn.Sequential(*layers)
        self.register_buffer("scale", torch.tensor(
            [spec.out_scale, spec.out_scale, spec.turn_scale]))

    def features(self, inputs: Tensor) -> Tensor:
        if self.spec.encoder == "joint":
            return self.encoder(inputs)
        return self.encoder(inputs.flatten(0, 1)[:, None]).reshape(inputs.shape[0], -1)

    def forward(self, inputs: Tensor) -> Tensor:
        return self.head(self.features(inputs)) * self.scale


def save_rigid(model: RigidMotion, folder: Path) -> None:
    """``weights.pt`` (state_dict) and ``spec.json`` into ``folder``, each written whole."""
    write_model_folder(model, model.spec, folder)


def load_rigid(folder: str | Path, device: str | torch.device = "cpu") -> RigidMotion:
    """An F_q model folder (``spec.json`` + ``weights.pt``, read with ``weights_only=True``)."""
    spec, state = read_model_folder(folder, ("rigid",), device)
    model = RigidMotion(spec)
    model.load_state_dict(state)
    return model.to(device).eval()
