"""The shared training loop's learning-rate schedule."""

from types import SimpleNamespace

import pytest

from robotplan.training.loop import lr_at


@pytest.fixture
def cfg():
    return SimpleNamespace(lr=1e-3, lr_min=1e-5, warmup=10, steps=110)


def test_warm_up_then_cosine_to_the_floor(cfg):
    assert lr_at(cfg, 0) == pytest.approx(1e-4)
    assert lr_at(cfg, 9) == pytest.approx(1e-3)
    assert lr_at(cfg, 60) == pytest.approx((1e-3 + 1e-5) / 2)
    assert lr_at(cfg, 110) == pytest.approx(1e-5)
    assert lr_at(cfg, 500) == pytest.approx(1e-5)


def test_a_spent_time_budget_ends_the_cosine_early(cfg):
    # halfway through the budget at a tenth of the steps: the schedule is halfway down
    assert lr_at(cfg, 20, time_fraction=0.5) == pytest.approx((1e-3 + 1e-5) / 2)
    assert lr_at(cfg, 20, time_fraction=1.0) == pytest.approx(1e-5)
    # the step count still wins where it is further along than the clock
    assert lr_at(cfg, 110, time_fraction=0.1) == pytest.approx(1e-5)
    assert lr_at(cfg, 5, time_fraction=0.9) == pytest.approx(6e-4)  # warm-up first
