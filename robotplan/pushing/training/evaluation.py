"""One-step prediction error of a push model on held-out data (paper eq. 20, Tab. 2)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import torch

from robotplan.base.scene_sums import scene_sums
from robotplan.pushing.models.dynamics import load_model
from robotplan.pushing.models.symmetry import symmetric_field
from robotplan.pushing.training.push_data import data_simulator
from robotplan.pushing.training.samples import PushSamples, SampleBatch
from robotplan.pushing.training.train import framed, scored_workspace

__all__ = ["evaluate_push", "pick_samples", "rmse_sums"]


def pick_samples(samples: PushSamples, per_scene: int | None, seed: int) -> np.ndarray:
    """All sample indices, or at most ``per_scene`` random ones of each scene (seeded)."""
    if per_scene is None:
        return np.arange(len(samples))
    rng = np.random.default_rng(seed)
    picked = []
    for s in range(samples.num_scenes):
        idx = np.flatnonzero(samples.scene == s)
        picked.append(rng.choice(idx, min(per_scene, len(idx)), replace=False))
    return np.sort(np.concatenate(picked))


def rmse_sums(scene: np.ndarray, contact: np.ndarray, err: np.ndarray, base: np.ndarray
              ) -> dict[str, list]:
    """Per-scene sums of the samples' RMSE (``err``) and the no-motion RMSE (``base``), with
    and without contact, and the samples counted: each mean of the result is a ratio of
    these sums, so a report can resample scenes (:func:`robotplan.base.scene_sums`)."""
    c = np.asarray(contact, dtype=float)
    return scene_sums(scene, {"contact": c, "free": 1 - c, "rmse_contact": err * c,
                              "rmse_free": err * (1 - c), "baseline_contact": base * c,
                              "baseline_free": base * (1 - c)})


@torch.no_grad()
def evaluate_push(model_dir: str | Path, data_dir: str | Path, scenes: int | None = None,
                  per_scene: int | None = None, seed: int = 0, chunk: int | None = None,
                  progress: bool = True, device: str | torch.device = "cpu",
                  views: int = 1) -> dict:
    """RMSE over every point of X_h between predicted and true φ1_t, per sample, averaged
    over samples with and without pusher contact; also for the "no motion" baseline
    φ1_t = φ1_{t−1}. Distances in millimetres; for a model on an occupancy measure the RMSE
    of ψ1_t, times 1000 (the paper's Tab. 4: not comparable with the SDFs' millimetres).
    ``chunk`` samples are evaluated at a time (default 8 on the CPU, 128 on a GPU). With
    ``views`` 4 or 8 the model's output is averaged over the scene's quarter turns (and
    mirrors), exact symmetries of X_h (:mod:`robotplan.pushing.models.symmetry`)."""
    from tqdm import tqdm

    t0 = time.time()
    if chunk is None:
        chunk = 8 if torch.device(device).type == "cpu" else 128
    model = load_model(model_dir, device)
    spec = model.spec
    if views != 1 and spec.frame != "table":
        raise ValueError("views: an object-frame model's grid turns with the object; "
                         "only a table-frame model is averaged over views")
    ws = spec.workspace()
    grid = ws.points().reshape(-1, 2).to(device)
    table = scored_workspace(spec).points().reshape(1, -1, 2).to(device)
    # a table-frame model reads the scored points as they are: their term computed once
    point_term = model.point_term(table) if spec.frame == "table" else None
    samples = PushSamples(data_dir, scenes)
    idx = pick_samples(samples, per_scene, seed)
    errs, bases = [], []
    for i in tqdm(range(0, len(idx), chunk), desc="eval", unit="batch", disable=not progress):
        b: SampleBatch = samples.batch(idx[i:i + chunk], device=device)
        inputs, points = framed(spec, b, grid, table)
        terms = point_term if point_term is not None else model.point_term(points)
        out = symmetric_field(
            lambda x, terms=terms: model.from_terms(model.sdf_term(model.features(x)), terms),
            inputs, views)
        prev = model.values_read(b.phi1_prev(table))
        now = model.values_read(b.phi1_now(table))
        pred = prev + out if spec.kind == "flow" else out
        errs.append((pred - now).pow(2).mean(1).sqrt())
        bases.append((prev - now).pow(2).mean(1).sqrt())
    err = torch.cat(errs).cpu().numpy() * 1e3
    base = torch.cat(bases).cpu().numpy() * 1e3
    contact = samples.contact[idx]

    def stats(v: np.ndarray) -> dict:
        return {"contact": round(float(v[contact].mean()), 3),
                "free": round(float(v[~contact].mean()), 3)}

    def spread(v: np.ndarray) -> dict:
        return {"contact": round(float(v[contact].std()), 3),
                "free": round(float(v[~contact].std()), 3)}

    return {
        "model": str(model_dir), "kind": spec.kind, "data": str(data_dir),
        "simulator": data_simulator(data_dir), "representation": spec.representation,
        "frame": spec.frame,
        "scenes": samples.num_scenes,
        "samples": {"contact": int(contact.sum()), "free": int((~contact).sum())},
        "rmse_mm": stats(err), "rmse_std_mm": spread(err),
        "baseline_rmse_mm": stats(base), "baseline_std_mm": spread(base),
        "by_scene": rmse_sums(samples.scene[idx], contact, err, base),
        "views": views, "seconds": round(time.time() - t0, 1), "device": str(device),
    }
