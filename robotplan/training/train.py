"""Training F_flow / F on push data: loss eq. (5) on random query points, held-out scenes.

The run is fixed by its arguments and seed: batch ``b`` of epoch ``e`` is a slice of a
permutation drawn from ``(seed, e)``, the query points of step ``s`` come from
``(seed, s)``, so ``--resume`` continues exactly where a checkpoint left off.
Checkpoints (``checkpoint.pt``: model, optimiser, step; loaded with ``weights_only=True``)
are written every few minutes and at the end; the model folder (weights, spec, metrics,
model card) is refreshed at every validation.
"""

from __future__ import annotations

import json
import math
import os
import platform
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import torch

from robotplan.models.dynamics import DynamicsSpec, PushDynamics, save_model
from robotplan.sdf import Workspace
from robotplan.training.samples import PushSamples, SampleBatch

__all__ = ["TrainConfig", "grid_rmse", "hardware", "lr_at", "query_points", "train",
           "validation_indices", "write_json"]


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


def lr_at(cfg: TrainConfig, step: int) -> float:
    """Linear warm-up, then cosine decay from ``lr`` to ``lr_min`` at ``steps``."""
    if step < cfg.warmup:
        return cfg.lr * (step + 1) / cfg.warmup
    frac = min(1.0, (step - cfg.warmup) / max(1, cfg.steps - cfg.warmup))
    return cfg.lr_min + 0.5 * (cfg.lr - cfg.lr_min) * (1 + math.cos(math.pi * frac))


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


def _target(model: PushDynamics, batch: SampleBatch, pts: torch.Tensor) -> torch.Tensor:
    now = batch.phi1_now(pts)
    return now - batch.phi1_prev(pts) if model.spec.kind == "flow" else now


@torch.no_grad()
def grid_rmse(model: PushDynamics, batch: SampleBatch, ws: Workspace, stride: int = 1,
              chunk: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """Per-sample RMSE (m) over X_h (eq. 20) of the model and of the "no motion" baseline.

    ``stride`` > 1 evaluates every stride-th grid point in each direction (for quick checks).
    """
    grid = ws.points(batch.params.dtype).to(batch.params.device)
    pts = grid[::stride, ::stride].reshape(1, -1, 2)
    full = grid.reshape(-1, 2)
    model_err, base_err = [], []
    for i in range(0, len(batch.radius), chunk):
        sub = batch.slice(i, i + chunk)
        inputs = sub.inputs(full, ws.shape)
        prev, now = sub.phi1_prev(pts), sub.phi1_now(pts)
        pred = model.predict_next(inputs, pts, prev)
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
    from tqdm import tqdm

    out = Path(cfg.out)
    ckpt_path = out / "checkpoint.pt"
    device = torch.device(cfg.device)
    torch.manual_seed(cfg.seed)
    spec = DynamicsSpec(kind=cfg.kind, **cfg.spec)
    if cfg.kind == "direct" and "out_scale" not in cfg.spec:
        spec = DynamicsSpec(**{**asdict(spec), "out_scale": 0.1})
    model = PushDynamics(spec).to(device)
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
    ws = Workspace(spec.workspace_center, spec.workspace_size,
                   spec.workspace_size[0] / spec.grid[1])
    grid = ws.points().reshape(-1, 2).to(device)
    per_epoch = len(train_idx) // cfg.batch
    train_contact = train_idx[samples.contact[train_idx]]
    train_free = train_idx[~samples.contact[train_idx]]

    def save_checkpoint() -> None:
        tmp = ckpt_path.with_suffix(".tmp")
        torch.save({"model": model.state_dict(), "optimizer": opt.state_dict(), "step": step,
                    "history": json.dumps(history), "seconds": seconds,
                    "config": json.dumps(asdict(cfg))}, tmp)
        os.replace(tmp, ckpt_path)

    def validate() -> dict:
        model.eval()
        err, base = grid_rmse(model, val_batch, ws, stride=2)
        model.train()
        c = val_batch.contact.cpu().numpy()
        row = {"step": step, "epoch": round(step / per_epoch, 3), "minutes": round(seconds / 60, 1),
               "val_rmse_mm": {"contact": round(1e3 * float(err[c].mean()), 3),
                               "free": round(1e3 * float(err[~c].mean()), 3)},
               "val_baseline_mm": {"contact": round(1e3 * float(base[c].mean()), 3),
                                   "free": round(1e3 * float(base[~c].mean()), 3)}}
        history.append(row)
        save_model(model, out)
        write_json(out / "training.json", {"config": asdict(cfg), "history": history,
                                             "samples": {"train": len(train_idx),
                                                         "val": len(val_idx)},
                                             "hardware": hardware(device)})
        return row

    out.mkdir(parents=True, exist_ok=True)
    model.train()
    run_start = start = last_ckpt = time.time()
    bar = tqdm(total=cfg.steps, initial=step, unit="step", disable=not progress,
               desc=f"train {cfg.kind}")
    loss_ema = None
    perm, perm_epoch = train_idx, -1
    if step == 0:
        bar.write(json.dumps(validate()))  # the untrained model, for the record
    try:
        while step < cfg.steps:
            epoch, b = divmod(step, per_epoch)
            if cfg.contact_share is None:
                if perm_epoch != epoch:  # one permutation per epoch (not per step)
                    perm = np.random.default_rng([cfg.seed, epoch]).permutation(train_idx)
                    perm_epoch = epoch
                chosen = perm[b * cfg.batch:(b + 1) * cfg.batch]
            else:  # balanced batches: the metric averages contact and free separately
                rng = np.random.default_rng([cfg.seed, 7, step])
                n_contact = round(cfg.contact_share * cfg.batch)
                chosen = np.concatenate([rng.choice(train_contact, n_contact),
                                         rng.choice(train_free, cfg.batch - n_contact)])
            batch = samples.batch(chosen, device=device)
            gen = torch.Generator().manual_seed(cfg.seed * 1_000_003 + step)
            pts = query_points(batch, cfg.points, cfg.near_share, ws, gen).to(device)
            inputs = batch.inputs(grid, ws.shape)
            loss = (model(inputs, pts) - _target(model, batch, pts)).pow(2).mean()
            for g in opt.param_groups:
                g["lr"] = lr_at(cfg, step)
            opt.zero_grad(set_to_none=True)
            loss.backward()
            opt.step()
            step += 1
            now = time.time()
            seconds += now - start
            start = now
            rmse = 1e3 * float(loss.detach()) ** 0.5
            loss_ema = rmse if loss_ema is None else 0.98 * loss_ema + 0.02 * rmse
            bar.update(1)
            bar.set_postfix(rmse_mm=f"{loss_ema:.2f}", epoch=f"{step / per_epoch:.2f}")
            if step % cfg.val_every == 0 or step == cfg.steps:
                row = validate()
                bar.write(json.dumps(row))
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


def hardware(device: torch.device) -> dict:
    info = {"device": str(device), "cpu": platform.processor() or platform.machine(),
            "cores": os.cpu_count(), "threads": torch.get_num_threads(),
            "torch": torch.__version__}
    if device.type == "cuda":
        info["gpu"] = torch.cuda.get_device_name(device)
    return info


def write_json(path: Path, data: dict) -> None:
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(data, indent=1))
    os.replace(tmp, path)
