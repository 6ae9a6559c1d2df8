"""Clearance of a moving object from the fixed obstacles (a check on plans, not a functional).

Open-loop pushing drifts (README, known limits): a plan that meets H_coll by skimming an
obstacle by a centimetre hits it in pybullet. :func:`obstacle_clearance` measures how close
a planned motion comes; the skeleton search asks for :data:`OBSTACLE_MARGIN` before it
calls a plan around obstacles good (``robotplan.pushing.search.planner``), and routes are laid out
with a margin of their own (``robotplan.pushing.search.route``).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import torch

from robotplan.scene import Scene

__all__ = ["OBSTACLE_MARGIN", "densify", "obstacle_clearance"]

# a plan that skims an obstacle by a centimetre executes against it in open loop; routes
# keep 4 cm (0.9 × that at detours) (measured: docs/experiments.md#obstacle-margin)
OBSTACLE_MARGIN = 0.02


def densify(poses: np.ndarray, step: float) -> np.ndarray:
    """Poses ``(N, k)`` (x, y[, yaw]) with linear in-betweens so that consecutive positions
    lie at most ``step`` apart: ``(M, k)``, the given poses among them."""
    poses = np.asarray(poses, dtype=float)
    out = [poses[:1]]
    for a, b in itertools.pairwise(poses):
        n = max(1, math.ceil(float(np.linalg.norm(b[:2] - a[:2])) / step))
        out.append(a + (b - a) * (np.arange(1, n + 1)[:, None] / n))
    return np.concatenate(out)


def obstacle_clearance(scene: Scene, obj: str, poses: np.ndarray, step: float = 0.005
                       ) -> float:
    """The least distance (m) between the footprint of ``obj`` at ``poses (N, 3)`` (and
    between them, every ``step`` m; ``inf``: the poses as given) and every obstacle of
    ``scene``; negative where they overlap, ``inf`` without obstacles.

    Both ways, sampled: φ_obstacle at the object's outline points and φ_object at the
    obstacle's outline points (a thin wall can fall between the object's samples).
    """
    if not scene.obstacles:
        return math.inf
    body = scene.bodies[obj]
    X = densify(poses, step)
    outline = body.shape.outline(n_arc=64)
    c, s = np.cos(X[:, 2:3]), np.sin(X[:, 2:3])
    every = np.stack((c * outline[:, 0] - s * outline[:, 1] + X[:, 0:1],
                      s * outline[:, 0] + c * outline[:, 1] + X[:, 1:2]), axis=-1)  # (M, V, 2)
    least = math.inf
    X_t = torch.as_tensor(X)
    for spec in scene.obstacles:
        wall = scene.bodies[spec.name]
        least = min(least, float(wall.sdf(torch.as_tensor(every.reshape(-1, 2))).min()))
        rim = torch.as_tensor(wall.outline_world())
        least = min(least, float(body.sdf(rim, X_t).min()))
    return least
