"""Training and evaluating F_q (:mod:`robotplan.pushing.models.rigid`) on push data.

Two losses (``TrainConfig.rigid_loss``): ``"delta"``, the ground-truth Δq of each step from
the simulator's poses about the pivot the SDF defines
(:func:`~robotplan.pushing.models.rigid.moved_pivot_delta`), its squared error in units of the
spec's ``out_scale`` (m) and ``turn_scale`` (rad); ``"sdf"``, the SDFs alone: eq. (5)
through the transform, φ1_{t−1}(T(Δq)⁻¹x) against φ1_t(x) at query points
(:func:`sdf_space_loss`), in units of ``out_scale``. The
run is seeded and resumable as :func:`robotplan.pushing.training.train.train` is (batches from a
permutation per ``(seed, epoch)``, ``checkpoint.pt`` every few minutes and at the end).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import torch
from torch import Tensor

from robotplan.geometry.transforms import planar_to_world
from robotplan.models.spec import DynamicsSpec
from robotplan.pushing.models.rigid import (
    RigidMotion,
    delta_in_frame,
    moved_pivot_delta,
    object_frame,
    save_rigid,
    sdf_pivot,
    transform_points,
)
from robotplan.pushing.models.symmetry import symmetric_delta_q
from robotplan.pushing.training.model_card import earlier_stages
from robotplan.pushing.training.samples import PushSamples, SampleBatch
from robotplan.pushing.training.train import (
    WINDOW_AUGMENTS,
    TrainConfig,
    augmented,
    query_points,
    validation_indices,
)
from robotplan.training.loop import (
    Run,
    epoch_batch,
    load_checkpoint,
    run_steps,
    write_training_record,
)

__all__ = ["PLACEMENT_REACH", "WINDOW_AUGMENTS", "delta_q_predictions",
           "rigid_targets", "sdf_space_loss", "table5_errors", "train_rigid", "turn_gain",
           "window_placements"]

PLACEMENT_REACH = TrainConfig.placement_reach
"""m: how far "placements" moves the window's origin from the centroid by default
(``TrainConfig.placement_reach``); at 6 cm the largest footprint (half-diagonal 0.21 m) and
a pusher touching it stay inside the 0.64 m window."""


def rigid_targets(batch: SampleBatch, grid: Tensor, shape: tuple[int, int],
                  frame: str = "table", placement: Tensor | None = None
                  ) -> tuple[Tensor, Tensor, Tensor]:
    """The model inputs ``(B, 3, H, W)``, the pivots ``(B, 2)`` and the true Δq ``(B, 3)``,
    for X_h (``grid (N, 2)``) in the model's ``frame``: the table's, with the pivot read from
    the grid (:func:`sdf_pivot`) and Δq in the table frame; or the object's at t−1, with the
    footprint's centroid as the pivot and Δq in that frame. Where given, ``placement (B, 3)``
    = (x, y, yaw) places the window in that frame (X_OF): its origin, the pivot, moved by
    (x, y) and its axes turned by yaw from the body's."""
    if frame == "object":
        X_F = object_frame(batch.object_prev, batch.centroid)
        if placement is not None:
            X_F = torch.cat((planar_to_world(placement[:, None, :2], X_F)[:, 0],
                             X_F[:, 2:] + placement[:, 2:]), 1)
        pivot = X_F[:, :2]
        true = moved_pivot_delta(pivot, batch.object_prev, batch.object_now)
        return (batch.inputs(grid, shape, X_F), pivot,
                delta_in_frame(true, X_F[:, 2], to_table=False))
    inputs = batch.inputs(grid, shape)
    pivot = sdf_pivot(inputs[:, 0].flatten(1), grid)
    return inputs, pivot, moved_pivot_delta(pivot, batch.object_prev, batch.object_now)


def window_placements(cfg: TrainConfig, step: int, n: int) -> Tensor:
    """The object-frame window placements X_OF ``(n, 3)`` of training step ``step`` under
    ``cfg.augment``, drawn from ``(seed, step)`` so a resumed run sees the same ones:
    "headings", the axes at a uniform heading; "placements", also the origin moved
    uniformly within ``cfg.placement_reach`` of the centroid, so that the object is seen off
    the window's centre, about pivots other than its centroid, as on a table-fixed grid."""
    rng = np.random.default_rng([cfg.seed, 13, step])
    yaw = rng.uniform(-math.pi, math.pi, n)
    xy = np.zeros((n, 2))
    if cfg.augment == "placements":
        r = cfg.placement_reach * np.sqrt(rng.uniform(0.0, 1.0, n))
        a = rng.uniform(-math.pi, math.pi, n)
        xy = np.stack((r * np.cos(a), r * np.sin(a)), 1)
    return torch.as_tensor(np.concatenate((xy, yaw[:, None]), 1), dtype=torch.float32)


def sdf_space_loss(delta: Tensor, phi_prev_grid: Tensor, pivot: Tensor, phi_now: Tensor,
                   points: Tensor, bounds: tuple[float, float, float, float]) -> Tensor:
    """Eq. (5) through the rigid transform: the mean over samples and ``points (B, N, 2)`` of
    (φ1_{t−1}(T(Δq)⁻¹x) − φ1_t(x))², φ1_{t−1} read from its grid ``(B, H, W)`` on X_h
    (``bounds``: x_min, x_max, y_min, y_max; cell centres) by bilinear interpolation,
    ``phi_now (B, N)`` the observed φ1_t at the points."""
    back = transform_points(points, pivot, delta, inverse=True)
    x0, x1, y0, y1 = bounds
    where = torch.stack((2 * (back[..., 0] - x0) / (x1 - x0) - 1,
                         2 * (back[..., 1] - y0) / (y1 - y0) - 1), -1)
    phi = torch.nn.functional.grid_sample(phi_prev_grid[:, None], where[:, None],
                                          mode="bilinear", padding_mode="border",
                                          align_corners=False)[:, 0, 0]
    return (phi - phi_now).pow(2).mean()


@torch.no_grad()
def delta_q_predictions(model: RigidMotion, batch: SampleBatch, grid: Tensor,
                        shape: tuple[int, int], views: int = 1, chunk: int = 64
                        ) -> tuple[Tensor, Tensor, Tensor]:
    """Predicted and true Δq, each ``(B, 3)`` in m, m, rad in the table frame, about the
    pivots ``(B, 2)`` (table frame) the model's frame defines. With ``views`` 4 or 8 the
    prediction is averaged over the window's quarter turns (and mirrors)
    (:func:`~robotplan.pushing.models.symmetry.symmetric_delta_q`)."""
    preds, trues, pivots = [], [], []
    frame = model.spec.frame
    for i in range(0, len(batch.radius), chunk):
        sub = batch.slice(i, i + chunk)
        inputs, pivot, true = rigid_targets(sub, grid, shape, frame)
        pred = symmetric_delta_q(model, inputs, views)
        if frame == "object":
            yaw = sub.object_prev[:, 2]
            pred, true = delta_in_frame(pred, yaw), delta_in_frame(true, yaw)
        preds.append(pred)
        trues.append(true)
        pivots.append(pivot)
    return torch.cat(preds), torch.cat(trues), torch.cat(pivots)


def turn_gain(pred: np.ndarray, true: np.ndarray) -> float:
    """The least-squares slope of predicted on true turns (1: turns as much as the world)."""
    t = true[:, 2]
    return float(pred[:, 2] @ t / max(float(t @ t), 1e-12))


def table5_errors(pred: np.ndarray, true: np.ndarray) -> dict:
    """Paper Tab. 5 columns: |error| of x, y in mm and α in degrees, [mean, std]."""
    err = np.abs(pred - true) * np.array([1e3, 1e3, 180 / math.pi])
    return {key: [round(float(err[:, k].mean()), 3), round(float(err[:, k].std()), 3)]
            for k, key in enumerate(("x_mm", "y_mm", "alpha_deg"))}


def train_rigid(cfg: TrainConfig, resume: bool = False, progress: bool = True) -> dict:
    """Run (or resume) F_q training with ``cfg.rigid_loss``; returns the last validation
    row (Δq errors against the ground truth, whichever loss trains)."""
    if cfg.rigid_loss not in ("delta", "sdf"):
        raise ValueError(f"rigid_loss {cfg.rigid_loss!r}: expected 'delta' or 'sdf'")
    spec = DynamicsSpec(**{"encoder": "joint", **cfg.spec, "kind": "rigid"})
    if spec.frame == "object" and (cfg.rigid_loss != "delta" or cfg.augment == "turns"):
        raise ValueError("an object-frame F_q trains on the simulator's Δq (rigid_loss "
                         "'delta'), without turns (they leave its inputs unchanged)")
    if cfg.augment in WINDOW_AUGMENTS and spec.frame != "object":
        raise ValueError(f"augment {cfg.augment!r} places an object-frame F_q's window; "
                         "this F_q's X_h is the table's")
    out, device = Path(cfg.out), torch.device(cfg.device)
    ckpt_path = out / "checkpoint.pt"
    torch.manual_seed(cfg.seed)
    model = RigidMotion(spec).to(device)
    opt = torch.optim.Adam(model.parameters(), lr=cfg.lr)
    if cfg.init_weights and not resume:
        model.load_state_dict(torch.load(cfg.init_weights, map_location=device,
                                         weights_only=True))
    run = load_checkpoint(ckpt_path, model, opt, device) if resume else Run()
    stages = earlier_stages(cfg.init_weights)  # read before this run overwrites that folder
    samples = PushSamples(cfg.data, cfg.scenes)
    train_idx, val_idx = samples.split_by_scene(cfg.val_fraction, cfg.seed)
    val_batch = samples.batch(validation_indices(samples, val_idx, cfg.val_samples, cfg.seed),
                              device=device)
    ws = spec.workspace()
    grid = ws.points().reshape(-1, 2).to(device)
    per_epoch = max(1, len(train_idx) // cfg.batch)

    def validate() -> dict:
        model.eval()
        pred, true, _ = (v.cpu().numpy() for v in
                         delta_q_predictions(model, val_batch, grid, ws.shape))
        model.train()
        c = val_batch.contact.cpu().numpy()
        row = {"step": run.step, "epoch": round(run.step / per_epoch, 3),
               "minutes": round(run.seconds / 60, 1),
               "val_delta_q_error": {"contact": table5_errors(pred[c], true[c]),
                                     "free": table5_errors(pred[~c], true[~c])},
               "val_turn_gain": round(turn_gain(pred[c], true[c]), 3)}
        run.history.append(row)
        save_rigid(model, out)
        write_training_record(out, cfg, run, {"train": len(train_idx), "val": len(val_idx)},
                              device, stages=stages)
        return row

    batch_of = epoch_batch(train_idx, cfg.batch, cfg.seed)

    def step_loss(step: int) -> torch.Tensor:
        batch, placement = samples.batch(batch_of(step), device=device), None
        if cfg.augment in WINDOW_AUGMENTS:
            placement = window_placements(cfg, step, len(batch.radius)).to(batch.radius)
        else:
            batch = augmented(batch, cfg, ws, step)
        inputs, pivot, true = rigid_targets(batch, grid, ws.shape, spec.frame, placement)
        if cfg.rigid_loss == "sdf":
            gen = torch.Generator().manual_seed(cfg.seed * 1_000_003 + step)
            pts = query_points(batch, cfg.points, cfg.near_share, ws, gen).to(device)
            return sdf_space_loss(model(inputs), inputs[:, 0], pivot, batch.phi1_now(pts),
                                  pts, ws.bounds) / spec.out_scale**2
        return ((model(inputs) - true) / model.scale).pow(2).mean()

    out.mkdir(parents=True, exist_ok=True)
    return run_steps(cfg, run, model, opt, ckpt_path, step_loss, validate, per_epoch,
                     "train rigid", ("rms", lambda v: v**0.5, ".3f"), progress)
