"""Training F_flow / F on push data: loss eq. (5) on random query points, held-out scenes.

The run is fixed by its arguments and seed (the shared loop:
:mod:`robotplan.training.loop`): batch ``b`` of epoch ``e`` is a slice of a permutation drawn
from ``(seed, e)``, the query points of step ``s`` come from
``(seed, s)``, so ``--resume`` continues exactly where a checkpoint left off.
Checkpoints (``checkpoint.pt``: model, optimiser, step; loaded with ``weights_only=True``)
are written every few minutes and at the end; the model folder (weights, spec, metrics,
model card) is refreshed at every validation.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import torch

from robotplan.geometry.transforms import planar_to_body
from robotplan.pushing.models.dynamics import DynamicsSpec, PushDynamics, save_model
from robotplan.pushing.models.rigid import object_frame
from robotplan.pushing.training.model_card import earlier_stages
from robotplan.pushing.training.samples import PushSamples, SampleBatch
from robotplan.sdf import Workspace
from robotplan.training.loop import (
    Run,
    epoch_batch,
    load_checkpoint,
    run_steps,
    write_training_record,
)

__all__ = ["AUGMENTS", "WINDOW_AUGMENTS", "TrainConfig", "augmented", "framed", "grid_rmse",
           "query_points", "scored_workspace", "train", "validation_indices"]

AUGMENTS = ("none", "turns", "headings", "placements")
WINDOW_AUGMENTS = ("headings", "placements")
"""Augmentations that place an object-frame F_q's window about the object (drawn where
its frame is built, :func:`robotplan.pushing.training.rigid.window_placements`)."""


@dataclass
class TrainConfig:
    data: str
    out: str
    kind: str = "flow"
    steps: int = 60_000
    batch: int = 32
    lr: float = 5e-4
    lr_min: float = 1e-5
    warmup: int = 500
    points: int = 256
    near_share: float = 0.25  # share of query points drawn near the object
    contact_share: float | None = None  # draw batches with this share of contact samples
    init_weights: str | None = None  # start from these weights (a state_dict file)
    val_fraction: float = 0.02
    val_samples: int = 128
    val_every: int = 2000
    seed: int = 0
    scenes: int | None = None
    device: str = "cpu"
    minutes: float | None = None  # stop (with a checkpoint) after this wall time
    checkpoint_minutes: float = 5.0
    command: str = ""
    spec: dict = field(default_factory=dict)  # DynamicsSpec overrides
    # F_q's loss: "delta", the ground-truth Δq; "sdf", eq. (5) through T(Δq) on SDFs alone
    rigid_loss: str = "delta"
    # "turns": each sample's scene turned by a random multiple of 90° about X_h's centre
    # (an exact symmetry, SampleBatch.turned), four orientations of every push; "headings"
    # (an object-frame F_q): X_h's axes at a random heading about the object, so that the
    # model sees each footprint at every heading, as a table-frame model does; "placements":
    # also the window's origin, the pivot, moved up to a few cm from the object's centroid
    augment: str = "none"
    placement_reach: float = 0.06  # m, "placements": see robotplan.pushing.training.rigid
    anneal_by_time: bool = False  # the cosine also ends when ``minutes`` run out


def query_points(batch: SampleBatch, n: int, near_share: float, ws: Workspace,
                  gen: torch.Generator) -> torch.Tensor:
    """``(B, n, 2)`` points: uniform on the table, plus a share within 10 cm of the object's
    bounding circle at t−1."""
    B = len(batch.radius)
    x0, x1, y0, y1 = ws.bounds
    u = torch.rand(B, n, 2, generator=gen)
    pts = torch.stack((x0 + (x1 - x0) * u[..., 0], y0 + (y1 - y0) * u[..., 1]), dim=-1)
    k = round(near_share * n)
    if k:
        # drawn on the CPU whatever the device: the same points for a seed everywhere
        reach = batch.params[:, :2].norm(dim=1).cpu() + 0.10  # (B,)
        ang = 2 * math.pi * torch.rand(B, k, generator=gen)
        rad = reach[:, None] * torch.rand(B, k, generator=gen).sqrt()
        near = batch.object_prev[:, None, :2].cpu() + torch.stack((rad * ang.cos(),
                                                                     rad * ang.sin()), -1)
        pts[:, :k] = near
    return pts


def augmented(batch: SampleBatch, cfg: TrainConfig, ws: Workspace, step: int) -> SampleBatch:
    """The batch of ``step`` as training sees it under ``cfg.augment``; the turns are drawn
    from ``(seed, step)`` so a resumed run sees the same ones."""
    if cfg.augment == "none":
        return batch
    if cfg.augment in WINDOW_AUGMENTS:
        raise ValueError(f"augment {cfg.augment!r} places an object-frame F_q's window, "
                         "drawn where its frame is built")
    if cfg.augment != "turns":
        raise ValueError(f"augment {cfg.augment!r}: expected one of {', '.join(AUGMENTS)}")
    k = np.random.default_rng([cfg.seed, 11, step]).integers(0, 4, len(batch.radius))
    return batch.turned(torch.as_tensor(k, device=batch.radius.device), tuple(ws.center))


def scored_workspace(spec: DynamicsSpec) -> Workspace:
    """The X_h that Tab. 2 scores a model on: a table-frame model's own grid; for an
    object-frame one, the table's default 140 × 140 grid over 1.4 m, the grid every other
    model is scored on (its own window only feeds the encoder)."""
    return spec.workspace() if spec.frame == "table" else DynamicsSpec().workspace()


def framed(spec: DynamicsSpec, batch: SampleBatch, grid: torch.Tensor,
           points: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """The model inputs ``(B, 3, H, W)`` on the model's X_h (``grid (N, 2)`` in its frame)
    and the query ``points (B or 1, P, 2)`` (table frame) as the model reads them: as they
    are for a table-frame model; for an object-frame one (``spec.frame == "object"``) X_h
    is attached to the object at t−1 (origin at the footprint's centroid, the body's axes,
    :func:`~robotplan.pushing.models.rigid.object_frame`) and the points are given in that frame.
    The predicted field is a function on the table either way: the frame moves with the
    object, the points with it."""
    shape = tuple(spec.grid)
    if spec.frame != "object":
        return batch.inputs(grid, shape), points
    X_F = object_frame(batch.object_prev, batch.centroid)
    return batch.inputs(grid, shape, X_F), planar_to_body(points, X_F)


def _target(model: PushDynamics, batch: SampleBatch, pts: torch.Tensor) -> torch.Tensor:
    now = model.values_read(batch.phi1_now(pts))
    return now - model.values_read(batch.phi1_prev(pts)) if model.spec.kind == "flow" else now


@torch.no_grad()
def grid_rmse(model: PushDynamics, batch: SampleBatch, stride: int = 1, chunk: int = 16
              ) -> tuple[np.ndarray, np.ndarray]:
    """Per-sample RMSE (m; of ψ for a model on an occupancy measure) over X_h (eq. 20,
    :func:`scored_workspace`) of the model and of the "no motion" baseline.

    ``stride`` > 1 evaluates every stride-th grid point in each direction (for quick checks).
    """
    spec = model.spec
    device = batch.params.device
    grid = spec.workspace().points(batch.params.dtype).to(device).reshape(-1, 2)
    table = scored_workspace(spec).points(batch.params.dtype).to(device)
    pts = table[::stride, ::stride].reshape(1, -1, 2)
    model_err, base_err = [], []
    for i in range(0, len(batch.radius), chunk):
        sub = batch.slice(i, i + chunk)
        inputs, model_pts = framed(spec, sub, grid, pts)
        prev = model.values_read(sub.phi1_prev(pts))
        now = model.values_read(sub.phi1_now(pts))
        pred = model.predict_next(inputs, model_pts, prev)
        model_err.append((pred - now).pow(2).mean(1).sqrt())
        base_err.append((prev - now).pow(2).mean(1).sqrt())
    return torch.cat(model_err).cpu().numpy(), torch.cat(base_err).cpu().numpy()


def validation_indices(samples: PushSamples, val_idx: np.ndarray, n: int, seed: int
                        ) -> np.ndarray:
    rng = np.random.default_rng([seed, 99])
    contact = val_idx[samples.contact[val_idx]]
    free = val_idx[~samples.contact[val_idx]]
    k = min(n // 2, len(contact), len(free)) if len(free) else min(n, len(contact))
    return np.concatenate([rng.choice(contact, min(len(contact), n - k), replace=False),
                           rng.choice(free, k, replace=False)])


def train(cfg: TrainConfig, resume: bool = False, progress: bool = True) -> dict:
    """Run (or resume) training; returns the last metrics."""
    out = Path(cfg.out)
    ckpt_path = out / "checkpoint.pt"
    device = torch.device(cfg.device)
    torch.manual_seed(cfg.seed)
    spec = DynamicsSpec(kind=cfg.kind, **cfg.spec)
    if "out_scale" not in cfg.spec and spec.representation != "sdf":
        # ψ changes by up to 2 where the boundary passes in one step
        spec = DynamicsSpec(**{**asdict(spec), "out_scale": 1.0})
    elif cfg.kind == "direct" and "out_scale" not in cfg.spec:
        spec = DynamicsSpec(**{**asdict(spec), "out_scale": 0.1})
    if spec.frame == "object" and cfg.augment != "none":
        raise ValueError(f"augment {cfg.augment!r}: an object-frame F_flow or F trains "
                         "without (its inputs are the same wherever the push happens)")
    model = PushDynamics(spec).to(device)
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
    ws, table = spec.workspace(), scored_workspace(spec)
    grid = ws.points().reshape(-1, 2).to(device)
    per_epoch = len(train_idx) // cfg.batch
    train_contact = train_idx[samples.contact[train_idx]]
    train_free = train_idx[~samples.contact[train_idx]]

    def validate() -> dict:
        model.eval()
        err, base = grid_rmse(model, val_batch, stride=2)
        model.train()
        c = val_batch.contact.cpu().numpy()
        row = {"step": run.step, "epoch": round(run.step / per_epoch, 3),
               "minutes": round(run.seconds / 60, 1),
               "val_rmse_mm": {"contact": round(1e3 * float(err[c].mean()), 3),
                               "free": round(1e3 * float(err[~c].mean()), 3)},
               "val_baseline_mm": {"contact": round(1e3 * float(base[c].mean()), 3),
                                   "free": round(1e3 * float(base[~c].mean()), 3)}}
        run.history.append(row)
        save_model(model, out)
        write_training_record(out, cfg, run, {"train": len(train_idx), "val": len(val_idx)},
                              device, stages=stages)
        return row

    batch_of = epoch_batch(train_idx, cfg.batch, cfg.seed)

    def step_loss(step: int) -> torch.Tensor:
        if cfg.contact_share is None:
            chosen = batch_of(step)
        else:  # balanced batches: the metric averages contact and free separately
            rng = np.random.default_rng([cfg.seed, 7, step])
            n_contact = round(cfg.contact_share * cfg.batch)
            chosen = np.concatenate([rng.choice(train_contact, n_contact),
                                     rng.choice(train_free, cfg.batch - n_contact)])
        batch = augmented(samples.batch(chosen, device=device), cfg, ws, step)
        gen = torch.Generator().manual_seed(cfg.seed * 1_000_003 + step)
        pts = query_points(batch, cfg.points, cfg.near_share, table, gen).to(device)
        inputs, model_pts = framed(spec, batch, grid, pts)
        return (model(inputs, model_pts) - _target(model, batch, pts)).pow(2).mean()

    out.mkdir(parents=True, exist_ok=True)
    return run_steps(cfg, run, model, opt, ckpt_path, step_loss, validate, per_epoch,
                     f"train {cfg.kind}", ("rmse_mm", lambda v: 1e3 * v**0.5, ".2f"),
                     progress)


