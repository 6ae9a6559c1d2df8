"""Push samples (t−1, t) from a data folder, with their SDFs rendered on the fly in torch.

Boxes and L-shapes are drawn by the exact L-shape SDF with per-sample parameters (a box is
the L whose thickness is its full height), so a whole batch of mixed shapes renders in one
vectorised call. Other footprints (the unseen families of Tab. 6) render sample by sample
through their own exact SDFs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from pathlib import Path

import numpy as np
import torch
from torch import Tensor

from robotplan.geometry.transforms import planar_to_body, planar_to_world
from robotplan.pushing.training.footprints import LSHAPE
from robotplan.pushing.training.push_data import load_shards, scene_footprint
from robotplan.sdf import Shape2D
from robotplan.sdf.closed_form import lshape_sdf, safe_hypot
from robotplan.sdf.footprint import footprint_centroid

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

    params: Tensor  # (B, 3) (w/2, h/2, thickness); for other footprints their bounding box
    object_prev: Tensor  # (B, 3)
    object_now: Tensor  # (B, 3)
    radius: Tensor  # (B,)
    pusher_prev: Tensor  # (B, 2)
    pusher_now: Tensor  # (B, 2)
    contact: Tensor  # (B,) bool
    shapes: tuple[Shape2D, ...] | None = None  # per sample, where not all are boxes and Ls
    centroid: Tensor | None = None  # (B, 2) the footprint's area centroid, body frame

    def _phi1(self, X_WB: Tensor, points: Tensor) -> Tensor:
        if self.shapes is None:
            return object_sdf(self.params, X_WB, points)
        p = planar_to_body(points, X_WB)  # (B, N, 2)
        return torch.stack([shape.sdf(p[b]) for b, shape in enumerate(self.shapes)])

    def phi1_prev(self, points: Tensor) -> Tensor:
        """φ1_{t−1} at ``points (B or 1, N, 2)`` → ``(B, N)``."""
        return self._phi1(self.object_prev, points)

    def phi1_now(self, points: Tensor) -> Tensor:
        """φ1_t at ``points (B or 1, N, 2)`` → ``(B, N)``."""
        return self._phi1(self.object_now, points)

    def slice(self, start: int, stop: int) -> SampleBatch:
        """Samples ``start`` to ``stop`` of the batch."""
        return SampleBatch(**{f.name: None if getattr(self, f.name) is None
                              else getattr(self, f.name)[start:stop] for f in fields(self)})

    def turned(self, quarter_turns: Tensor, center: tuple[float, float]) -> SampleBatch:
        """The same samples with the whole scene turned by ``quarter_turns (B,)`` × 90° about
        ``center``, the centre of X_h: an exact symmetry of the world (isotropic friction,
        gravity along z) and, on a square grid centred there, of the rendered inputs too, so
        a trainer can use it to show each push in four orientations."""
        angle = quarter_turns.to(self.object_prev) * (math.pi / 2)
        c, s = torch.cos(angle).round(), torch.sin(angle).round()  # exact 0, ±1
        o = torch.as_tensor(center, dtype=self.object_prev.dtype, device=angle.device)

        def xy(p: Tensor) -> Tensor:
            d = p[:, :2] - o
            return o + torch.stack((c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1]), 1)

        def pose(p: Tensor) -> Tensor:
            return torch.cat((xy(p), (p[:, 2] + angle)[:, None]), 1)

        return replace(self, object_prev=pose(self.object_prev),
                       object_now=pose(self.object_now), pusher_prev=xy(self.pusher_prev),
                       pusher_now=xy(self.pusher_now))

    def inputs(self, grid_points: Tensor, shape: tuple[int, int], frame: Tensor | None = None
               ) -> Tensor:
        """The model inputs φ1_{t−1}, φ2_{t−1}, φ2_t on X_h: ``(B, 3, H, W)``; X_h's points
        ``(N, 2)`` in the table frame, or in the planar frames ``frame (B, 3)``."""
        g = grid_points[None] if frame is None else planar_to_world(grid_points[None], frame)
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
        # footprints other than boxes and L-shapes, each rendered by its own SDF
        self.footprints: list[Shape2D] | None = (
            [scene_footprint(d, k) for k in range(len(lengths))]
            if (d["shape_type"] > LSHAPE).any() else None)
        self.centroids = np.array([footprint_centroid(scene_footprint(d, k))
                                   for k in range(len(lengths))])

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
            shapes=(None if self.footprints is None
                    else tuple(self.footprints[k] for k in self.scene[idx])),
            centroid=t(self.centroids[self.scene[idx]]),
        )
