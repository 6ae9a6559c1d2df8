"""Per-scene sums of per-sample quantities: what an evaluation keeps so that a report can
resample whole scenes (a bootstrap over scenes) without the samples themselves."""

from __future__ import annotations

import numpy as np

__all__ = ["scene_sums"]

# decimals kept of each sum: millimetres and degrees to 1e-4, far below any reported digit
DECIMALS = 4


def scene_sums(scene: np.ndarray, columns: dict[str, np.ndarray]) -> dict[str, list]:
    """Sum each column over the samples of each scene.

    ``scene``: (N,) scene index of each sample; ``columns``: name → (N,) values. Returns
    ``{"scene": [s0, s1, …], name: [sum over scene s0, …], …}`` for the scenes that have
    samples, in increasing order; a statistic that is a ratio of sums (a mean error, a
    share, a least-squares slope) is then a ratio of these columns for any multiset of
    scenes."""
    scene = np.asarray(scene)
    ids, inverse = np.unique(scene, return_inverse=True)
    out: dict[str, list] = {"scene": [int(s) for s in ids]}
    for name, values in columns.items():
        values = np.asarray(values, dtype=float)
        if values.shape != scene.shape:
            raise ValueError(f"column {name!r}: shape {values.shape}, samples {scene.shape}")
        sums = np.bincount(inverse, weights=values, minlength=len(ids))
        out[name] = [round(float(v), DECIMALS) for v in sums]
    return out
