"""The optimiser loop every trainer shares: learning-rate schedule, per-epoch batch order,
validation cadence, checkpoints (``checkpoint.pt``: model, optimiser, step, history, seconds,
config; loaded with ``weights_only=True``), a wall-time limit and a progress bar.

A trainer supplies the loss of a step and a ``validate()`` that appends its row to
``run.history`` (and refreshes the model folder); ``--resume`` continues where the
checkpoint left off because the batch of step ``s`` depends only on ``(seed, s)``."""

from __future__ import annotations

import json
import math
import os
import platform
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import torch

__all__ = ["Run", "epoch_batch", "hardware", "load_checkpoint", "lr_at", "run_steps",
           "write_json", "write_training_record"]


@dataclass
class Run:
    """Where a training run stands: optimiser steps, validation rows, training seconds."""

    step: int = 0
    history: list = field(default_factory=list)
    seconds: float = 0.0


def lr_at(cfg, step: int, time_fraction: float = 0.0) -> float:
    """Linear warm-up, then cosine decay from ``lr`` to ``lr_min`` at ``steps``, or earlier
    where ``time_fraction`` (the share of a wall-time budget spent) is further along."""
    if step < cfg.warmup:
        return cfg.lr * (step + 1) / cfg.warmup
    frac = min(1.0, max((step - cfg.warmup) / max(1, cfg.steps - cfg.warmup), time_fraction))
    return cfg.lr_min + 0.5 * (cfg.lr - cfg.lr_min) * (1 + math.cos(math.pi * frac))


def load_checkpoint(path: Path, model: torch.nn.Module, opt: torch.optim.Optimizer,
                    device: str | torch.device = "cpu") -> Run:
    state = torch.load(path, map_location=device, weights_only=True)
    model.load_state_dict(state["model"])
    opt.load_state_dict(state["optimizer"])
    return Run(state["step"], json.loads(state["history"]), state["seconds"])


def _save_checkpoint(path: Path, model, opt, run: Run, cfg) -> None:
    tmp = path.with_suffix(".tmp")
    torch.save({"model": model.state_dict(), "optimizer": opt.state_dict(), "step": run.step,
                "history": json.dumps(run.history), "seconds": run.seconds,
                "config": json.dumps(asdict(cfg))}, tmp)
    os.replace(tmp, path)


def epoch_batch(train_idx: np.ndarray, batch: int, seed: int) -> Callable[[int], np.ndarray]:
    """``step → indices``: batch ``b`` of epoch ``e`` is a slice of a permutation drawn from
    ``(seed, e)`` (one permutation per epoch, kept while the epoch lasts)."""
    per_epoch = max(1, len(train_idx) // batch)
    cache: dict[int, np.ndarray] = {}

    def indices(step: int) -> np.ndarray:
        epoch, b = divmod(step, per_epoch)
        if epoch not in cache:
            cache.clear()
            cache[epoch] = np.random.default_rng([seed, epoch]).permutation(train_idx)
        return cache[epoch][b * batch:(b + 1) * batch]

    return indices


def run_steps(cfg, run: Run, model: torch.nn.Module, opt: torch.optim.Optimizer,
              ckpt_path: Path, step_loss: Callable[[int], torch.Tensor],
              validate: Callable[[], dict], per_epoch: int, desc: str,
              shown: tuple[str, Callable[[float], float], str], progress: bool = True) -> dict:
    """Optimise until ``cfg.steps`` (or ``cfg.minutes`` of wall time); returns the last
    validation row. ``shown = (name, f, format)``: the bar shows an average of
    ``f(loss)`` under ``name``. ``cfg`` needs ``steps, lr, lr_min, warmup, val_every,
    checkpoint_minutes, minutes, anneal_by_time``."""
    from tqdm import tqdm

    name, of_loss, fmt = shown
    model.train()
    run_start = start = last_ckpt = time.time()
    bar = tqdm(total=cfg.steps, initial=run.step, unit="step", disable=not progress,
               desc=desc)
    ema = None
    if run.step == 0:
        bar.write(json.dumps(validate()))  # the untrained model, for the record
    try:
        while run.step < cfg.steps:
            loss = step_loss(run.step)
            # --anneal-by-time: the cosine ends with the wall-time budget even where fewer
            # steps fit than asked (the run is then not step-for-step reproducible)
            spent = ((time.time() - run_start) / (60 * cfg.minutes)
                     if cfg.anneal_by_time and cfg.minutes else 0.0)
            for g in opt.param_groups:
                g["lr"] = lr_at(cfg, run.step, spent)
            opt.zero_grad(set_to_none=True)
            loss.backward()
            opt.step()
            run.step += 1
            now = time.time()
            run.seconds, start = run.seconds + now - start, now
            value = of_loss(float(loss.detach()))
            ema = value if ema is None else 0.98 * ema + 0.02 * value
            bar.update(1)
            bar.set_postfix({name: format(ema, fmt), "epoch": f"{run.step / per_epoch:.2f}"})
            if run.step % cfg.val_every == 0 or run.step == cfg.steps:
                bar.write(json.dumps(validate()))
            if now - last_ckpt > 60 * cfg.checkpoint_minutes:
                _save_checkpoint(ckpt_path, model, opt, run, cfg)
                last_ckpt = now
            if cfg.minutes is not None and now - run_start > 60 * cfg.minutes:
                break
    finally:
        bar.close()
        _save_checkpoint(ckpt_path, model, opt, run, cfg)
    if not run.history or run.history[-1]["step"] != run.step:
        validate()
    return run.history[-1]


def hardware(device: torch.device) -> dict:
    """Where a model was trained: device, CPU, cores, torch threads and version."""
    info = {"device": str(device), "cpu": platform.processor() or platform.machine(),
            "cores": os.cpu_count(), "threads": torch.get_num_threads(),
            "torch": torch.__version__}
    if device.type == "cuda":
        info["gpu"] = torch.cuda.get_device_name(device)
    return info


def write_training_record(out: Path, cfg, run: Run, samples: dict[str, int],
                          device: torch.device, **sections: object) -> None:
    """``out/training.json`` beside the weights: the config ``cfg`` (a dataclass), any
    further ``sections`` (e.g. the training stages), the validation history, the sample
    counts and where it ran (:func:`hardware`)."""
    write_json(out / "training.json", {"config": asdict(cfg), **sections,
                                       "history": run.history, "samples": samples,
                                       "hardware": hardware(device)})


def write_json(path: Path, data: dict) -> None:
    """``data`` as JSON at ``path``, whole or not at all (written beside it, then moved)."""
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(data, indent=1))
    os.replace(tmp, path)
