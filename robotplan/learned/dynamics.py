"""Learned pushing dynamics in SDF space: F (eq. 3) and F_flow (eq. 4), network of app. I.1.

Each of φ1_{t−1}, φ2_{t−1}, φ2_t, rendered on the table grid X_h (140 × 140), is encoded by
one shared encoder (conv 3, 5, 5 channels, kernels 3, 5, 5, strides 1, 2, 2, ReLU, then a
linear layer to 200 features); the query point x is encoded by a linear layer to 100
features; the 700 features go through an MLP (300, 300, ReLU) to one output:

* ``kind="flow"``: F_flow, so that φ1_t(x) = φ1_{t−1}(x) + F_flow(…)(x)   (eq. 4)
* ``kind="direct"``: F, so that φ1_t(x) = F(…)(x)                          (eq. 3)

The first MLP layer is split into its SDF part (600 → 300, the same for every query point)
and its point part (100 → 300), so that planning evaluates the SDF part once per step and
the point part once per quadrature point.
"""

from __future__ import annotations

import json
import warnings
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Literal

import torch
from torch import Tensor, nn

__all__ = ["DynamicsSpec", "PushDynamics", "load_model", "save_model"]


@dataclass(frozen=True)
class DynamicsSpec:
    """Constructor arguments of :class:`PushDynamics` (written to ``spec.json``)."""

    kind: Literal["flow", "direct"] = "flow"
    grid: tuple[int, int] = (140, 140)
    workspace_center: tuple[float, float] = (0.0, 0.0)
    workspace_size: tuple[float, float] = (1.4, 1.4)
    channels: tuple[int, ...] = (3, 5, 5)
    kernels: tuple[int, ...] = (3, 5, 5)
    strides: tuple[int, ...] = (1, 2, 2)
    sdf_features: int = 200
    point_features: int = 100
    hidden: tuple[int, ...] = (300, 300)
    sdf_scale: float = 5.0  # input SDF values (m) are multiplied by this
    out_scale: float = 0.01  # the network's output is multiplied by this (m)
    extra: dict = field(default_factory=dict)  # free-form notes (not used by the network)

    @classmethod
    def from_json(cls, data: dict) -> DynamicsSpec:
        kw = dict(data)
        for k in ("grid", "workspace_center", "workspace_size", "channels", "kernels",
                  "strides", "hidden"):
            if k in kw:
                kw[k] = tuple(kw[k])
        return cls(**kw)


class SDFEncoder(nn.Module):
    """φ(X_h) ``(M, 1, H, W)`` → features ``(M, sdf_features)``."""

    def __init__(self, spec: DynamicsSpec) -> None:
        super().__init__()
        layers: list[nn.Module] = []
        c_in, (h, w) = 1, spec.grid
        for c, k, s in zip(spec.channels, spec.kernels, spec.strides, strict=True):
            layers += [nn.Conv2d(c_in, c, k, stride=s), nn.ReLU()]
            c_in, h, w = c, (h - k) // s + 1, (w - k) // s + 1
        self.conv = nn.Sequential(*layers)
        self.linear = nn.Linear(c_in * h * w, spec.sdf_features)
        self.scale = spec.sdf_scale

    def forward(self, grids: Tensor) -> Tensor:
        x = grids * self.scale
        # A one-channel first convolution runs ~4x faster (forward and backward) on the CPU
        # without oneDNN; the later ones are faster with it.
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            with torch.backends.mkldnn.flags(enabled=x.device.type != "cpu"):
                x = self.conv[0](x)
        return self.linear(self.conv[1:](x).flatten(1))


class PushDynamics(nn.Module):
    """F_flow or F for a pusher (φ2) moving an object (φ1); see the module docstring."""

    def __init__(self, spec: DynamicsSpec = DynamicsSpec()) -> None:
        super().__init__()
        self.spec = spec
        self.encoder = SDFEncoder(spec)
        self.point_encoder = nn.Linear(2, spec.point_features)
        first = spec.hidden[0]
        self.first_sdf = nn.Linear(3 * spec.sdf_features, first)  # carries the bias
        self.first_point = nn.Linear(spec.point_features, first, bias=False)
        rest: list[nn.Module] = []
        for a, b in zip(spec.hidden[:-1], spec.hidden[1:], strict=True):
            rest += [nn.Linear(a, b), nn.ReLU()]
        rest.append(nn.Linear(spec.hidden[-1], 1))
        self.head = nn.Sequential(*rest)
        self.register_buffer("center", torch.tensor(spec.workspace_center))
        self.register_buffer("half_size", torch.tensor(spec.workspace_size) / 2)

    # --- the split pieces (used as they are by the fast planner path) ---
    def encode(self, grids: Tensor) -> Tensor:
        """Encode single SDF grids ``(M, H, W)`` → ``(M, sdf_features)``."""
        return self.encoder(grids[:, None])

    def sdf_term(self, features: Tensor) -> Tensor:
        """``(B, 3 · sdf_features)`` (φ1_{t−1}, φ2_{t−1}, φ2_t) → first-layer term ``(B, H1)``."""
        return self.first_sdf(features)

    def point_term(self, points: Tensor) -> Tensor:
        """Query points ``(..., P, 2)`` in the table frame → first-layer term ``(..., P, H1)``."""
        return self.first_point(self.point_encoder((points - self.center) / self.half_size))

    def from_terms(self, sdf_term: Tensor, point_term: Tensor) -> Tensor:
        """``(B, H1)`` and ``(B or 1, P, H1)`` → the output ``(B, P)`` in metres."""
        h = torch.relu(sdf_term[:, None, :] + point_term)
        return self.head(h)[..., 0] * self.spec.out_scale

    # --- the whole model ---
    def forward(self, inputs: Tensor, points: Tensor) -> Tensor:
        """``inputs (B, 3, H, W)`` = φ1_{t−1}, φ2_{t−1}, φ2_t on X_h; ``points (B or 1, P, 2)``.

        Returns ``(B, P)``: F_flow(x) for ``kind="flow"``, φ1_t(x) for ``kind="direct"``.
        """
        B = inputs.shape[0]
        feats = self.encode(inputs.flatten(0, 1)).reshape(B, -1)
        return self.from_terms(self.sdf_term(feats), self.point_term(points))

    def predict_next(self, inputs: Tensor, points: Tensor, phi1_prev_at_points: Tensor
                     ) -> Tensor:
        """φ1_t at the points ``(B, P)``, for either kind."""
        out = self.forward(inputs, points)
        return phi1_prev_at_points + out if self.spec.kind == "flow" else out


def save_model(model: PushDynamics, folder: Path) -> None:
    """Write ``weights.pt`` (state_dict) and ``spec.json`` into ``folder``."""
    import os

    folder.mkdir(parents=True, exist_ok=True)
    tmp = folder / ".weights.pt.tmp"
    torch.save(model.state_dict(), tmp)
    os.replace(tmp, folder / "weights.pt")
    tmp = folder / ".spec.json.tmp"
    tmp.write_text(json.dumps(asdict(model.spec), indent=1))
    os.replace(tmp, folder / "spec.json")


def load_model(folder: str | Path, device: str | torch.device = "cpu") -> PushDynamics:
    """Load a model folder (``spec.json`` + ``weights.pt``, read with ``weights_only=True``)."""
    folder = Path(folder)
    for name in ("spec.json", "weights.pt"):
        if not (folder / name).is_file():
            raise FileNotFoundError(f"{folder}: no {name}; not a robotplan model folder")
    spec = DynamicsSpec.from_json(json.loads((folder / "spec.json").read_text()))
    model = PushDynamics(spec)
    state = torch.load(folder / "weights.pt", map_location=device, weights_only=True)
    model.load_state_dict(state)
    return model.to(device).eval()
