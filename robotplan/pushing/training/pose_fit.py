"""What a push model says about the object's rigid motion, as the planner reads it.

The planner never asks the model for a pose: it asks which next pose q1_t makes H_t (eq. 5)
small. This evaluation does the same on held-out samples: per contact sample, it fits

    q̂1_t = argmin_{q1_t} H_t(q1_{t−1}, q1_t, q2_{t−1}, q2_t)

(L-BFGS from q1_{t−1}, H_t integrated on a 1 cm lattice of 60 × 60 cm around the object) and
compares q̂1_t − q1_{t−1} with the simulator's step. The field RMSE of
:func:`~robotplan.pushing.training.evaluation.evaluate_push` can be small while the turning is
wrong: a 2° turn of a 20 cm object moves its SDF by at most ~3.5 mm, about the model's field error.
The ``turn_gain`` (least-squares slope of the fitted turn against the true one, through 0)
says how much of the object's turning the model predicts: 1 is all of it, 0 none. The fitted
and the true step are also read as F_q's Δq (a turn about the footprint's centroid, then a
shift) for the paper's Tab. 5 columns (``delta_q_error``).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import torch
from scipy.optimize import minimize

from robotplan.functionals.base import Quadrature
from robotplan.geometry.transforms import wrap_angle
from robotplan.pushing.functionals.framed_dynamics import field_dynamics
from robotplan.pushing.models.dynamics import PushDynamics, load_model
from robotplan.pushing.models.rigid import moved_pivot_delta
from robotplan.pushing.training.footprints import BOX, LSHAPE
from robotplan.pushing.training.push_data import scene_footprint
from robotplan.pushing.training.rigid import table5_errors
from robotplan.pushing.training.rigid_evaluation import delta_q_sums
from robotplan.pushing.training.samples import PushSamples
from robotplan.scene.bodies import Body
from robotplan.sdf import Circle
from robotplan.sdf.footprint import footprint_centroid

__all__ = ["evaluate_pose_fit", "fit_step"]

LATTICE_HALF = 0.30  # m: the fit integrates H_t on a square of this half-side around q1_{t−1}
LATTICE_STEP = 0.01  # m
YAW_SCALE = 0.1  # m per rad in the optimiser's variables (a turn of 0.1 rad ~ 1 cm)


def _local_quadrature(center: np.ndarray, dtype: torch.dtype) -> Quadrature:
    g = torch.arange(-LATTICE_HALF, LATTICE_HALF - 1e-9, LATTICE_STEP, dtype=torch.float64)
    g = g + LATTICE_STEP / 2
    yy, xx = torch.meshgrid(g, g, indexing="ij")
    pts = torch.stack((xx, yy), -1).reshape(-1, 2) + torch.as_tensor(center[:2])
    return Quadrature(pts.to(dtype), torch.full((len(pts),), LATTICE_STEP**2, dtype=dtype))


def fit_step(model: PushDynamics, obj: Body, pusher: Body, q1_prev: np.ndarray,
             q2_prev: np.ndarray, q2_now: np.ndarray) -> np.ndarray:
    """The pose ``(3,)`` (x, y, yaw) that minimises H_t for the pusher's move
    ``q2_prev → q2_now`` from the object pose ``q1_prev``."""
    # the planner's H_F, which reads an object-frame model's grid about the object
    dyn = field_dynamics(model, obj, pusher,
                         _local_quadrature(q1_prev, next(model.parameters()).dtype))
    X2 = torch.tensor(np.stack([q2_prev, q2_now]), dtype=torch.float64)
    scale = np.array([1.0, 1.0, 1.0 / YAW_SCALE])
    q1_prev = np.asarray(q1_prev, dtype=float)

    def fun(z: np.ndarray) -> tuple[float, np.ndarray]:
        X1 = torch.tensor(np.stack([q1_prev, q1_prev + z * scale]))
        H, J1, _ = dyn.evaluate(X1, X2)
        return 1e6 * float(H[0]), 1e6 * J1[0, 1].double().numpy() * scale  # mm²·m²

    return q1_prev + minimize(fun, np.zeros(3), jac=True, method="L-BFGS-B").x * scale


def evaluate_pose_fit(model_dir: str | Path, data_dir: str | Path, samples: int = 100,
                      seed: int = 0, scenes: int | None = None, progress: bool = True
                      ) -> dict:
    """Fit :func:`fit_step` on ``samples`` random contact samples of the held-out data and
    report, per shape type, the median translation error (mm), the median |yaw error| and
    |true turn| (degrees), and the turn gain (see the module notes)."""
    from tqdm import tqdm

    t0 = time.time()
    model = load_model(model_dir)  # LearnedDynamics freezes its parameters
    data = PushSamples(data_dir, scenes)
    d = data.data
    contact = np.flatnonzero(data.contact)
    rng = np.random.default_rng(seed)
    picked = np.sort(rng.choice(contact, min(samples, len(contact)), replace=False))
    rows, deltas = [], []
    for i in tqdm(picked, desc="pose fit", unit="sample", disable=not progress):
        s, now = data.scene[i], data.now[i]
        shape = scene_footprint(d, s)
        kind = int(d["shape_type"][s])
        q1p, q1n = d["object_pose"][now - 1].astype(float), d["object_pose"][now].astype(float)
        q2p, q2n = d["pusher_xy"][now - 1].astype(float), d["pusher_xy"][now].astype(float)
        obj = Body("object", "object", shape, tuple(q1p), 0.0, 0.06)
        tool = Body("pusher", "pusher", Circle(float(d["pusher_radius"][s])),
                    (q2p[0], q2p[1], 0.0), 0.0, 0.06)
        fit = fit_step(model, obj, tool, q1p, q2p, q2n)
        true, pred = q1n - q1p, fit - q1p
        true[2], pred[2] = wrap_angle(true[2]), wrap_angle(pred[2])
        rows.append((kind, *true, *pred))
        c, s_ = np.cos(q1p[2]), np.sin(q1p[2])
        cx, cy = footprint_centroid(shape)
        pivot = torch.tensor([[q1p[0] + c * cx - s_ * cy, q1p[1] + s_ * cx + c * cy]])
        poses = torch.tensor(np.stack([q1p, q1p, q1n, fit]))
        steps = moved_pivot_delta(pivot.repeat(2, 1), poses[:2], poses[2:]).numpy()
        deltas.append(steps)  # (2, 3): the true Δq, the fitted one
    R = np.array(rows, dtype=float).reshape(-1, 7)
    out: dict = {"model": str(model_dir), "data": str(data_dir), "samples": len(R)}
    for name, mask in (("box", R[:, 0] == BOX), ("lshape", R[:, 0] == LSHAPE),
                       ("other", R[:, 0] > LSHAPE), ("all", R[:, 0] >= 0)):
        if not mask.any():
            continue
        t, p = R[mask, 1:4], R[mask, 4:7]
        out[name] = {
            "samples": int(mask.sum()),
            "translation_error_mm": round(1e3 * float(np.median(
                np.linalg.norm(t[:, :2] - p[:, :2], axis=1))), 2),
            "yaw_error_deg": round(float(np.degrees(np.median(np.abs(t[:, 2] - p[:, 2])))), 2),
            "true_turn_deg": round(float(np.degrees(np.median(np.abs(t[:, 2])))), 2),
            "turn_gain": round(float(t[:, 2] @ p[:, 2] / max(t[:, 2] @ t[:, 2], 1e-12)), 3),
        }
    if deltas:
        D = np.array(deltas)
        out["delta_q_error"] = table5_errors(D[:, 1], D[:, 0])
        names = {BOX: "box", LSHAPE: "lshape"}
        first = np.unique(data.scene[picked], return_index=True)[1]
        out["by_scene"] = {**delta_q_sums(data.scene[picked], np.ones(len(D)), D[:, 1], D[:, 0]),
                           "shape": [names.get(int(R[i, 0]), "other") for i in first]}
    out["seconds"] = round(time.time() - t0, 1)
    return out
