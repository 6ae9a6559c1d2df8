"""F_q on held-out push data: Δq errors in the paper's Tab. 5 terms, and the SDF error of
Tab. 2, so that F_q stands beside F_flow and F in the same units.

F_q's next SDF is φ1_t = T(Δq)[φ1_{t−1}] (eq. 17): φ1_{t−1} moved by the predicted rigid
step. Its Tab. 2 error is the RMSE over the table's X_h (140 × 140 points over 1.4 m, the
grid F_flow and F are scored on) between that SDF and the observed φ1_t, with φ1_{t−1} the
object's own SDF (as the planner has it), not a grid read back.
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import torch
from torch import Tensor

from robotplan.base.scene_sums import scene_sums
from robotplan.models.spec import DynamicsSpec
from robotplan.pushing.models.rigid import load_rigid, moved_pose
from robotplan.pushing.training.evaluation import pick_samples, rmse_sums
from robotplan.pushing.training.footprints import BOX, LSHAPE
from robotplan.pushing.training.push_data import data_simulator, scene_families
from robotplan.pushing.training.rigid import delta_q_predictions, table5_errors, turn_gain
from robotplan.pushing.training.samples import PushSamples, SampleBatch

__all__ = ["delta_q_sums", "evaluate_rigid", "moved_sdf_rmse"]


@torch.no_grad()
def moved_sdf_rmse(batch: SampleBatch, delta: Tensor, pivot: Tensor, grid: Tensor,
                   chunk: int = 64) -> tuple[Tensor, Tensor]:
    """Per sample, the RMSE over ``grid (N, 2)`` between φ1_{t−1} moved by ``delta (B, 3)``
    about ``pivot (B, 2)`` (both table frame) and the observed φ1_t; and the no-motion
    baseline's, φ1_{t−1} against φ1_t. Two ``(B,)`` tensors in m."""
    errs, bases = [], []
    for i in range(0, len(batch.radius), chunk):
        sub = batch.slice(i, i + chunk)
        now = sub.phi1_now(grid[None])
        moved = replace(sub, object_now=moved_pose(sub.object_prev, pivot[i:i + chunk],
                                                   delta[i:i + chunk]))
        errs.append((moved.phi1_now(grid[None]) - now).pow(2).mean(1).sqrt())
        bases.append((sub.phi1_prev(grid[None]) - now).pow(2).mean(1).sqrt())
    return torch.cat(errs), torch.cat(bases)


def delta_q_sums(scene: np.ndarray, contact: np.ndarray, pred: np.ndarray, true: np.ndarray
                 ) -> dict[str, list]:
    """Per-scene sums over the contact samples (counted: ``contact``) of |Δq error| (x, y
    mm; α °), of the no-motion error |Δq|, and of the turn products pred_α·true_α and
    true_α² (°²): Tab. 5's means and the turn gain as ratios of sums
    (:func:`robotplan.base.scene_sums`).
    ``pred``, ``true``: (N, 3) Δq in m, m, rad."""
    c = np.asarray(contact, dtype=float)[:, None]
    scale = np.array([1e3, 1e3, 180 / np.pi])
    err, base = np.abs(pred - true) * scale * c, np.abs(true) * scale * c
    p_a, t_a = pred[:, 2] * scale[2], true[:, 2] * scale[2]
    return scene_sums(scene, {"contact": c[:, 0],
                              "x_mm": err[:, 0], "y_mm": err[:, 1], "alpha_deg": err[:, 2],
                              "baseline_x_mm": base[:, 0], "baseline_y_mm": base[:, 1],
                              "baseline_alpha_deg": base[:, 2],
                              "turn_product": p_a * t_a * c[:, 0],
                              "turn_square": t_a * t_a * c[:, 0]})


@torch.no_grad()
def evaluate_rigid(model_dir: str | Path, data_dir: str | Path, scenes: int | None = None,
                   per_scene: int | None = None, seed: int = 0,
                   device: str | torch.device = "cpu", views: int = 1) -> dict:
    """F_q's one-step Δq errors on held-out data in the paper's Tab. 5 terms (contact and
    free samples), the turn gain per shape, the no-motion baseline (Δq = 0), and the Tab. 2
    RMSE of the SDF it predicts (:func:`moved_sdf_rmse`, mm). With ``views`` 4 or 8 the
    prediction is averaged over the scene's quarter turns (and mirrors)."""
    t0 = time.time()
    model = load_rigid(model_dir, device)
    ws = model.spec.workspace()
    grid = ws.points().reshape(-1, 2).to(device)
    samples = PushSamples(data_dir, scenes)
    idx = pick_samples(samples, per_scene, seed)
    batch = samples.batch(idx, device=device)
    pred_t, true_t, pivot = delta_q_predictions(model, batch, grid, ws.shape, views)
    table = DynamicsSpec().workspace().points().reshape(-1, 2).to(device)
    err, base = (v.cpu().numpy() * 1e3 for v in moved_sdf_rmse(batch, pred_t, pivot, table))
    pred, true = pred_t.cpu().numpy(), true_t.cpu().numpy()
    c = samples.contact[idx]
    code = samples.data["shape_type"][samples.scene[idx]]
    kinds = {"box": code == BOX, "lshape": code == LSHAPE, "other": code > LSHAPE}
    family = scene_families(samples.folder, samples.data)[samples.scene[idx]]
    by_footprint = {}
    for name in dict.fromkeys(family):  # in the order the scenes draw them
        m = c & (family == name)
        if m.any():
            by_footprint[str(name)] = {"samples": int(m.sum()),
                                       "delta_q_error": table5_errors(pred[m], true[m]),
                                       "turn_gain": round(turn_gain(pred[m], true[m]), 3)}

    def split(v: np.ndarray, f) -> dict:
        return {"contact": round(float(f(v[c])), 3), "free": round(float(f(v[~c])), 3)}

    return {
        "model": str(model_dir), "kind": "rigid", "data": str(data_dir),
        "simulator": data_simulator(data_dir), "scenes": samples.num_scenes,
        "samples": {"contact": int(c.sum()), "free": int((~c).sum())},
        "delta_q_error": table5_errors(pred[c], true[c]),
        "delta_q_error_free": table5_errors(pred[~c], true[~c]),
        "baseline_delta_q_error": table5_errors(np.zeros_like(true[c]), true[c]),
        "turn_gain": {k: round(turn_gain(pred[c & m], true[c & m]), 3)
                      for k, m in kinds.items() if (c & m).any()},
        "by_footprint": by_footprint,
        "rmse_mm": split(err, np.mean), "rmse_std_mm": split(err, np.std),
        "baseline_rmse_mm": split(base, np.mean), "baseline_std_mm": split(base, np.std),
        "by_scene": {**rmse_sums(samples.scene[idx], c, err, base),
                     **delta_q_sums(samples.scene[idx], c, pred, true),
                     "shape": [next(k for k, m in kinds.items() if m[i])
                               for i in np.unique(samples.scene[idx], return_index=True)[1]]},
        "views": views, "seconds": round(time.time() - t0, 1), "device": str(device),
    }
