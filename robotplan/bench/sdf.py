"""Benchmarks behind ``robotplan bench …`` (speed targets are checked here, not in tests)."""

from __future__ import annotations

import platform
import time

import numpy as np
import torch

from robotplan.scene import Scene

__all__ = ["bench_sdf"]


def bench_sdf(scene: Scene, steps: int = 40, repeats: int = 20, seed: int = 0,
              dtype: torch.dtype = torch.float32) -> dict:
    """Render every body of ``scene`` at ``steps`` poses on the workspace grid X_h.

    Poses are the start poses plus seeded random offsets (±5 cm, ±0.3 rad). Reports the
    median and best wall time of one full rendering over ``repeats`` runs after a warm-up.
    """
    rng = np.random.default_rng(seed)
    grid = scene.workspace.points(dtype).reshape(-1, 2)
    poses = {}
    for name, b in scene.bodies.items():
        noise = rng.uniform([-0.05, -0.05, -0.3], [0.05, 0.05, 0.3], size=(steps, 3))
        poses[name] = torch.tensor(np.asarray(b.pose) + noise, dtype=dtype)

    def render() -> list[torch.Tensor]:
        return [b.sdf(grid, poses[n]) for n, b in scene.bodies.items()]

    with torch.no_grad():
        render()
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            out = render()
            times.append(time.perf_counter() - t0)
    return {
        "scene": scene.name,
        "bodies": len(scene.bodies),
        "steps": steps,
        "grid": list(scene.workspace.shape),
        "dtype": str(dtype).removeprefix("torch."),
        "values": int(sum(o.numel() for o in out)),
        "median_ms": round(1e3 * float(np.median(times)), 3),
        "best_ms": round(1e3 * float(np.min(times)), 3),
        "repeats": repeats,
        "threads": torch.get_num_threads(),
        "cpu": platform.processor() or platform.machine(),
        "target_ms": 50.0,
    }
