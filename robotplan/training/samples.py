"""Push samples (t−1, t) from a data folder, with their SDFs rendered on the fly in torch.

Objects are boxes or L-shapes; both are drawn by the exact L-shape SDF with per-sample
parameters (a box is the L whose thickness is its full height), so a whole batch of mixed
shapes renders in one vectorised call.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
from torch import Tensor

from robotplan.geometry.transforms import planar_to_body
from robotplan.sdf.closed_form import lshape_sdf, safe_hypot
from robotplan.training.push_data import load_shards

__all__ = ["PushSamples", "SampleBatch", "object_sdf", "pusher_sdf"]


def object_sdf(params: Tensor, X_WB: Tensor, points_W: Tensor) -> Tensor:
    """φ1 of a batch of objects: ``params (B, 3) = (w/2, h/2, thickness)``, poses ``(B, 3)``,
    points ``(B or 1, N, 2)`` → ``(B, N)``."""
    p = planar_to_body(points_W, X_WB)
    return lshape_sdf(p[..., 0], p[..., 1], params[:, 0:1], params[:, 1:2], params[:, 2:3])


def pusher_sdf(radius: Tensor, xy: Tensor, points_W: Tensor) -> Tensor:
    """φ2 of a batch of disc pushers: ``radius (B,)``, centres ``(B, 2)``, points
    ``(B or 1, N, 2)`` → ``(B, N)``."""
    d = points_W - xy[:, None, :]
    return safe_hypot(d[..., 0], d[..., 1]) - radius[:, None]


@dataclass
class SampleBatch:
    """B samples: object parameters, poses and pusher positions at t−1 and t."""

    params: Tensor  # (B, 3)
    object_prev: Tensor  # (B, 3)
    object_now: Tensor  # (B, 3)
    radius: Tensor  # (B,)
    pusher_prev: Tensor  # (B, 2)
    pusher_now: Tensor  # (B, 2)
    contact: Tensor  # (B,) bool

    def phi1_prev(self, points: Tensor) -> Tensor:
        return object_sdf(self.params, self.object_prev, points)

    def phi1_now(self, points: Tensor) -> Tensor:
        return object_sdf(self.params, self.object_now, points)

    def inputs(self, grid_points: Tensor, shape: tuple[int, int]) -> Tensor:
        """The model inputs φ1_{t−1}, φ2_{t−1}, φ2_t on X_h: ``(B, 3, H, W)``."""
        g = grid_points[None]
        fields = (self.phi1_prev(g), pusher_sdf(self.radius, self.pusher_prev, g),
                  pusher_sdf(self.radius, self.pusher_now, g))
        return torch.stack(fields, dim=1).reshape(len(self.radius), 3, *shape)


class PushSamples:
    """All (t−1, t) pairs of a push data folder."""

    def __init__(self, folder: str | Path, scenes: int | None = None) -> None:
        self.folder = Path(folder)
        d = load_shards(self.folder, scenes)
        self.data = d
        lengths = np.diff(d["offsets"])
        scene_of_state = np.repeat(np.arange(len(lengths)), lengths)
        first_of_scene = d["offsets"][:-1]
        is_first = np.zeros(len(scene_of_state), dtype=bool)
        is_first[first_of_scene] = True
        self.now = np.flatnonzero(~is_first)  # state index of t; t−1 is now − 1
        self.scene = scene_of_state[self.now]
        self.contact = d["contact"][self.now]
        half = d["size"] / 2
        self.params = np.stack([half[:, 0], half[:, 1], d["thickness"]], axis=1)

    @property
    def num_scenes(self) -> int:
        return len(self.data["scene_index"])

    def __len__(self) -> int:
        return len(self.now)

    def split_by_scene(self, val_fraction: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
        """Sample indices of training and validation scenes (no scene in both)."""
        rng = np.random.default_rng(seed)
        n_val = max(1, round(val_fraction * self.num_scenes))
        val_scenes = rng.choice(self.num_scenes, n_val, replace=False)
        is_val = np.isin(self.scene, val_scenes)
        return np.flatnonzero(~is_val), np.flatnonzero(is_val)

    def batch(self, idx: np.ndarray, dtype: torch.dtype = torch.float32,
              device: str | torch.device = "cpu") -> SampleBatch:
        d = self.data
        now = self.now[idx]

        def t(a: np.ndarray) -> Tensor:
            return torch.as_tensor(np.asarray(a), dtype=dtype, device=device)

        return SampleBatch(
            params=t(self.params[self.scene[idx]]),
            object_prev=t(d["object_pose"][now - 1]), object_now=t(d["object_pose"][now]),
            radius=t(d["pusher_radius"][self.scene[idx]]),
            pusher_prev=t(d["pusher_xy"][now - 1]), pusher_now=t(d["pusher_xy"][now]),
            contact=torch.as_tensor(self.contact[idx], device=device),
        )
