"""Training H_hang on hanging data: loss eq. (21), Adam, batches of 32 (paper app. H.1).

The SDF grids are rendered from the stored shape parameters and poses as batches are drawn
(the hook's grid once per scene). Batch ``b`` of epoch ``e`` is a slice of a permutation
drawn from ``(seed, e)``, so ``--resume`` continues where the checkpoint left off;
checkpoints (``checkpoint.pt``, read with ``weights_only=True``) every few minutes and at the
end; the model folder (weights, spec, metrics) is refreshed at every validation.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from robotplan.hanging.functionals.h_hang import HangGrids, mug_grids
from robotplan.hanging.models.hang_model import (
    HANG_THRESHOLDS,
    HangSpec,
    HangSuccess,
    hang_loss,
    load_hang_model,
    save_hang_model,
)
from robotplan.hanging.training.data import decode_hook, load_hang_shards
from robotplan.training.loop import (
    Run,
    epoch_batch,
    load_checkpoint,
    run_steps,
    write_training_record,
)

__all__ = ["HangSamples", "HangTrainConfig", "hang_metrics", "train_hang"]

@dataclass
class HangTrainConfig:
    data: str
    out: str
    test: str | None = None  # held-out data folder; else val_fraction of the scenes
    # folders of poses the planner found, labelled (robotplan.hanging.training.mining): trained
    # on with ``data``, each of their samples ``mined_repeat`` times per epoch
    mined: list[str] = field(default_factory=list)
    mined_repeat: int = 1
    init: str | None = None  # a model folder whose weights training starts from
    steps: int = 20_000
    batch: int = 32
    lr: float = 1e-4
    lr_min: float = 1e-5
    warmup: int = 200
    val_fraction: float = 0.05
    val_every: int = 1000
    seed: int = 0
    scenes: int | None = None
    minutes: float | None = None
    checkpoint_minutes: float = 5.0
    command: str = ""
    spec: dict = field(default_factory=dict)  # HangSpec overrides (e.g. a tiny network)
    device: str = "cpu"  # the network's; grids are rendered and cached on the CPU
    anneal_by_time: bool = False  # the cosine also ends when ``minutes`` run out


class HangSamples:
    """Every labelled configuration of one or more data folders: ``scene (N,)``,
    ``poses (N, 7)``, ``hangs (N,)``, ``source (N,)`` (which folder), and per scene the mug,
    the hook and the hook's grid. A folder's scenes are its own (a mined folder repeats the
    shapes of the folder it was mined from, as scenes of its own)."""

    def __init__(self, folders: str | Path | list, spec: HangSpec,
                 scenes: int | None = None) -> None:
        parts = [load_hang_shards(Path(f)) for f in
                 (folders if isinstance(folders, list | tuple) else [folders])]
        mugs, hooks, poses, hangs, scene, source = [], [], [], [], [], []
        for k, d in enumerate(parts):
            n = len(d["mug"]) if scenes is None else min(scenes, len(d["mug"]))
            per = d["poses"].shape[1]
            scene.append(len(hooks) + np.repeat(np.arange(n), per))
            source.append(np.full(n * per, k))
            hooks += [decode_hook(d["hook"][s], *d["hook_radii"][s]) for s in range(n)]
            mugs.append(d["mug"][:n])
            poses.append(d["poses"][:n].reshape(-1, 7))
            hangs.append(d["hangs"][:n].reshape(-1))
        grids = [HangGrids(h, spec) for h in hooks]
        self.cells = spec.cells
        self.lattice = grids[0].points - grids[0].centre
        self.centres = torch.stack([g.centre for g in grids])
        self.hooks = torch.stack([g.hook for g in grids])  # (S, C, C, C)
        self.mugs = torch.from_numpy(np.concatenate(mugs)).float()
        self.scene, self.source = np.concatenate(scene), np.concatenate(source)
        self.poses = torch.from_numpy(np.concatenate(poses)).float()
        self.hangs = torch.from_numpy(np.concatenate(hangs))

    def __len__(self) -> int:
        return len(self.scene)

    def render(self, idx: np.ndarray) -> torch.Tensor:
        """The mug's grids ``(B, C, C, C)`` of samples ``idx``."""
        s, c = self.scene[idx], self.cells
        with torch.no_grad():
            mug = mug_grids(self.lattice, self.centres[s], self.mugs[s], self.poses[idx])
        return mug.reshape(-1, c, c, c)

    def cache(self, chunk: int = 64, progress: bool = True) -> None:
        """Render every sample's mug grid once and keep it (float16: 2 bytes a cell, 128 kB a
        sample; the values near the surfaces keep ~10 µm)."""
        from tqdm import tqdm

        grids = torch.empty((len(self), self.cells, self.cells, self.cells),
                            dtype=torch.float16)
        for i in tqdm(range(0, len(self), chunk), desc="render grids", unit="chunk",
                      disable=not progress):
            idx = np.arange(i, min(i + chunk, len(self)))
            grids[idx] = self.render(idx).half()
        self._cached = grids

    def inputs(self, idx: np.ndarray) -> torch.Tensor:
        """The network's input ``(B, 2, C, C, C)`` of samples ``idx``."""
        cached = getattr(self, "_cached", None)
        mug = cached[idx].float() if cached is not None else self.render(idx)
        return torch.stack((mug, self.hooks[self.scene[idx]]), dim=1)

    def split_by_scene(self, fraction: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
        """Training and validation indices, the validation scenes drawn from the first
        folder's."""
        scenes = np.unique(self.scene[self.source == 0])
        val = np.random.default_rng([seed, 5]).choice(
            scenes, max(1, round(fraction * len(scenes))), replace=False)
        is_val = np.isin(self.scene, val)
        return np.nonzero(~is_val)[0], np.nonzero(is_val)[0]


@torch.no_grad()
def hang_metrics(model: HangSuccess, samples: HangSamples, idx: np.ndarray,
                 chunk: int = 64) -> dict:
    """Loss (eq. 21) and, per threshold κ, the accuracy of "H < κ predicts success" and its
    rates on the successes (recall) and the failures (specificity)."""
    device = next(model.parameters()).device
    h = torch.cat([model(samples.inputs(idx[i:i + chunk]).to(device)).cpu()
                   for i in range(0, len(idx), chunk)])
    y = samples.hangs[idx]
    out = {"loss": round(float(hang_loss(h, y)), 5), "samples": len(idx),
           "successes": int(y.sum()), "h_median_success": round(float(h[y].median()), 4)
           if y.any() else None,
           "h_median_failure": round(float(h[~y].median()), 4) if (~y).any() else None}
    for name, kappa in HANG_THRESHOLDS.items():
        pred = h < kappa
        out[name] = {"kappa": kappa, "accuracy": round(float((pred == y).float().mean()), 4),
                     "recall": round(float(pred[y].float().mean()), 4) if y.any() else None,
                     "specificity": round(float((~pred[~y]).float().mean()), 4)
                     if (~y).any() else None}
    return out


def train_hang(cfg: HangTrainConfig, resume: bool = False, progress: bool = True) -> dict:
    """Run (or resume) training; returns the last validation row."""
    out, device = Path(cfg.out), torch.device(cfg.device)
    ckpt_path = out / "checkpoint.pt"
    torch.manual_seed(cfg.seed)
    if cfg.init:
        model = load_hang_model(cfg.init, device).train()
        spec = model.spec
    else:
        spec = HangSpec.from_json(cfg.spec)
        model = HangSuccess(spec).to(device)
    opt = torch.optim.Adam(model.parameters(), lr=cfg.lr)
    run = load_checkpoint(ckpt_path, model, opt, device) if resume else Run()
    samples = HangSamples([cfg.data, *cfg.mined], spec, cfg.scenes)
    samples.cache(progress=progress)
    if cfg.test:
        val_samples = HangSamples(cfg.test, spec)
        val_samples.cache(progress=progress)  # validated many times: rendered once
        train_idx, val_idx = np.arange(len(samples)), np.arange(len(val_samples))
    else:
        val_samples = samples
        train_idx, val_idx = samples.split_by_scene(cfg.val_fraction, cfg.seed)
    mined = train_idx[samples.source[train_idx] > 0]
    train_idx = np.concatenate([train_idx, *[mined] * (cfg.mined_repeat - 1)])
    per_epoch = max(1, len(train_idx) // cfg.batch)
    batch_of = epoch_batch(train_idx, cfg.batch, cfg.seed)

    def validate() -> dict:
        model.eval()
        row = {"step": run.step, "epoch": round(run.step / per_epoch, 3),
               "minutes": round(run.seconds / 60, 1),
               "validation": hang_metrics(model, val_samples, val_idx)}
        model.train()
        run.history.append(row)
        save_hang_model(model, out)
        write_training_record(out, cfg, run, {"train": len(train_idx), "val": len(val_idx)},
                              device)
        return row

    def step_loss(step: int) -> torch.Tensor:
        chosen = batch_of(step)
        return hang_loss(model(samples.inputs(chosen).to(device)),
                         samples.hangs[chosen].to(device))

    out.mkdir(parents=True, exist_ok=True)
    return run_steps(cfg, run, model, opt, ckpt_path, step_loss, validate, per_epoch,
                     "train hang", ("loss", lambda v: v, ".4f"), progress)
