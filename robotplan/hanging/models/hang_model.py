"""H_hang, the learned kinematic success model of mug hanging (paper §5.2, app. H.1): the SDFs
of the mug and of the hook on the grid X_h (40 × 40 × 40, 1 cm) stacked as two channels, three
3D convolutions (3, 5, 5 channels, kernels 3, 5, 5, strides 1, 2, 2, ReLU), a linear layer
to 200 features, an MLP of three hidden layers of 300 (ReLU) and one output. Trained with
eq. (21), H ≈ 0 where the configuration hangs and H > 0 where it does not.

The paper's baselines (app. A, Tab. 3) read other object representations of the same grids
(``HangSpec.representation``): the occupancy measure ψ = sign(φ) or ψ_s = tanh(b φ) through
the same convolutions, or each object's boundary cloud (marching-cubes vertices, eq. 12)
through a PointNet or PointNet++, whose features per object replace the convolutions'."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Literal

import torch
from torch import Tensor, nn

from robotplan.models.encoder import represent_grids
from robotplan.models.pointnet import cloud_encoder
from robotplan.models.spec import read_model_folder, write_model_folder

__all__ = ["HANG_THRESHOLDS", "HangSpec", "HangSuccess", "grid_lattice", "hang_loss",
           "load_hang_model", "save_hang_model"]


# the paper's feasibility thresholds κ1, κ2, κ3 (app. A.5): H_hang < κ predicts success
HANG_THRESHOLDS = {"k1": 0.15, "k2": 1.5, "k3": 0.015}


@dataclass(frozen=True)
class HangSpec:
    """Constructor arguments of :class:`HangSuccess` and the grid it reads (``spec.json``)."""

    kind: Literal["hang"] = "hang"
    cells: int = 40
    size: float = 0.4  # edge of X_h (m)
    below_arm: float = 0.25  # X_h's floor below the top of the hook's post (m)
    channels: tuple[int, ...] = (3, 5, 5)
    kernels: tuple[int, ...] = (3, 5, 5)
    strides: tuple[int, ...] = (1, 2, 2)
    features: int = 200
    hidden: tuple[int, ...] = (300, 300, 300)
    sdf_scale: float = 10.0  # input SDF values (m) and cloud points (m) are multiplied by this
    # what the network reads of each grid: the SDF (the paper's proposal), the occupancy
    # measure ψ = sign(φ) (eq. 10) or ψ_s = tanh(b φ) (eq. 11), or the boundary's point cloud
    # (eq. 12), as the paper's baselines (app. A.5)
    representation: Literal["sdf", "occupancy", "smooth_occupancy", "pointcloud"] = "sdf"
    occupancy_sharpness: float = 1000.0  # b of ψ_s (1/m); the paper's hanging baseline: 1000
    cloud_points: int = 512  # points per boundary cloud (pointcloud)
    cloud_widths: tuple[int, ...] = (64, 128, 256)  # PointNet's per-point MLP (pointcloud)
    cloud_encoder: Literal["pointnet", "pointnet2"] = "pointnet"
    cloud_centroids: int = 64  # PointNet++'s set abstraction (pointcloud, pointnet2)
    cloud_neighbours: int = 16
    cloud_local_widths: tuple[int, ...] = (32, 64)
    cloud_local_scale: float = 50.0  # offsets from a centroid (m) are multiplied by this
    extra: dict = field(default_factory=dict)  # free-form notes (not used by the network)

    @classmethod
    def from_json(cls, data: dict) -> HangSpec:
        kw = dict(data)
        for k in ("channels", "kernels", "strides", "hidden", "cloud_widths",
                  "cloud_local_widths"):
            if k in kw:
                kw[k] = tuple(kw[k])
        return cls(**kw)

    def as_dict(self) -> dict:
        return asdict(self)


def _conv_out(n: int, kernel: int, stride: int) -> int:
    return (n - kernel) // stride + 1


def grid_lattice(spec: HangSpec) -> Tensor:
    """X_h's cell centres about its centre ``(C, C, C, 3)``, indexed (x, y, z), m."""
    h = spec.size / spec.cells
    axis = (torch.arange(spec.cells, dtype=torch.float32) + 0.5) * h - spec.size / 2
    return torch.stack(torch.meshgrid(axis, axis, axis, indexing="ij"), -1)


class HangSuccess(nn.Module):
    """``forward(grids (B, 2, C, C, C)) → H (B,)``: grids are the mug's and the hook's SDF
    values (m) at the cell centres of X_h, indexed (x, y, z); the network reads them in the
    spec's ``representation``."""

    def __init__(self, spec: HangSpec = HangSpec()) -> None:
        super().__init__()
        self.spec = spec
        if spec.representation == "pointcloud":
            self.encoder = cloud_encoder(spec, grid_lattice(spec), spec.features)
            width = 2 * spec.features  # one feature vector per object
        else:
            convs, c_in, n = [], 2, spec.cells
            for c_out, k, s in zip(spec.channels, spec.kernels, spec.strides, strict=True):
                convs += [nn.Conv3d(c_in, c_out, k, s), nn.ReLU()]
                c_in, n = c_out, _conv_out(n, k, s)
            self.encoder = nn.Sequential(*convs, nn.Flatten(),
                                         nn.Linear(c_in * n**3, spec.features))
            width = spec.features
        layers = []
        for h in spec.hidden:
            layers += [nn.Linear(width, h), nn.ReLU()]
            width = h
        self.head = nn.Sequential(*layers, nn.Linear(width, 1))

    def forward(self, grids: Tensor) -> Tensor:
        spec = self.spec
        if spec.representation == "pointcloud":
            return self.head(self.encoder(grids)).squeeze(-1)
        read, _ = represent_grids(grids, spec.representation, spec.occupancy_sharpness)
        # SDF values (m) are scaled to unit range; occupancy measures are in [-1, 1] already
        scale = spec.sdf_scale if spec.representation == "sdf" else 1.0
        return self.head(self.encoder(read * scale)).squeeze(-1)


def hang_loss(h: Tensor, hangs: Tensor) -> Tensor:
    """Eq. (21), averaged: y H² + (1 − y) exp(−H), so that H → 0 where the mug hangs
    (y = 1) and H grows where it does not."""
    y = hangs.to(h.dtype)
    return (y * h.square() + (1 - y) * torch.exp(-h)).mean()


def save_hang_model(model: HangSuccess, folder: Path) -> None:
    write_model_folder(model, model.spec, folder)


def load_hang_model(folder: str | Path, device: str | torch.device = "cpu") -> HangSuccess:
    spec, state = read_model_folder(folder, ("hang",), device, spec_type=HangSpec)
    model = HangSuccess(spec).to(device)
    model.load_state_dict(state)
    return model.eval()
