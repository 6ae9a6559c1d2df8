"""Bootstrap intervals over scenes and the per-scene sums they resample."""

from __future__ import annotations

import numpy as np
import pytest

from robotplan.base.intervals import (
    median_interval,
    pooled_sums,
    ratio_interval,
    share_interval,
)
from robotplan.base.scene_sums import scene_sums


@pytest.fixture
def rng():
    return np.random.default_rng(0)


def test_scene_sums_add_each_scenes_samples_in_scene_order():
    sums = scene_sums(np.array([3, 1, 3, 1, 7]), {"n": np.ones(5),
                                                  "err": np.array([1.0, 2, 3, 4, 5])})
    assert sums == {"scene": [1, 3, 7], "n": [2.0, 2.0, 1.0], "err": [6.0, 4.0, 5.0]}
    with pytest.raises(ValueError, match="err"):
        scene_sums(np.arange(3), {"err": np.ones(4)})


def test_a_ratio_interval_holds_the_ratio_and_narrows_with_more_scenes(rng):
    def interval(scenes: int) -> tuple[float, float]:
        n = rng.integers(1, 10, scenes).astype(float)
        err = n * rng.normal(3.0, 1.0, scenes)
        lo, hi = ratio_interval(err, n)
        assert lo <= err.sum() / n.sum() <= hi
        return lo, hi

    small, large = interval(20), interval(2000)
    assert large[1] - large[0] < (small[1] - small[0]) / 4
    assert large[0] < 3.0 < large[1]  # the true mean, drawn this way


def test_a_ratio_interval_is_the_same_on_every_call_and_none_without_samples():
    num, den = [1.0, 2.0, 4.0], [1.0, 1.0, 2.0]
    assert ratio_interval(num, den) == ratio_interval(num, den)
    assert ratio_interval([0.0, 0.0], [0.0, 0.0]) is None
    with pytest.raises(ValueError):
        ratio_interval([1.0], [1.0, 2.0])


def test_share_intervals_of_all_none_and_half():
    assert share_interval(0, 30) == (0.0, 0.0)
    assert share_interval(30, 30) == (1.0, 1.0)
    lo, hi = share_interval(75, 150)
    # the binomial's normal interval: 0.5 ± 1.96 · 0.5 / √150 = 0.5 ± 0.080
    assert lo == pytest.approx(0.42, abs=0.015) and hi == pytest.approx(0.58, abs=0.015)
    assert share_interval(0, 0) is None
    with pytest.raises(ValueError):
        share_interval(4, 3)


def test_a_median_interval_holds_the_median(rng):
    values = rng.uniform(0, 1, 41)
    lo, hi = median_interval(values)
    assert lo <= np.median(values) <= hi and hi - lo < 0.5
    assert median_interval([]) is None


def test_pooled_sums_add_seeds_scene_by_scene_and_refuse_other_scenes():
    a = {"scene": [0, 2], "n": [1.0, 2.0], "shape": ["box", "lshape"]}
    b = {"scene": [0, 2], "n": [3.0, 4.0], "shape": ["box", "lshape"]}
    assert pooled_sums([a, b]) == {"scene": [0, 2], "n": [4.0, 6.0],
                                   "shape": ["box", "lshape"]}
    with pytest.raises(ValueError, match="different scenes"):
        pooled_sums([a, {**b, "scene": [0, 1]}])
