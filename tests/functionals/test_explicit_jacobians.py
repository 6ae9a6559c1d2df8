"""The functionals that write their Jacobians out (no autograd) agree with autograd through
their own ``residual`` in float64, taper terms of the windows included."""

import pytest
import torch

from robotplan.functionals import Collision, GoalRegion
from robotplan.functionals.base import Functional
from robotplan.functionals.collision import SweptClearance
from robotplan.functionals.contact import ContactPoint
from robotplan.functionals.windows import window_bound_gradients
from tests.functionals.conftest import F64, central_difference_jacobian


@pytest.fixture
def states():
    g = torch.Generator().manual_seed(7)
    T = 6
    X1 = torch.cat((0.04 * torch.rand(T, 2, generator=g, dtype=F64),
                    2 * torch.rand(T, 1, generator=g, dtype=F64) - 1), dim=1)
    X2 = torch.stack((-0.12 - 0.02 * torch.rand(T, generator=g, dtype=F64),
                      0.1 * torch.rand(T, generator=g, dtype=F64) - 0.05), dim=1)
    return X1, X2


def cases(obj, pusher, region, X1, X2):
    shifted = X1 + torch.tensor([0.15, 0.05, 0.3], dtype=F64)
    return [(Collision(obj, pusher), (X1, X2)),
            (Collision(obj, obj), (X1, shifted)),
            (GoalRegion(obj, region), (X1 + torch.tensor([0.15, 0.1, 0.0], dtype=F64),)),
            (SweptClearance(obj, pusher), (X1, X2, X2 + 0.1)),
            (ContactPoint(obj, pusher), (X1, X2, X2 + 0.03))]


@pytest.mark.parametrize("shape", ["box", "ell"])
def test_explicit_jacobians_equal_autograd(shape, states, pusher, region, request):
    obj = request.getfixturevalue(shape)
    for H, inputs in cases(obj, pusher, region, *states):
        r, J = H.jacobians(*inputs)
        r_ad, J_ad = Functional.jacobians(H, *inputs)
        assert torch.allclose(r, r_ad, rtol=0, atol=1e-14), type(H).__name__
        for a, b in zip(J, J_ad, strict=True):
            assert a.shape == b.shape
            assert (a - b).abs().max() <= 1e-10 * b.abs().max(), type(H).__name__
        assert any((a.abs() > 0).any() for a in J)


def test_window_taper_terms_matter(ell, region, monkeypatch):
    """Without the taper's slope the goal's Jacobian is off by more than the tolerance
    above: the test of the taper terms can fail."""
    import robotplan.functionals.goal as goal

    X = torch.tensor([[0.15, 0.1, 0.4], [0.2, 0.12, -0.3]], dtype=F64)
    H = GoalRegion(ell, region)
    _, (J_ad,) = Functional.jacobians(H, X)
    monkeypatch.setattr(goal, "window_bound_gradients",
                        lambda f, fac: tuple(0 * t for t in window_bound_gradients(f, fac)))
    _, (J,) = H.jacobians(X)
    assert (J - J_ad).abs().max() > 1e-6 * J_ad.abs().max()


def test_goal_jacobian_matches_finite_differences(ell, region):
    X = torch.tensor([[0.15, 0.1, 0.4], [0.22, 0.02, -0.3]], dtype=F64)
    H = GoalRegion(ell, region)
    _, (J,) = H.jacobians(X)
    fd = central_difference_jacobian(H, (X,), 0)
    assert torch.allclose(J, fd, rtol=1e-5, atol=1e-9), (J - fd).abs().max()
