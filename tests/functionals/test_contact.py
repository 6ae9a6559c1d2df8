import torch

from robotplan.functionals import ContactPoint
from tests.functionals.conftest import F64, central_difference_jacobian


def test_residual_vanishes_exactly_at_a_contact_point(box, pusher):
    H = ContactPoint(box, pusher)
    X_box = torch.tensor([[0.0, 0.0, 0.0]], dtype=F64)
    X_pusher = torch.tensor([[-0.13, 0.02]], dtype=F64)  # touching the box's left face
    p = torch.tensor([[-0.1, 0.02]], dtype=F64)
    assert H(X_box, X_pusher, p).abs().max() < 1e-12
    assert H(X_box, X_pusher, p + 0.01).abs().max() > 1e-3


def test_no_point_zeroes_both_when_apart(box, pusher):
    """min_p |φ1(p)| + |φ2(p)| equals the gap when the bodies are apart (eq. 9)."""
    H = ContactPoint(box, pusher)
    gap = 0.05
    X_box = torch.tensor([[0.0, 0.0, 0.0]], dtype=F64)
    X_pusher = torch.tensor([[-0.1 - 0.03 - gap, 0.0]], dtype=F64)
    xs = torch.linspace(-0.2, 0.0, 2001, dtype=F64)
    p = torch.stack([xs, torch.zeros_like(xs)], dim=1)
    r = H(X_box.expand(len(xs), 3), X_pusher.expand(len(xs), 2), p)
    assert abs(r.abs().sum(dim=1).min().item() - gap) < 1e-4


def test_gradcheck_and_finite_differences(ell, pusher):
    H = ContactPoint(ell, pusher)
    X1 = torch.tensor([[0.0, 0.0, 0.3], [0.01, 0.02, -0.4]], dtype=F64, requires_grad=True)
    X2 = torch.tensor([[-0.15, -0.05], [-0.12, 0.1]], dtype=F64, requires_grad=True)
    p = torch.tensor([[-0.11, -0.03], [-0.09, 0.06]], dtype=F64, requires_grad=True)
    assert torch.autograd.gradcheck(H, (X1, X2, p))
    r, jacs = H.jacobians(X1, X2, p)
    assert r.shape == (2, 2)
    for which, J in enumerate(jacs):
        fd = central_difference_jacobian(H, (X1.detach(), X2.detach(), p.detach()), which)
        assert torch.allclose(J, fd, rtol=1e-6, atol=1e-9)
