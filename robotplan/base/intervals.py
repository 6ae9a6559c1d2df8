"""95 % intervals by a percentile bootstrap over scenes.

Scenes are the unit resampled: the samples of one scene share its object, pusher and goal,
so resampling samples alone would understate the spread. A statistic that is a ratio of
per-scene sums (a mean error, a share of successes, a least-squares slope) is resampled
from those sums (:func:`robotplan.base.scene_sums.scene_sums`); a median from the scenes'
values. The draws come from a fixed seed, so a report is the same on every machine.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["LEVEL", "RESAMPLES", "median_interval", "pooled_sums", "ratio_interval",
           "share_interval"]

LEVEL = 0.95
# the ends move by ≤ 2 % of the interval's width with 50,000 resamples or another seed
# (docs/experiments.md#bootstrap); more only costs time
RESAMPLES = 2_000
SEED = 0

Interval = tuple[float, float]


def _draws(n: int, resamples: int, seed: int) -> np.ndarray:
    """(resamples, n) scene indices, drawn with replacement."""
    return np.random.default_rng(seed).integers(0, n, size=(resamples, n))


def _ends(values: np.ndarray, level: float) -> Interval:
    lo, hi = np.nanpercentile(values, [50 * (1 - level), 50 * (1 + level)])
    return float(lo), float(hi)


def ratio_interval(numerator: Sequence[float], denominator: Sequence[float],
                   level: float = LEVEL, resamples: int = RESAMPLES, seed: int = SEED
                   ) -> Interval | None:
    """The interval of Σ numerator / Σ denominator over scenes resampled with replacement.

    ``numerator``, ``denominator``: (S,) per-scene sums. ``None`` with no scene whose
    denominator is positive; resamples whose denominator sums to 0 are left out."""
    num, den = np.asarray(numerator, dtype=float), np.asarray(denominator, dtype=float)
    if num.shape != den.shape or num.ndim != 1:
        raise ValueError(f"numerator {num.shape} and denominator {den.shape}: (S,) each")
    if not (den > 0).any():
        return None
    idx = _draws(len(num), resamples, seed)
    d = den[idx].sum(1)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(d > 0, num[idx].sum(1) / np.where(d > 0, d, 1.0), np.nan)
    return _ends(ratio, level)


def share_interval(successes: int, scenes: int, level: float = LEVEL,
                   resamples: int = RESAMPLES, seed: int = SEED) -> Interval | None:
    """The interval of a share of ``successes`` among ``scenes`` (one outcome per scene)."""
    if scenes <= 0:
        return None
    if not 0 <= successes <= scenes:
        raise ValueError(f"successes {successes} of {scenes} scenes")
    outcome = np.zeros(scenes)
    outcome[:successes] = 1.0
    return ratio_interval(outcome, np.ones(scenes), level, resamples, seed)


def median_interval(values: Sequence[float], level: float = LEVEL,
                    resamples: int = RESAMPLES, seed: int = SEED) -> Interval | None:
    """The interval of the median of one value per scene."""
    v = np.asarray(values, dtype=float)
    if v.size == 0:
        return None
    return _ends(np.median(v[_draws(len(v), resamples, seed)], axis=1), level)


def pooled_sums(runs: Sequence[dict[str, list]]) -> dict[str, list]:
    """Per-scene sums of several evaluations (e.g. one per training seed) added scene by
    scene, so that a ratio of them averages the runs and a resample draws each scene with
    all of its runs. Every run must cover the same scenes."""
    if not runs:
        raise ValueError("no runs to pool")
    first = runs[0]
    for run in runs[1:]:
        if run["scene"] != first["scene"]:
            raise ValueError("runs cover different scenes; pool only evaluations of one set")
    out: dict[str, list] = {}
    for name, column in first.items():
        if name == "scene" or not all(isinstance(v, (int, float)) for v in column):
            out[name] = list(column)
        else:
            out[name] = [float(sum(vals)) for vals in zip(*(r[name] for r in runs), strict=True)]
    return out
