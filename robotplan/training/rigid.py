"""Training and evaluating F_q (:mod:`robotplan.models.rigid`) on push data.

Two losses (``TrainConfig.rigid_loss``): ``"delta"``, the ground-truth Δq of each step from
the simulator's poses about the pivot the SDF defines
(:func:`~robotplan.models.rigid.moved_pivot_delta`), its squared error in units of the
spec's ``out_scale`` (m) and ``turn_scale`` (rad); ``"sdf"``, the SDFs alone: eq. (5)
through the transform, φ1_{t−1}(T(Δq)⁻¹x) against φ1_t(x) at query points
(:func:`sdf_space_loss`), in units of ``out_scale``. The
run is seeded and resumable as :func:`robotplan.training.train.train` is (batches from a
permutation per ``(seed, epoch)``, ``checkpoint.pt`` every few minutes and at the end).
"""

from __future__ import annotations

import json
import math
import os
import time
from dataclasses import asdict
from pathlib import Path

import numpy as np
import torch
from torch import Tensor

from robotplan.models.rigid import (
    RigidMotion,
    load_rigid,
    moved_pivot_delta,
    save_rigid,
    sdf_pivot,
    transform_points,
)
from robotplan.models.spec import DynamicsSpec
from robotplan.sdf import Workspace
from robotplan.training.evaluation import pick_samples
from robotplan.training.footprints import BOX, LSHAPE
from robotplan.training.samples import PushSamples, SampleBatch
from robotplan.training.train import (
    TrainConfig,
    hardware,
    lr_at,
    query_points,
    validation_indices,
    write_json,
)

__all__ = ["delta_q_errors", "evaluate_rigid", "rigid_targets", "sdf_space_loss",
           "table5_errors", "train_rigid", "turn_gain"]


def rigid_targets(batch: SampleBatch, grid: Tensor, shape: tuple[int, int]
                  ) -> tuple[Tensor, Tensor, Tensor]:
    """The model inputs ``(B, 3, H, W)``, the pivots ``(B, 2)`` and the true Δq ``(B, 3)``."""
    inputs = batch.inputs(grid, shape)
    pivot = sdf_pivot(inputs[:, 0].flatten(1), grid)
    return inputs, pivot, moved_pivot_delta(pivot, batch.object_prev, batch.object_now)


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
def delta_q_errors(model: RigidMotion, batch: SampleBatch, grid: Tensor,
                   shape: tuple[int, int], chunk: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """Predicted and true Δq, each ``(B, 3)`` in m, m, rad."""
    preds, trues = [], []
    for i in range(0, len(batch.radius), chunk):
        sub = batch.slice(i, i + chunk)
        inputs, _, true = rigid_targets(sub, grid, shape)
        preds.append(model(inputs))
        trues.append(true)
    return torch.cat(preds).cpu().numpy(), torch.cat(trues).cpu().numpy()


def turn_gain(pred: np.ndarray, true: np.ndarray) -> float:
    """The least-squares slope of predicted on true turns (1: turns as much as the world)."""
    t = true[:, 2]
    return float(pred[:, 2] @ t / max(float(t @ t), 1e-12))


def table5_errors(pred: np.ndarray, true: np.ndarray) -> dict:
    """Paper Tab. 5 columns: |error| of x, y in mm and α in degrees, [mean, std]."""
    err = np.abs(pred - true) * np.array([1e3, 1e3, 180 / math.pi])
    return {key: [round(float(err[:, k].mean()), 3), round(float(err[:, k].std()), 3)]
            for k, key in enumerate(("x_mm", "y_mm", "alpha_deg"))}


def _workspace(spec: DynamicsSpec) -> Workspace:
    return Workspace(spec.workspace_center, spec.workspace_size,
                     spec.workspace_size[0] / spec.grid[1])


def train_rigid(cfg: TrainConfig, resume: bool = False, progress: bool = True) -> dict:
    """Run (or resume) F_q training with ``cfg.rigid_loss``; returns the last validation
    row (Δq errors against the ground truth, whichever loss trains)."""
    if cfg.rigid_loss not in ("delta", "sdf"):
        raise ValueError(f"rigid_loss {cfg.rigid_loss!r}: expected 'delta' or 'sdf'")
    from tqdm import tqdm

    out, device = Path(cfg.out), torch.device(cfg.device)
    ckpt_path = out / "checkpoint.pt"
    torch.manual_seed(cfg.seed)
    spec = DynamicsSpec(**{"encoder": "joint", **cfg.spec, "kind": "rigid"})
    model = RigidMotion(spec).to(device)
    opt = torch.optim.Adam(model.parameters(), lr=cfg.lr)
    step, history, seconds = 0, [], 0.0
    if cfg.init_weights and not resume:
        model.load_state_dict(torch.load(cfg.init_weights, map_location=device,
                                         weights_only=True))
    if resume:
        state = torch.load(ckpt_path, map_location=device, weights_only=True)
        model.load_state_dict(state["model"])
        opt.load_state_dict(state["optimizer"])
        step, history, seconds = state["step"], json.loads(state["history"]), state["seconds"]
    samples = PushSamples(cfg.data, cfg.scenes)
    train_idx, val_idx = samples.split_by_scene(cfg.val_fraction, cfg.seed)
    val_batch = samples.batch(validation_indices(samples, val_idx, cfg.val_samples, cfg.seed),
                              device=device)
    ws = _workspace(spec)
    grid = ws.points().reshape(-1, 2).to(device)
    per_epoch = max(1, len(train_idx) // cfg.batch)

    def save_checkpoint() -> None:
        tmp = ckpt_path.with_suffix(".tmp")
        torch.save({"model": model.state_dict(), "optimizer": opt.state_dict(), "step": step,
                    "history": json.dumps(history), "seconds": seconds,
                    "config": json.dumps(asdict(cfg))}, tmp)
        os.replace(tmp, ckpt_path)

    def validate() -> dict:
        model.eval()
        pred, true = delta_q_errors(model, val_batch, grid, ws.shape)
        model.train()
        c = val_batch.contact.cpu().numpy()
        row = {"step": step, "epoch": round(step / per_epoch, 3),
               "minutes": round(seconds / 60, 1),
               "val_delta_q_error": {"contact": table5_errors(pred[c], true[c]),
                                     "free": table5_errors(pred[~c], true[~c])},
               "val_turn_gain": round(turn_gain(pred[c], true[c]), 3)}
        history.append(row)
        save_rigid(model, out)
        write_json(out / "training.json", {"config": asdict(cfg), "history": history,
                                            "samples": {"train": len(train_idx),
                                                        "val": len(val_idx)},
                                            "hardware": hardware(device)})
        return row

    out.mkdir(parents=True, exist_ok=True)
    model.train()
    run_start = start = last_ckpt = time.time()
    bar = tqdm(total=cfg.steps, initial=step, unit="step", disable=not progress,
               desc="train rigid")
    perm, perm_epoch, loss_ema = train_idx, -1, None
    if step == 0:
        bar.write(json.dumps(validate()))
    try:
        while step < cfg.steps:
            epoch, b = divmod(step, per_epoch)
            if perm_epoch != epoch:
                perm = np.random.default_rng([cfg.seed, epoch]).permutation(train_idx)
                perm_epoch = epoch
            batch = samples.batch(perm[b * cfg.batch:(b + 1) * cfg.batch], device=device)
            inputs, pivot, true = rigid_targets(batch, grid, ws.shape)
            if cfg.rigid_loss == "sdf":
                gen = torch.Generator().manual_seed(cfg.seed * 1_000_003 + step)
                pts = query_points(batch, cfg.points, cfg.near_share, ws, gen).to(device)
                loss = sdf_space_loss(model(inputs), inputs[:, 0], pivot, batch.phi1_now(pts),
                                      pts, ws.bounds) / spec.out_scale**2
            else:
                loss = ((model(inputs) - true) / model.scale).pow(2).mean()
            for g in opt.param_groups:
                g["lr"] = lr_at(cfg, step)
            opt.zero_grad(set_to_none=True)
            loss.backward()
            opt.step()
            step += 1
            now = time.time()
            seconds, start = seconds + now - start, now
            value = float(loss.detach()) ** 0.5
            loss_ema = value if loss_ema is None else 0.98 * loss_ema + 0.02 * value
            bar.update(1)
            bar.set_postfix(rms=f"{loss_ema:.3f}", epoch=f"{step / per_epoch:.2f}")
            if step % cfg.val_every == 0 or step == cfg.steps:
                bar.write(json.dumps(validate()))
            if now - last_ckpt > 60 * cfg.checkpoint_minutes:
                save_checkpoint()
                last_ckpt = now
            if cfg.minutes is not None and now - run_start > 60 * cfg.minutes:
                break
    finally:
        bar.close()
        save_checkpoint()
    if not history or history[-1]["step"] != step:
        validate()
    return history[-1]


@torch.no_grad()
def evaluate_rigid(model_dir: str | Path, data_dir: str | Path, scenes: int | None = None,
                   per_scene: int | None = None, seed: int = 0,
                   device: str | torch.device = "cpu") -> dict:
    """F_q's one-step Δq errors on held-out data in the paper's Tab. 5 terms (contact and
    free samples), the turn gain per shape, and the no-motion baseline (Δq = 0)."""
    t0 = time.time()
    model = load_rigid(model_dir, device)
    ws = _workspace(model.spec)
    grid = ws.points().reshape(-1, 2).to(device)
    samples = PushSamples(data_dir, scenes)
    idx = pick_samples(samples, per_scene, seed)
    pred, true = delta_q_errors(model, samples.batch(idx, device=device), grid, ws.shape)
    contact = samples.contact[idx]
    code = samples.data["shape_type"][samples.scene[idx]]
    c = contact
    kinds = {"box": code == BOX, "lshape": code == LSHAPE, "other": code > LSHAPE}
    return {
        "model": str(model_dir), "kind": "rigid", "data": str(data_dir),
        "scenes": samples.num_scenes,
        "samples": {"contact": int(c.sum()), "free": int((~c).sum())},
        "delta_q_error": table5_errors(pred[c], true[c]),
        "delta_q_error_free": table5_errors(pred[~c], true[~c]),
        "baseline_delta_q_error": table5_errors(np.zeros_like(true[c]), true[c]),
        "turn_gain": {k: round(turn_gain(pred[c & m], true[c & m]), 3)
                      for k, m in kinds.items() if (c & m).any()},
        "seconds": round(time.time() - t0, 1), "device": str(device),
    }
